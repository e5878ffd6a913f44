"""The packaged FMU's shared library loads on old distributions: it needs glibc 2.17 at
most (manylinux2014: RHEL/CentOS 7, Rocky 8, Ubuntu 20.04), only libraries every Linux has,
and it exports the FMI 2.0 Co-Simulation functions and nothing else. The ELF file is read
here with the format's description (section headers, .dynsym, .gnu.version_r), not with
binutils; `objdump -T`, where installed, must agree."""

import re
import shutil
import struct
import subprocess
import zipfile

import pytest

BINARY = "binaries/linux64/FtFusion.so"
MAX_GLIBC = (2, 17)
MAX_LIBGCC = (4, 8, 0)  # manylinux2014's libgcc_s symbol versions: GCC_4.8.0 at most
# What manylinux2014 lets a binary link against (plus the dynamic loader itself).
SYSTEM_LIBRARIES = {
    "libc.so.6",
    "libm.so.6",
    "libdl.so.2",
    "libpthread.so.0",
    "librt.so.1",
    "libgcc_s.so.1",
    "ld-linux-x86-64.so.2",
}
# FMI 2.0: the 25 functions common to both interface types and the 9 of Co-Simulation.
FMI2_COSIMULATION = {
    "fmi2GetTypesPlatform", "fmi2GetVersion", "fmi2SetDebugLogging", "fmi2Instantiate",
    "fmi2FreeInstance", "fmi2SetupExperiment", "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode", "fmi2Terminate", "fmi2Reset", "fmi2GetReal",
    "fmi2GetInteger", "fmi2GetBoolean", "fmi2GetString", "fmi2SetReal", "fmi2SetInteger",
    "fmi2SetBoolean", "fmi2SetString", "fmi2GetFMUstate", "fmi2SetFMUstate",
    "fmi2FreeFMUstate", "fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate",
    "fmi2DeSerializeFMUstate", "fmi2GetDirectionalDerivative",
    "fmi2SetRealInputDerivatives", "fmi2GetRealOutputDerivatives", "fmi2DoStep",
    "fmi2CancelStep", "fmi2GetStatus", "fmi2GetRealStatus", "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus", "fmi2GetStringStatus",
}  # fmt: skip

SHT_DYNSYM, SHT_DYNAMIC, SHT_GNU_VERNEED = 11, 6, 0x6FFFFFFE
DT_NEEDED = 1


class Elf:
    """The dynamic-linking view of a little-endian ELF64 shared library."""

    def __init__(self, data: bytes):
        assert data[:4] == b"\x7fELF", "not an ELF file"
        assert data[4] == 2 and data[5] == 1, "not ELF64 little-endian"
        assert struct.unpack_from("<H", data, 0x12)[0] == 62, "not x86_64"
        self.data = data
        shoff, = struct.unpack_from("<Q", data, 0x28)
        shentsize, shnum = struct.unpack_from("<HH", data, 0x3A)
        # sh_name, sh_type, sh_flags, sh_addr, sh_offset, sh_size, sh_link, sh_info, ...
        self.sections = [
            struct.unpack_from("<IIQQQQII", data, shoff + k * shentsize) for k in range(shnum)
        ]

    def _section(self, kind):
        found = [s for s in self.sections if s[1] == kind]
        assert len(found) == 1, f"{len(found)} sections of type {kind:#x}"
        return found[0]

    def _string(self, strtab, offset):
        start = self.sections[strtab][4] + offset
        return self.data[start : self.data.index(b"\0", start)].decode()

    def defined_dynamic_symbols(self):
        """What `nm -D --defined-only` lists: the named .dynsym entries with a section."""
        _, _, _, _, off, size, strtab, _ = self._section(SHT_DYNSYM)
        names = []
        for at in range(off + 24, off + size, 24):  # entry 0 is the null symbol
            name, _info, _other, shndx = struct.unpack_from("<IBBH", self.data, at)
            if shndx != 0 and name != 0:
                names.append(self._string(strtab, name))
        return names

    def needed_libraries(self):
        """The DT_NEEDED entries of .dynamic."""
        _, _, _, _, off, size, strtab, _ = self._section(SHT_DYNAMIC)
        tags = (struct.unpack_from("<qQ", self.data, at) for at in range(off, off + size, 16))
        return [self._string(strtab, value) for tag, value in tags if tag == DT_NEEDED]

    def needed_versions(self):
        """{library: [version names]} from .gnu.version_r (Elf64_Verneed, Elf64_Vernaux):
        the symbol versions the dynamic loader checks before loading the library."""
        _, _, _, _, off, _, strtab, count = self._section(SHT_GNU_VERNEED)
        needed, at = {}, off
        for _ in range(count):
            _version, cnt, file, aux, nxt = struct.unpack_from("<HHIII", self.data, at)
            names, a = [], at + aux
            for _ in range(cnt):
                _hash, _flags, _other, name, anext = struct.unpack_from("<IHHII", self.data, a)
                names.append(self._string(strtab, name))
                a += anext
            needed[self._string(strtab, file)] = names
            at += nxt
        return needed


def numbers(version):
    """GLIBC_2.3.4 -> (2, 3, 4)."""
    return tuple(int(x) for x in version.split("_", 1)[1].split("."))


@pytest.fixture(scope="module")
def binary(fmu_path, tmp_path_factory):
    with zipfile.ZipFile(fmu_path) as z:
        data = z.read(BINARY)
    path = tmp_path_factory.mktemp("portable") / "FtFusion.so"
    path.write_bytes(data)
    return path, Elf(data)


def test_needs_glibc_2_17_at_most(binary):
    path, elf = binary
    needed = elf.needed_versions()
    versions = [v for names in needed.values() for v in names]
    glibcs = [v for v in versions if v.startswith("GLIBC_")]
    assert glibcs, "no glibc symbol versions: not a glibc binary?"
    libgcc = [v for v in versions if v.startswith("GCC_")]
    assert all(numbers(v) <= MAX_LIBGCC for v in libgcc), libgcc
    others = set(versions) - set(glibcs) - set(libgcc)
    assert not others, f"symbol versions of other libraries: {others}"
    newest = max(glibcs, key=numbers)
    assert numbers(newest) <= MAX_GLIBC, (
        f"{BINARY} needs {newest} (from {needed}): it will not load where glibc is older "
        f"(RHEL/Rocky 8 has 2.28, Ubuntu 20.04 2.31); build it with `cargo xtask fmu`, "
        f"which links against glibc {'.'.join(map(str, MAX_GLIBC))} with cargo zigbuild"
    )
    if shutil.which("objdump"):  # binutils, where installed, reads the same newest version
        out = subprocess.run(["objdump", "-T", str(path)], capture_output=True, text=True, check=True)
        assert max(re.findall(r"GLIBC_[0-9.]+", out.stdout), key=numbers) == newest


def test_links_only_system_libraries(binary):
    _, elf = binary
    assert set(elf.needed_libraries()) <= SYSTEM_LIBRARIES, elf.needed_libraries()


def test_exports_exactly_the_34_fmi2_cosimulation_functions(binary):
    path, elf = binary
    exported = elf.defined_dynamic_symbols()
    assert len(exported) == len(set(exported))
    assert set(exported) == FMI2_COSIMULATION, (
        f"not exported: {sorted(FMI2_COSIMULATION - set(exported))}; exported besides the "
        f"fmi2 functions ({len(set(exported) - FMI2_COSIMULATION)}): "
        f"{sorted(set(exported) - FMI2_COSIMULATION)[:10]}"
    )
    assert len(FMI2_COSIMULATION) == 34
    if shutil.which("nm"):
        out = subprocess.run(["nm", "-D", "--defined-only", str(path)], capture_output=True, text=True, check=True)
        assert sorted(line.split()[-1] for line in out.stdout.splitlines()) == sorted(exported)
