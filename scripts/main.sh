#!/usr/bin/env bash
# The main job on a fresh Debian machine: installs what is needed (scripts/setup.sh),
# builds, computes the peg-in-hole FT-Map, packages FtFusion.fmu and runs a campaign of
# every task, MuJoCo driving the FMU through FMI calls: peg_in_hole (20 trials), the tight
# fit (tight_peg, 0.02 mm radial clearance, 100 trials), the octagon and the gear (20
# each), the grip offset (peg_grip, 20), the octagon's yaw (octagon_yaw, 20), the tilted
# hole (peg_in_hole_4dof, 20; its scene made from its meshes on first use), then
# experiment D (bearing_housing, 20 trials with the camera fused and 20 with force only),
# and prints them in one table. The reports land in runs/<name>/ (trials.csv,
# measurements.csv, summary.json, estimates.png).
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
target/release/harness trials --task octagon --trials 20 --seed 9 --out runs/octagon
target/release/harness trials --task gear --trials 20 --seed 9 --out runs/gear
target/release/harness trials --task peg_grip --trials 20 --seed 22 --out runs/grip
target/release/harness trials --task octagon_yaw --trials 20 --seed 13 --out runs/octagon_yaw
target/release/harness trials --task peg_in_hole_4dof --trials 20 --seed 21 --out runs/tilt
target/release/harness trials --task bearing_housing --trials 20 --seed 3 --vision --out runs/d_vision
target/release/harness trials --task bearing_housing --trials 20 --seed 3 --out runs/d_force
target/release/harness compare-runs runs/d_vision runs/d_force --plot runs/d_compare.png
target/release/harness render --task bearing_housing --out out/d.png
target/release/harness table runs/peg runs/tight runs/octagon runs/gear runs/grip runs/octagon_yaw runs/tilt runs/d_force runs/d_vision | tee runs/table.md
echo "main: every campaign above (runs/table.md; each in runs/<name>/: summary.json, trials.csv, measurements.csv, estimates.png), experiment D compared in runs/d_compare.png; map out/peg.ftmap, plot out/peg_ty.png, camera image out/d.png"
