"""Faulty files for the file-handling tests: zip bombs, FIFOs, hand-written SSDs.

Shared by ``test_file_faults.py`` (one test per case) and the slow
``test_fault_injection_files.py`` (the same cases through the CLI).
"""
from __future__ import annotations

import io
import os
import struct
import zlib
from pathlib import Path

import numpy as np

SSD_HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription version="1.0" name="hand"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues">
"""


def ssd_text(ramp: str = "Ramp.fmu", gain: str = "Gain.fmu", ramp_connectors: str = "",
             ramp_extra: str = "") -> str:
    """A ramp feeding a gain (fixture FMUs), sources and connectors as given."""
    source = ramp.replace("&", "&amp;").replace('"', "&quot;")
    return SSD_HEAD + f"""
  <ssd:System name="hand">
    <ssd:Elements>
      <ssd:Component name="ramp" source="{source}">{ramp_connectors}{ramp_extra}</ssd:Component>
      <ssd:Component name="gain" source="{gain}"/>
    </ssd:Elements>
    <ssd:Connections>
      <ssd:Connection startElement="ramp" startConnector="y" endElement="gain" endConnector="u"/>
    </ssd:Connections>
  </ssd:System>
</ssd:SystemStructureDescription>
"""


def system_folder(folder: Path, fixture_fmus: dict, **ssd) -> Path:
    """``folder`` with Ramp.fmu, Gain.fmu and a SystemStructure.ssd; returns the SSD path."""
    folder.mkdir(parents=True, exist_ok=True)
    for name in ("Ramp", "Gain"):
        (folder / f"{name}.fmu").write_bytes(Path(fixture_fmus[name]).read_bytes())
    path = folder / "SystemStructure.ssd"
    path.write_text(ssd_text(**ssd))
    return path


def fifo(path: Path) -> Path:
    """A FIFO at ``path``: opening it for reading or writing blocks (a loud failure in a test)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    os.mkfifo(path)
    return path


def npy_header(nbytes: int) -> bytes:
    """The ``.npy`` header of a float64 vector of ``nbytes`` bytes."""
    buffer = io.BytesIO()
    np.lib.format.write_array_header_1_0(buffer, {"descr": "<f8", "fortran_order": False,
                                                  "shape": (nbytes // 8,)})
    return buffer.getvalue()


def npz_bomb(path: Path, mib: int, member: str = "time_s.npy") -> Path:
    """A zip (zip64 when needed) with one ``.npy`` member of ``mib`` MiB of zeros.

    About 1 KB per MiB on disk: one raw-deflate block of 1 MiB of zeros,
    repeated (a full flush resets the compressor, so every block compresses
    to the same bytes).  The CRC is not computed (a reader must refuse the
    member before inflating it); sizes and headers are valid.
    """
    header = npy_header(mib << 20)
    compressor = zlib.compressobj(9, zlib.DEFLATED, -15)
    head = compressor.compress(header) + compressor.flush(zlib.Z_FULL_FLUSH)
    block = compressor.compress(bytes(1 << 20)) + compressor.flush(zlib.Z_FULL_FLUSH)
    data = head + block * mib + compressor.flush()
    size = len(header) + (mib << 20)
    name = member.encode()
    big = size >= 0xFFFFFFFF
    extra = struct.pack("<HHQQ", 1, 16, size, len(data)) if big else b""
    shown_size, shown_csize = (0xFFFFFFFF, 0xFFFFFFFF) if big else (size, len(data))
    version = 45 if big else 20
    local = struct.pack("<IHHHHHIIIHH", 0x04034B50, version, 0, 8, 0, 0x21, 0, shown_csize,
                        shown_size, len(name), len(extra)) + name + extra
    central = struct.pack("<IHHHHHHIIIHHHHHII", 0x02014B50, version, version, 0, 8, 0, 0x21, 0,
                          shown_csize, shown_size, len(name), len(extra), 0, 0, 0, 0, 0
                          ) + name + extra
    end = struct.pack("<IHHHHIIH", 0x06054B50, 0, 0, 1, 1, len(central),
                      len(local) + len(data), 0)
    path.write_bytes(local + data + central + end)
    return path


def sparse_file(path: Path, size: int, head: bytes = b"") -> Path:
    """A file of ``size`` bytes that takes no disk space (``head``, then a hole)."""
    with open(path, "wb") as stream:
        stream.write(head)
        stream.truncate(size)
    return path


def good_log(path: Path, samples: int = 7200, step: float = 1.0) -> Path:
    """A valid static IMU log (Earth rate and gravity on the up axis) of ``samples`` samples."""
    from sarins_fmu.imu_log import write_log

    time = step * np.arange(1, samples + 1)
    dtheta = np.zeros((samples, 3))
    dtheta[:, 2] = 7.292115e-5 * step
    dv = np.zeros((samples, 3))
    dv[:, 2] = 9.79 * step
    return write_log(path, time, dtheta, dv, lat_deg=28.2)


def rewrite_fmu(source: Path, target: Path, description=None, library=None) -> Path:
    """A copy of the FMU ``source`` at ``target`` with its modelDescription.xml text passed through
    ``description`` and its binaries/linux64 library bytes through ``library`` (either may be None)."""
    import zipfile

    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml" and description is not None:
                data = description(data.decode()).encode()
            elif item.filename.startswith("binaries/linux64/") and library is not None:
                data = library(data)
            zout.writestr(item, data)
    return target


def many_variables(count: int):
    """A ``description`` rewrite adding ``count`` compact local Real variables (a description bomb)."""
    def rewrite(text: str) -> str:
        at = text.index("<ModelVariables>") + len("<ModelVariables>")
        extra = "".join(f'<ScalarVariable name="b{k}" valueReference="{10**7 + k}"><Real/></ScalarVariable>'
                        for k in range(count))
        return text[:at] + extra + text[at:]
    return rewrite


def same_value_reference(first: str, second: str):
    """A ``description`` rewrite giving variable ``second`` the value reference of ``first``."""
    import re

    def rewrite(text: str) -> str:
        vr = re.search(rf'name="{first}"[^>]*valueReference="(\d+)"', text).group(1)
        return re.sub(rf'(name="{second}"[^>]*valueReference=")\d+(")', rf"\g<1>{vr}\g<2>", text, count=1)
    return rewrite
