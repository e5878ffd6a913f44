#!/usr/bin/env bash
# The main job on a fresh Debian machine: installs what is needed (scripts/setup.sh),
# builds, computes the peg-in-hole FT-Map, packages FtFusion.fmu and runs the default
# trial campaign (peg_in_hole, 20 trials, MuJoCo driving the FMU through FMI calls), the
# tight fit's (tight_peg, 0.02 mm radial clearance, 100 trials), then experiment D
# (bearing_housing, 20 trials with the camera fused and 20 with force only). The reports
# land in runs/peg/, runs/tight/, runs/d_vision/, runs/d_force/ (trials.csv, summary.json,
# estimates.png).
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
target/release/harness boundary                  # where each scene accepts part A, against the geometry
target/release/harness trials --task peg_in_hole --trials 20 --seed 7 --out runs/peg
target/release/harness trials --task tight_peg --trials 100 --seed 61 --out runs/tight
target/release/harness trials --task bearing_housing --trials 20 --seed 3 --vision --out runs/d_vision
target/release/harness trials --task bearing_housing --trials 20 --seed 3 --out runs/d_force
target/release/harness compare-runs runs/d_vision runs/d_force --plot runs/d_compare.png
target/release/harness render --task bearing_housing --out out/d.png
echo "main: report in runs/peg/ (summary.json, trials.csv, estimates.png), the tight fit in runs/tight/, experiment D in runs/d_vision/ and runs/d_force/ (compared: runs/d_compare.png); map out/peg.ftmap, plot out/peg_ty.png, camera image out/d.png"
