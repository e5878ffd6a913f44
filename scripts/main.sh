#!/usr/bin/env bash
# The main job on a fresh Debian machine: installs what is needed (scripts/setup.sh),
# builds, computes the peg-in-hole FT-Map, packages FtFusion.fmu and runs the default
# trial campaign (peg_in_hole, 20 trials, MuJoCo driving the FMU through FMI calls).
# The report lands in runs/peg/ (trials.csv, summary.json, estimates.png).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
source scripts/env.sh
cargo build --release --workspace
cargo xtask fmu
mkdir -p out
target/release/ftmap generate --task peg_in_hole --out out/peg.ftmap
target/release/ftmap plot out/peg.ftmap --channel ty --out out/peg_ty.png
target/release/harness scene --check
target/release/harness trials --task peg_in_hole --trials 20 --seed 7 --out runs/peg
echo "main: report in runs/peg/ (summary.json, trials.csv, estimates.png); map out/peg.ftmap, plot out/peg_ty.png"
