"""Shared fixtures of the cross-language tests: the packaged FtFusion.fmu (built with
`cargo xtask fmu` when missing) and an independent reader of its FT-Map."""

import importlib
import json
import os
import shutil
import struct
import subprocess
import zipfile
import zlib
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent


def missing(what):
    """A prerequisite is missing: under CI (CI=true) the test fails, so that a green run
    means it ran; elsewhere it is skipped with the reason."""
    if os.environ.get("CI") == "true":
        pytest.fail(f"{what} (under CI=true a missing prerequisite fails the test)")
    pytest.skip(what)


def require_module(name):
    """The module `name`, or `missing` when it is not installed (scripts/setup.sh installs it)."""
    try:
        return importlib.import_module(name)
    except ImportError as e:
        missing(f"Python module {name} is not installed ({e}): run scripts/setup.sh")
FMU = ROOT / "target" / "fmu" / "FtFusion.fmu"
CHANNELS = ["fx", "fy", "fz", "tx", "ty", "tz", "depth"]


@pytest.fixture(scope="session")
def fmu_path():
    """The packaged FMU, built if missing."""
    if not FMU.is_file():
        if shutil.which("cargo") is None:
            missing("target/fmu/FtFusion.fmu is missing and cargo is not installed to build it")
        subprocess.run(["cargo", "xtask", "fmu"], cwd=ROOT, check=True)
    return str(FMU)


class FtMap:
    """An FT-Map file read with the format's description (docs/map-format.md), not its code."""

    def __init__(self, data: bytes):
        assert data[:8] == b"FTMAP\0\r\n", "magic"
        version, hlen = struct.unpack_from("<II", data, 8)
        assert version == 1
        self.header = json.loads(data[16 : 16 + hlen])
        (crc,) = struct.unpack_from("<I", data, len(data) - 4)
        assert crc == zlib.crc32(data[:-4]), "checksum"
        self.axes = self.header["grid"]["axes"]
        shape = [a["count"] for a in self.axes] + [len(CHANNELS)]
        self.values = np.frombuffer(data[16 + hlen : -4], dtype="<f4").reshape(shape)

    def dofs(self):
        return [a["dof"] for a in self.axes]

    def cell(self, coords):
        """Channels of the cell nearest to `coords` (one value per axis, SI)."""
        idx = tuple(int(round((c - a["min"]) / a["step"])) for c, a in zip(coords, self.axes))
        return dict(zip(CHANNELS, self.values[idx].astype(float)))


@pytest.fixture(scope="session")
def ftmap(fmu_path):
    """The FMU's default map, read from its resources."""
    with zipfile.ZipFile(fmu_path) as z:
        return FtMap(z.read("resources/peg_in_hole.ftmap"))
