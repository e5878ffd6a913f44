"""scripts/step_profile.py: part A pressed on part B's top comes to rest carrying the press,
on the committed scene and on a copy with a coarser bed, which has fewer contacts."""

import importlib.util
import shutil
import subprocess

from conftest import ROOT, missing, require_module

HARNESS = ROOT / "target" / "release" / "harness"


def profile_module():
    """scripts/step_profile.py as a module."""
    require_module("mujoco")
    spec = importlib.util.spec_from_file_location("step_profile", ROOT / "scripts" / "step_profile.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_pressed_part_rests_on_the_press_and_a_coarser_bed_has_fewer_contacts(tmp_path):
    mujoco = require_module("mujoco")
    sp = profile_module()
    if not HARNESS.is_file():
        missing(f"{HARNESS} is missing: cargo build --release --workspace")
    copy = tmp_path / "peg_in_hole"
    shutil.copytree(ROOT / "models_mjcf" / "peg_in_hole", copy)
    with open(copy / "task.toml", "a") as f:
        f.write("\n[scene]\nbed_pitch = 0.0015\n")
    subprocess.run([HARNESS, "scene", "--task", copy / "task.toml"], check=True, capture_output=True)
    runs = {}
    for name, folder in [("default", ROOT / "models_mjcf" / "peg_in_hole"), ("coarse", copy)]:
        m = mujoco.MjModel.from_xml_path(str(folder / "scene.xml"))
        runs[name] = sp.press(m, 0.002, 50.0, 500)
    for name, r in runs.items():
        # At rest on the top: the contacts carry the press, part A within a micrometre of it.
        assert abs(r["normal"] - 50.0) < 0.5, (name, r)
        assert r["speed"] < 1e-4 and abs(r["sink_um"]) < 1.0, (name, r)
        assert 0.0 < r["narrow"] < 1.0 and r["us_per_step"] > 0.0, (name, r)
    assert runs["coarse"]["contacts"] < 0.5 * runs["default"]["contacts"], runs
