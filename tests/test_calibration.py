"""The harness's calibration figures (summary.json) against NumPy on the same campaign's
measurements.csv: the fraction of contact measurements whose true offset lies within the
reported 1- and 2-sigma ellipse (of the reported spreads and their correlation), per DOF,
and the mean and median NEES."""

import csv
import json
import subprocess
from pathlib import Path

import numpy as np
from conftest import missing

ROOT = Path(__file__).resolve().parent.parent
HARNESS = ROOT / "target" / "release" / "harness"
MIN_STD = 1e-9  # harness::calibration::MIN_STD
MAX_CORR = 0.999  # harness::calibration::MAX_CORR


def test_calibration_figures_agree_with_numpy(fmu_path, tmp_path):
    if not HARNESS.is_file():
        missing("target/release/harness is missing: cargo build --release -p harness")
    subprocess.run(
        [str(HARNESS), "trials", "--task", "peg_in_hole", "--trials", "6", "--seed", "11",
         "--fmu", fmu_path, "--out", str(tmp_path)],
        check=True, cwd=ROOT,
    )
    with open(tmp_path / "measurements.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    with open(tmp_path / "trials.csv", newline="") as f:
        trials = list(csv.DictReader(f))
    # Every trial's contact measurements are there, numbered 1, 2, ...
    assert len(rows) == sum(int(t["measurements"]) for t in trials) > 0
    for i, t in enumerate(trials):
        mine = [int(r["measurement"]) for r in rows if int(r["trial"]) == i]
        assert mine == list(range(1, int(t["measurements"]) + 1))
        assert all(float(r["true_x_m"]) == float(t["offset_x_m"]) for r in rows if int(r["trial"]) == i)

    col = lambda name: np.array([float(r[name]) for r in rows])
    err = np.stack([col("object_x_m") - col("true_x_m"), col("object_y_m") - col("true_y_m")], axis=1)
    std = np.maximum(np.stack([col("object_x_std_m"), col("object_y_std_m")], axis=1), MIN_STD)
    z = err / std
    corr = np.clip(col("object_xy_corr"), -MAX_CORR, MAX_CORR)
    cov = np.stack([np.stack([np.ones_like(corr), corr], axis=1),
                    np.stack([corr, np.ones_like(corr)], axis=1)], axis=1)
    nees = np.einsum("ni,nij,nj->n", z, np.linalg.inv(cov), z)

    c = json.loads((tmp_path / "summary.json").read_text())["calibration"]
    assert c["measurements"] == len(rows)
    n = len(rows)

    def agrees(fraction, values, bound):
        # The CSV rounds positions to 1 nm: only a sample within that of the boundary may
        # be counted differently.
        near = np.sum(np.abs(values - bound) <= 1e-3 * bound)
        return abs(fraction * n - np.sum(values <= bound)) <= near + 1e-9

    assert agrees(c["within_1sigma"], nees, 1.0)
    assert agrees(c["within_2sigma"], nees, 4.0)
    for k, d in enumerate(c["per_dof"]):
        assert d["dof"] == ["object.x", "object.y"][k]
        assert agrees(d["within_1sigma"], np.abs(z[:, k]), 1.0)
        assert agrees(d["within_2sigma"], np.abs(z[:, k]), 2.0)
    assert np.isclose(c["nees_mean"], nees.mean(), rtol=1e-3)
    assert c["nees_ideal"] == 2
    assert np.isclose(c["nees_median"], np.median(nees), rtol=1e-3)
    np.testing.assert_allclose(col("nees"), nees, rtol=1e-3, atol=1e-6)
