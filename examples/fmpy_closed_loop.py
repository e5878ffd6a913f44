#!/usr/bin/env python3
"""The harness's closed loop (the paper's Algorithm 1) in Python: the generated MuJoCo scene
through MuJoCo's Python bindings (mujoco==3.17.0) and FtFusion.fmu through FMPy, with
contact motions only (the harness's `--slide off`).

It repeats the Rust harness's contact motion step for step (harness/src/sim.rs): reset,
place part B (mocap body) at the true offset, put the carriage 0.1 mm above part B's top
(the scene's `start` keyframe height) at the commanded point, press with the task's force
against the feed's damping until the approach speed stays below 1e-4 m/s for 10 ms with a
contact and the torque then moves less than 1 mN.m over 10 ms more (unless part A drops
by 10 µm meanwhile; at most 2 s); once part A is 0.1 mm below part B's top, the feed
drives it down at 0.1 m/s, at most the height left over 10 ms.
The wrench handed to the FMU is the negated raw sensor reading (harness/src/sensor.rs),
without noise; the FMU's seed of trial i is seed + i. Success: the task frame settles less
than 1 mm above the goal.

    python3 examples/fmpy_closed_loop.py --offset 0.002,-0.0015 --offset 0.001,0.003
    python3 examples/fmpy_closed_loop.py --offsets-csv out/h20/trials.csv --seed 1 --json
"""

import argparse
import csv
import json
import sys
import tomllib
from pathlib import Path

import mujoco
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

ROOT = Path(__file__).resolve().parent.parent
MAX_TIME, SETTLE_SPEED, SETTLE_TIME, SETTLE_TORQUE, DROP_DEPTH = 2.0, 1.0e-4, 0.01, 1.0e-3, 0.00001
TORQUE_WINDOW = 0.03
APPROACH_CLEARANCE, ENTRY_DEPTH, INSERTION_SPEED, INSERTION_TIME = 0.0001, 0.0001, 0.1, 0.01
SUCCESS_HEIGHT = 0.001
STEP = 0.001


class Cell:
    """The task's scene in MuJoCo 3.17 (Python bindings)."""

    def __init__(self, task):
        folder = ROOT / "models_mjcf" / task
        self.force = tomllib.loads((folder / "task.toml").read_text())["contact"]["force"]
        self.model = mujoco.MjModel.from_xml_path(str(folder / "scene.xml"))
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.qpos = [m.jnt_qposadr[m.joint(n).id] for n in ("x", "y", "z")]
        self.dof_z = m.jnt_dofadr[m.joint("z").id]
        self.act = [m.actuator(n).id for n in ("servo_x", "servo_y", "press", "feed")]
        self.force_adr = m.sensor_adr[m.sensor("ft_force").id]
        self.torque_adr = m.sensor_adr[m.sensor("ft_torque").id]
        self.mocap = m.body_mocapid[m.body("part_b").id]
        self.start_z = m.key("start").qpos[self.qpos[2]]
        self.entered = self.start_z - APPROACH_CLEARANCE - ENTRY_DEPTH

    def contact(self, obj, xy):
        """One contact motion at the commanded point `xy`; returns (wrench, tcp, ended): ended
        is whether it settled or fed part A within SUCCESS_HEIGHT of the goal."""
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        d.mocap_pos[self.mocap] = [obj[0], obj[1], 0.0]
        for q, v in zip(self.qpos, (xy[0], xy[1], self.start_z)):
            d.qpos[q] = v
        for a, v in zip(self.act, (xy[0], xy[1], -self.force, 0.0)):
            d.ctrl[a] = v
        max_steps = round(MAX_TIME / m.opt.timestep)
        settle_steps = round(SETTLE_TIME / m.opt.timestep)
        torque_steps = round(TORQUE_WINDOW / m.opt.timestep)
        calm = steps = 0
        first, calm_torque, fed_home = None, None, False
        while steps < max_steps:
            mujoco.mj_step(m, d)
            steps += 1
            z = d.qpos[self.qpos[2]]
            if z < self.entered:
                d.ctrl[self.act[3]] = -min(INSERTION_SPEED, max(z, 0.0) / INSERTION_TIME)
                if z < SUCCESS_HEIGHT and first is None:
                    # Fed within SUCCESS_HEIGHT of the goal: inserted, the motion ends.
                    fed_home = True
                    break
            if abs(d.qvel[self.dof_z]) < SETTLE_SPEED and d.ncon > 0:
                if calm == 0:
                    calm_torque = self.read()[0][3:]
                calm += 1
            elif first is None:
                calm = 0
            if calm < (torque_steps if first is not None else settle_steps):
                continue
            if z > self.entered:
                # Read once the torque has settled too: it moved less than SETTLE_TORQUE
                # over a window of TORQUE_WINDOW from when the speed settled, unless part A
                # dropped since the speed settled (the harness's `sim::TORQUE_WINDOW`).
                now = self.read()
                window = first is not None
                if first is None:
                    first = now
                if first[1][2] - z > DROP_DEPTH:
                    break
                moved = sum((a - b) ** 2 for a, b in zip(now[0][3:], calm_torque)) ** 0.5
                if not window or moved >= SETTLE_TORQUE:
                    calm_torque, calm = now[0][3:], 1
                    continue
                first = now
            break
        raw, tcp = first if first is not None else self.read()
        ended = calm >= settle_steps or first is not None or fed_home
        wrench = [-v for v in raw]
        return wrench, tcp, ended

    def read(self):
        """The raw sensor values (force, torque) and the task frame's position now."""
        d = self.data
        raw = list(d.sensordata[self.force_adr : self.force_adr + 3]) + list(d.sensordata[self.torque_adr : self.torque_adr + 3])
        return raw, [float(d.qpos[q]) for q in self.qpos]


class Estimator:
    """One FtFusion.fmu instance through FMPy's FMU2Slave."""

    def __init__(self, fmu, md, unzipdir, seed, map_path=None):
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.slave = FMU2Slave(
            guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier, instanceName="fmpy"
        )
        self.slave.instantiate()
        self.slave.setInteger([self.vr["seed"]], [seed])
        if map_path:
            self.slave.setString([self.vr["map"]], [str(Path(map_path).resolve())])
        self.slave.setupExperiment(startTime=0.0)
        self.slave.enterInitializationMode()
        self.slave.exitInitializationMode()
        self.time = 0.0

    def _step(self):
        self.slave.doStep(currentCommunicationPoint=self.time, communicationStepSize=STEP)
        self.time += STEP

    def measure(self, wrench, tcp):
        v = self.vr
        names = ["wrench.fx", "wrench.fy", "wrench.fz", "wrench.tx", "wrench.ty", "wrench.tz"]
        self.slave.setReal([v[n] for n in names], wrench)
        self.slave.setReal([v[n] for n in ("tcp.x", "tcp.y", "tcp.z", "tcp.rx", "tcp.ry", "tcp.rz")], tcp + [0.0, 0.0, 0.0])
        self.slave.setBoolean([v["contact"]], [True])
        self._step()
        est = self.slave.getReal([v["object.x"], v["object.y"]])
        self.slave.setBoolean([v["contact"]], [False])
        self._step()
        return est

    def close(self):
        self.slave.terminate()
        self.slave.freeInstance()


def run_trials(offsets, task="peg_in_hole", fmu=None, seed=1, max_contacts=30, map_path=None):
    """Runs one closed-loop trial per true offset; returns a list of result dicts."""
    fmu = str(fmu or ROOT / "target" / "fmu" / "FtFusion.fmu")
    if not Path(fmu).is_file():
        sys.exit(f"FMU {fmu} not found: build it with `cargo xtask fmu`")
    md = read_model_description(fmu)
    unzipdir = extract(fmu)
    cell = Cell(task)
    results = []
    for i, obj in enumerate(offsets):
        est = Estimator(fmu, md, unzipdir, seed + i, map_path)
        target, contacts, success, tcp = [0.0, 0.0], 0, False, [0.0, 0.0, 0.0]
        while contacts < max_contacts:
            wrench, tcp, ended = cell.contact(obj, target)
            contacts += 1
            if ended and tcp[2] < SUCCESS_HEIGHT:
                success = True
                break
            target = est.measure(wrench, tcp)
        est.close()
        err = ((tcp[0] - obj[0]) ** 2 + (tcp[1] - obj[1]) ** 2) ** 0.5
        results.append({"offset": list(obj), "contacts": contacts, "success": success, "final_error": err})
    return results


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--task", default="peg_in_hole")
    ap.add_argument("--fmu", help="default: target/fmu/FtFusion.fmu")
    ap.add_argument("--map", help="FT-Map for the FMU (default: its embedded peg_in_hole map)")
    ap.add_argument("--seed", type=int, default=1, help="FMU seed of the first trial (trial i: seed + i)")
    ap.add_argument("--offset", action="append", default=[], help="true offset x,y in m (repeatable)")
    ap.add_argument("--offsets-csv", help="take the offsets of a harness trials.csv")
    ap.add_argument("--max-contacts", type=int, default=30)
    ap.add_argument("--json", action="store_true", help="print the results as JSON")
    a = ap.parse_args()
    offsets = [tuple(float(v) for v in o.split(",")) for o in a.offset]
    if a.offsets_csv:
        with open(a.offsets_csv, newline="") as f:
            offsets += [(float(r["offset_x_m"]), float(r["offset_y_m"])) for r in csv.DictReader(f)]
    if not offsets:
        offsets = [(0.002, -0.0015)]
    res = run_trials(offsets, a.task, a.fmu, a.seed, a.max_contacts, a.map)
    if a.json:
        print(json.dumps(res))
    else:
        for i, r in enumerate(res):
            print(f"trial {i}: offset ({r['offset'][0]*1e3:+.3f}, {r['offset'][1]*1e3:+.3f}) mm: "
                  f"{r['contacts']} contacts, {'ok' if r['success'] else 'FAILED'}, final error {r['final_error']*1e3:.3f} mm")


if __name__ == "__main__":
    main()
