#!/usr/bin/env bash
# Installs what is needed (scripts/setup.sh), builds, computes the peg-in-hole FT-Map and
# packages the FMU. (The default trial campaign joins here with the harness.)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
source scripts/env.sh
cargo build --release --workspace
mkdir -p out
target/release/ftmap generate --task peg_in_hole --out out/peg.ftmap
target/release/ftmap info out/peg.ftmap
target/release/ftmap plot out/peg.ftmap --channel ty --out out/peg_ty.png
if [ -d xtask ]; then
  cargo xtask fmu
fi
echo "main: map out/peg.ftmap, plot out/peg_ty.png"
