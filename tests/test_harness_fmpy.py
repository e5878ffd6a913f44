"""The harness's closed loop scripted in Python (MuJoCo's Python bindings + FMPy) against
the Rust harness (mujoco-rs + the fmi crate) on the same offsets and seeds: same scene, same
FMU, so the same contact counts (the harness with contact motions only, `--slide off`, as
the script makes them)."""

import csv
import importlib.util
import subprocess
from pathlib import Path

from conftest import missing

ROOT = Path(__file__).resolve().parent.parent
HARNESS = ROOT / "target" / "release" / "harness"


def load_example():
    spec = importlib.util.spec_from_file_location("fmpy_closed_loop", ROOT / "examples" / "fmpy_closed_loop.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_fmpy_script_contact_counts_agree_with_the_rust_harness(fmu_path, tmp_path):
    if not HARNESS.is_file():
        missing("target/release/harness is missing: cargo build --release -p harness")
    seed = 5
    subprocess.run(
        [str(HARNESS), "trials", "--task", "peg_in_hole", "--trials", "4", "--seed", str(seed),
         "--sensor-noise", "off", "--slide", "off", "--fmu", fmu_path, "--out", str(tmp_path)],
        check=True, cwd=ROOT,
    )
    with open(tmp_path / "trials.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    offsets = [(float(r["offset_x_m"]), float(r["offset_y_m"])) for r in rows]
    py = load_example().run_trials(offsets, fmu=fmu_path, seed=seed)
    for r, p in zip(rows, py):
        assert p["success"] == (r["success"] == "true")
        assert p["contacts"] == int(r["contacts"]), (r, p)
