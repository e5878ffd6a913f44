"""Shared fixtures of the cross-language tests: the packaged FtFusion.fmu (built with
`cargo xtask fmu` when missing) and an independent reader of its FT-Map."""

import json
import shutil
import struct
import subprocess
import zipfile
import zlib
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
FMU = ROOT / "target" / "fmu" / "FtFusion.fmu"
CHANNELS = ["fx", "fy", "fz", "tx", "ty", "tz", "depth"]


@pytest.fixture(scope="session")
def fmu_path():
    """The packaged FMU, built if missing."""
    if not FMU.is_file():
        if shutil.which("cargo") is None:
            pytest.skip("target/fmu/FtFusion.fmu is missing and cargo is not installed to build it")
        subprocess.run(["cargo", "xtask", "fmu"], cwd=ROOT, check=True)
    return str(FMU)


class FtMap:
    """An FT-Map file read with the format's description (maps/src/format.rs), not its code."""

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
