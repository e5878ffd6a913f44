"""FtFusion.fmu through FMPy: validation, a simulation driven by contact measurements read
from the FMU's own map at a true offset, and low-level calls that must be refused or warned
about without harming the run."""

import math
import subprocess

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave, fmi2Warning
from fmpy.util import fmu_info  # noqa: F401  (imported to check FMPy is complete)
from fmpy.validation import validate_fmu

TRUTH = (2.0e-3, -1.5e-3)  # true object offset (m), a cell of the map
WRENCH = ["wrench.fx", "wrench.fy", "wrench.fz", "wrench.tx", "wrench.ty", "wrench.tz"]


def contact_table(ftmap, truth, contacts=4, period=1.0):
    """Input rows: contact rises once per period with the map's wrench at `truth`."""
    cell = ftmap.cell(truth)
    dtype = [("time", float)] + [(n, float) for n in WRENCH] + [("tcp.z", float), ("contact", bool)]
    rows = []
    for k in range(contacts):
        t = k * period
        w = tuple(cell[c] for c in ["fx", "fy", "fz", "tx", "ty", "tz"])
        rows.append((t, *w, cell["depth"], False))
        rows.append((t + 0.5 * period, *w, cell["depth"], True))
    rows.append((contacts * period, *w, cell["depth"], False))
    return np.array(rows, dtype=dtype)


def test_fmpy_validation_finds_no_problem(fmu_path):
    assert validate_fmu(fmu_path) == []
    md = read_model_description(fmu_path)
    assert md.coSimulation.modelIdentifier == "FtFusion"
    names = {v.name for v in md.modelVariables}
    for n in WRENCH + ["tcp.x", "tcp.rz", "contact", "object.x", "grip.rz_std", "confidence", "converged", "clusters"]:
        assert n in names


def test_fmpy_cli_validate_exits_cleanly(fmu_path):
    subprocess.run(["fmpy", "validate", fmu_path], check=True)


def test_fmutool_check_passes(fmu_path):
    out = subprocess.run(["fmutool", "-check", "-input", fmu_path], capture_output=True, text=True, check=True)
    text = out.stdout + out.stderr
    assert "compliant with FMI-2.0" in text and "ERROR" not in text, text


def test_simulation_with_map_contacts_ends_near_the_true_offset(fmu_path, ftmap):
    assert ftmap.dofs() == ["object.x", "object.y"]
    result = simulate_fmu(
        fmu_path,
        stop_time=4.0,
        step_size=0.1,
        input=contact_table(ftmap, TRUTH),
        start_values={"particles": 4000, "seed": 3},
        output=["object.x", "object.y", "object.z", "confidence", "measurements", "clusters"],
    )
    last = result[-1]
    err = math.hypot(last["object.x"] - TRUTH[0], last["object.y"] - TRUTH[1])
    assert err < 2e-4, f"estimate ({last['object.x']}, {last['object.y']}), truth {TRUTH}"
    assert last["object.z"] == 0.0
    assert last["measurements"] == 4
    assert result[0]["measurements"] == 0


def slave(fmu_path, tmp_path, guid=None):
    """An extracted FMU2Slave (not instantiated) and its model description."""
    from fmpy import extract

    unzipdir = extract(fmu_path, unzipdir=str(tmp_path / "fmu"))
    md = read_model_description(fmu_path)
    s = FMU2Slave(
        guid=guid or md.guid,
        unzipDirectory=unzipdir,
        modelIdentifier="FtFusion",
        instanceName="t",
    )
    return s, {v.name: v.valueReference for v in md.modelVariables}


def test_a_wrong_guid_is_refused(fmu_path, tmp_path):
    s, _ = slave(fmu_path, tmp_path, guid="{00000000-0000-0000-0000-000000000000}")
    with pytest.raises(Exception):
        s.instantiate()


def test_an_illegal_call_order_gets_an_error_and_the_instance_survives(fmu_path, tmp_path):
    s, vr = slave(fmu_path, tmp_path)
    s.instantiate()
    with pytest.raises(Exception, match="3|Error"):
        s.doStep(0.0, 0.1)  # before initialization
    with pytest.raises(Exception):
        s.exitInitializationMode()  # never entered
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    s.doStep(0.0, 0.1)
    assert s.getInteger([vr["measurements"]]) == [0]
    s.terminate()
    s.freeInstance()


def test_a_nan_input_gets_a_warning_and_the_run_goes_on(fmu_path, ftmap, tmp_path):
    s, vr = slave(fmu_path, tmp_path)
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    cell = ftmap.cell(TRUTH)
    wrench = [cell[c] for c in ["fx", "fy", "fz", "tx", "ty", "tz"]]
    s.setReal([vr[n] for n in WRENCH], [float("nan")] + wrench[1:])
    s.setBoolean([vr["contact"]], [True])
    assert s.fmi2DoStep(s.component, 0.0, 0.1, 1) == fmi2Warning
    assert s.getInteger([vr["measurements"]]) == [0]
    s.setBoolean([vr["contact"]], [False])
    s.doStep(0.1, 0.1)
    s.setReal([vr[n] for n in WRENCH] + [vr["tcp.z"]], wrench + [cell["depth"]])
    s.setBoolean([vr["contact"]], [True])
    s.doStep(0.2, 0.1)
    assert s.getInteger([vr["measurements"]]) == [1]
    assert all(math.isfinite(x) for x in s.getReal([vr["object.x"], vr["object.y"], vr["confidence"]]))
    s.terminate()
    s.freeInstance()


def test_saved_states_replay_exactly_through_fmpy(fmu_path, ftmap, tmp_path):
    s, vr = slave(fmu_path, tmp_path)
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    cell = ftmap.cell(TRUTH)
    wrench = [cell[c] for c in ["fx", "fy", "fz", "tx", "ty", "tz"]]
    s.setReal([vr[n] for n in WRENCH] + [vr["tcp.z"]], wrench + [cell["depth"]])

    def contact(t):
        s.setBoolean([vr["contact"]], [True])
        s.doStep(t, 0.1)
        s.setBoolean([vr["contact"]], [False])
        s.doStep(t + 0.1, 0.1)
        return s.getReal([vr["object.x"], vr["object.y"], vr["confidence"], vr["ess"]])

    contact(0.0)
    state = s.getFMUState()
    blob = s.serializeFMUState(state)
    first = contact(1.0)
    s.setFMUState(state)
    assert contact(1.0) == first
    restored = s.deserializeFMUState(blob)
    s.setFMUState(restored)
    assert contact(1.0) == first
    s.freeFMUState(state)
    s.freeFMUState(restored)
    with pytest.raises(Exception):
        s.deserializeFMUState(b"not a state at all")
    s.terminate()
    s.freeInstance()
