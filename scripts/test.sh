#!/usr/bin/env bash
# Installs what is needed (scripts/setup.sh) and runs every test: rustfmt, clippy, the Rust tests
# (workspace, release profile: the map and filter tests compute real maps) and the Python
# tests (FMPy, fmutool, libcosim, ecos) against the packaged FMU and the FMPy tests again
# under valgrind memcheck (scripts/memcheck.sh), these two beside the Rust tests.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
source scripts/env.sh
cargo fmt --all --check
cargo build --release --workspace --all-targets
cargo clippy --release --workspace --all-targets -- -D warnings
cargo xtask fmu                      # the Rust importer test and the Python tests load it
# The Python tests, then the FMPy tests again under valgrind (no error in FtFusion.so), run
# beside the Rust tests (a test binary often runs one long single-threaded test), in their
# own process group, stopped if the script stops early; their report follows the Rust tests'.
mkdir -p out
setsid bash -c 'python3 -m pytest -q tests && bash scripts/memcheck.sh' > out/python-tests.log 2>&1 &
python=$!
trap 'kill -- -"$python" 2>/dev/null || true' EXIT
cargo test --release --workspace
status=0
wait "$python" || status=$?
trap - EXIT
cat out/python-tests.log
exit "$status"
