#!/usr/bin/env bash
# Installs what is needed (scripts/setup.sh) and runs every test: rustfmt, clippy, the Rust tests
# (workspace, release profile: the map and filter tests compute real maps) and the Python
# tests (FMPy, fmutool, libcosim, ecos) against the packaged FMU, then the FMPy tests again
# under valgrind memcheck (scripts/memcheck.sh).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
source scripts/env.sh
cargo fmt --all --check
cargo build --release --workspace --all-targets
cargo clippy --release --workspace --all-targets -- -D warnings
cargo xtask fmu                      # the Rust importer test and the Python tests load it
cargo test --release --workspace
python3 -m pytest -q tests
bash scripts/memcheck.sh             # the FMPy tests under valgrind: no error in FtFusion.so
