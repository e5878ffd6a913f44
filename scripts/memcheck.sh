#!/usr/bin/env bash
# Runs the Python FMU tests (FMPy and the other importers load target/fmu/FtFusion.fmu)
# under valgrind memcheck and counts the errors whose stack passes through FtFusion.so:
# invalid reads and writes, uses of uninitialised values, bad frees, bad system call
# arguments and memory definitely lost. Exit 0 when there are none. Python runs with
# PYTHONMALLOC=malloc so that its own allocator does not hide or fake errors; errors
# outside FtFusion.so (the interpreter, NumPy) are counted apart and do not fail the run.
# Usage: bash scripts/memcheck.sh [pytest arguments; default: the FMPy tests of the FMU,
# tests/test_fmu.py and tests/test_fmu_vision.py, about a minute]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh >/dev/null
source scripts/env.sh
cargo xtask fmu
out="$root/out/memcheck"
rm -rf "$out" && mkdir -p "$out"
tests=("$@")
[ ${#tests[@]} -gt 0 ] || tests=(tests/test_fmu.py tests/test_fmu_vision.py)
# The interpreter itself, not a version manager's shell shim: the shim's shell scripts and
# ldconfig (ctypes' library search) are not traced, the Python processes (pytest, fmpy,
# fmutool) are.
python="$(python3 -c 'import sys; print(sys.executable)')"
PYTHONMALLOC=malloc valgrind --tool=memcheck --leak-check=full --errors-for-leak-kinds=definite \
    --trace-children=yes --trace-children-skip='*/bash,*/sh,*/readlink,*/basename,*/ldconfig*' \
    --child-silent-after-fork=yes --xml=yes --xml-file="$out/memcheck.%p.xml" \
    "$python" -m pytest -q -p no:cacheprovider "${tests[@]}"
python3 - "$out" <<'PY'
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

ours, others, files = [], 0, sorted(Path(sys.argv[1]).glob("memcheck.*.xml"))
for f in files:
    try:
        root = ET.parse(f).getroot()
    except ET.ParseError:
        continue  # a process that exec'd before writing its log
    for e in root.iter("error"):
        kind = e.findtext("kind", "")
        if kind.startswith("Leak_") and kind != "Leak_DefinitelyLost":
            continue
        objs = [fr.findtext("obj", "") for fr in e.iter("frame")]
        if any("FtFusion" in o or "ftfusion" in o for o in objs):
            what = e.findtext("what") or e.findtext("xwhat/text") or kind
            ours.append(f"{f.name}: {kind}: {what}")
        else:
            others += 1
print(f"memcheck: {len(files)} processes, {len(ours)} errors in FtFusion.so, {others} elsewhere")
for line in ours:
    print("  " + line)
sys.exit(1 if ours else 0)
PY
