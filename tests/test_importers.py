"""FtFusion.fmu in independent importers: OSP libcosim (libcosimpy) and ecos (ecospy) run
the same contact sequence as FMPy and must give the same outputs (the filter is
deterministic for a seed)."""

import pytest
from fmpy import read_model_description

from conftest import require_module
from test_fmu import TRUTH, WRENCH, slave

STEP = 0.1
# Steps at which `contact` is high (rising edges at 2, 6, 10): three measurements.
HIGH = {2, 3, 6, 7, 10, 11}
STEPS = 14
OUTPUTS = ["object.x", "object.y", "confidence", "ess"]


def inputs(ftmap):
    cell = ftmap.cell(TRUTH)
    return dict(zip(WRENCH + ["tcp.z"], [cell[c] for c in ["fx", "fy", "fz", "tx", "ty", "tz", "depth"]]))


@pytest.fixture(scope="module")
def fmpy_outputs(fmu_path, ftmap, tmp_path_factory):
    s, vr = slave(fmu_path, tmp_path_factory.mktemp("fmpy"))
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    values = inputs(ftmap)
    s.setReal([vr[n] for n in values], list(values.values()))
    for k in range(STEPS):
        s.setBoolean([vr["contact"]], [k in HIGH])
        s.doStep(k * STEP, STEP)
    out = s.getReal([vr[n] for n in OUTPUTS]) + s.getInteger([vr["measurements"]])
    s.terminate()
    s.freeInstance()
    assert out[-1] == 3
    return out


def test_libcosim_gives_the_same_outputs_as_fmpy(fmu_path, ftmap, fmpy_outputs):
    require_module("libcosimpy")
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    vr = {v.name: v.valueReference for v in read_model_description(fmu_path).modelVariables}
    ex = CosimExecution.from_step_size(step_size=int(STEP * 1e9))  # nanoseconds
    idx = ex.add_local_slave(CosimLocalSlave(fmu_path=fmu_path, instance_name="ftfusion"))
    values = inputs(ftmap)
    for name, v in values.items():
        ex.real_initial_value(idx, vr[name], v)
    manipulator = CosimManipulator.create_override()
    observer = CosimObserver.create_last_value()
    ex.add_manipulator(manipulator)
    ex.add_observer(observer)
    for k in range(STEPS):
        manipulator.slave_boolean_values(idx, [vr["contact"]], [k in HIGH])
        ex.step()
    out = observer.last_real_values(idx, [vr[n] for n in OUTPUTS])
    out += observer.last_integer_values(idx, [vr["measurements"]])
    assert out == fmpy_outputs


def test_ecos_gives_the_same_outputs_as_fmpy(fmu_path, ftmap, fmpy_outputs):
    ecospy = require_module("ecospy")
    structure = ecospy.EcosSimulationStructure()
    structure.add_model("ftfusion", fmu_path)
    with ecospy.EcosSimulation(structure=structure, step_size=STEP) as sim:
        sim.init()
        for name, v in inputs(ftmap).items():
            sim.set_real(f"ftfusion::{name}", v)
        for k in range(STEPS):
            sim.set_bool("ftfusion::contact", k in HIGH)
            sim.step()
        out = [sim.get_real(f"ftfusion::{n}") for n in OUTPUTS] + [sim.get_integer("ftfusion::measurements")]
        sim.terminate()
    assert out == fmpy_outputs
