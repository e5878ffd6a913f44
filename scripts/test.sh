#!/usr/bin/env bash
# Installs what is needed (scripts/setup.sh) and runs every test: rustfmt, clippy, the Rust tests
# (workspace, release profile: the map and filter tests compute real maps) and the Python
# tests (FMPy, fmutool, libcosim, ecos) against the packaged FMU, and the FMPy tests again
# under valgrind memcheck (scripts/memcheck.sh) beside the Rust tests.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
source scripts/env.sh
cargo fmt --all --check
cargo build --release --workspace --all-targets
cargo clippy --release --workspace --all-targets -- -D warnings
cargo xtask fmu                      # the Rust importer test and the Python tests load it
# The FMPy tests under valgrind (no error in FtFusion.so) on one core, beside the Rust tests
# (a test binary often runs one long single-threaded test): its own process group, stopped
# if the script stops early; its report is printed after the Rust and Python tests.
mkdir -p out
setsid bash scripts/memcheck.sh > out/memcheck.log 2>&1 &
memcheck=$!
trap 'kill -- -"$memcheck" 2>/dev/null || true' EXIT
cargo test --release --workspace
python3 -m pytest -q tests
status=0
wait "$memcheck" || status=$?
trap - EXIT
cat out/memcheck.log
exit "$status"
