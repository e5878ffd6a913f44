#!/usr/bin/env python3
"""Where a MuJoCo step of a task's scene spends its time: part A pressed on part B's top
with --force (the tasks' 50 N), part B --offset mm off along x, as a `harness` contact motion starts
(carriage held in x, y, the press motor on z, the feed at rest). Prints per variant the
wall time per step, the real-time factor of the stepping alone, the contacts per step,
the shares of MuJoCo's collision narrow phase and constraint solver (its own timers), and
whether part A came to rest (the contacts' normal force against the press, its speed and
how far it sank into part B's top at the end).

    python3 scripts/step_profile.py --task peg_in_hole --offset 2 [--timestep 0.0004]

--timestep runs the scene again at other time steps (the scene's contact stiffness
unchanged), to see where the stepping stays stable. Uses the `mujoco` Python package that
`scripts/setup.sh` installs (the library's version, 3.17.0).
"""

import argparse
import os
import pathlib
import sys
import time

import mujoco
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent


def top_of_part_b(m, d):
    """Height of the highest point of part B's colliding geoms (m)."""
    body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "part_b")
    mujoco.mj_forward(m, d)
    top = -np.inf
    for g in range(m.ngeom):
        if m.geom_bodyid[g] != body or m.geom_contype[g] == 0:
            continue
        centre, half = m.geom_aabb[g][:3], m.geom_aabb[g][3:]
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
        local = centre + corners * half
        world = d.geom_xpos[g] + local @ d.geom_xmat[g].reshape(3, 3).T
        top = max(top, world[:, 2].max())
    return top


def press(m, offset, force, steps):
    """Steps part A pressed `offset` (m) off the hole; returns the figures of one run."""
    d = mujoco.MjData(m)
    top = top_of_part_b(m, d)
    mujoco.mj_resetData(m, d)
    press_id = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "press")
    joint = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "z")
    z, vz = m.jnt_qposadr[joint], m.jnt_dofadr[joint]
    body_b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "part_b")
    d.mocap_pos[m.body_mocapid[body_b]] = [offset, 0.0, 0.0]
    d.qpos[z] = top + 2e-5
    d.ctrl[press_id] = -force
    contacts = []
    start = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(m, d)
        contacts.append(d.ncon)
    wall = time.perf_counter() - start
    timer = d.timer
    share = lambda k: timer[k].duration / timer[mujoco.mjtTimer.mjTIMER_STEP].duration
    force6 = np.zeros(6)
    normal = 0.0
    for i in range(d.ncon):
        mujoco.mj_contactForce(m, d, i, force6)
        normal += force6[0]
    return {
        "us_per_step": 1e6 * wall / steps,
        "realtime": steps * m.opt.timestep / wall,
        "contacts": float(np.mean(contacts[steps // 2 :])),
        "narrow": share(mujoco.mjtTimer.mjTIMER_COL_NARROW),
        "constraint": share(mujoco.mjtTimer.mjTIMER_CONSTRAINT),
        "normal": normal,
        "speed": abs(d.qvel[vz]),
        "sink_um": 1e6 * (top - d.qpos[z]),
    }


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument(
        "--task", default="peg_in_hole", help="task name, or its folder or task.toml"
    )
    p.add_argument("--offset", type=float, default=2.0, help="part B off the goal along x (mm)")
    p.add_argument("--force", type=float, default=50.0, help="the press (N)")
    p.add_argument("--seconds", type=float, default=0.3, help="simulated time per run (s)")
    p.add_argument("--timestep", type=float, nargs="*", default=[], help="other time steps (s)")
    a = p.parse_args()
    given = pathlib.Path(a.task)
    if given.exists():
        folder = given if given.is_dir() else given.parent
    else:
        folder = pathlib.Path(os.environ.get("FTFUSION_MODELS", ROOT / "models_mjcf")) / a.task
    scene = folder / "scene.xml"
    if not scene.is_file():
        sys.exit(f"step_profile: no scene {scene}: write it with `harness scene --task {a.task}`")
    m = mujoco.MjModel.from_xml_path(str(scene))
    print(f"{scene}: {m.ngeom} geoms, part B {a.offset} mm off, {a.force} N")
    for dt in [m.opt.timestep, *a.timestep]:
        m.opt.timestep = dt
        r = press(m, a.offset * 1e-3, a.force, round(a.seconds / dt))
        print(
            f"  time step {dt * 1e3:.2f} ms: {r['us_per_step']:.0f} us/step, real-time factor "
            f"{r['realtime']:.2f} x, {r['contacts']:.0f} contacts/step, narrow phase "
            f"{100 * r['narrow']:.0f} %, constraint solver {100 * r['constraint']:.0f} %; "
            f"at the end: contact normal force {r['normal']:.1f} N, speed {r['speed'] * 1e3:.3f} mm/s, "
            f"part A {r['sink_um']:.2f} um below part B's top"
        )


if __name__ == "__main__":
    main()
