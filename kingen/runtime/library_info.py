"""What a compiled library says about itself, read from its bytes, never by loading it.

Every library kingen generates carries the exported string ``kingen_build_info``
("kingen-build-info: robot=... routine=... dof=... postures=... sha256=... kingen=...");
:func:`build_info` finds and parses it, :func:`binary_format` names the file's format and
machine from its header. Nothing here runs the library's code. The string is a label the
library carries, not a proof of where it came from: any file can hold one.
"""

import re
import struct

from .file_gate import read_limited

BUILD_INFO_MARKER = "kingen-build-info:"
"""Starts the build-info string compiled into every generated library (kingen.hosts.render writes it)."""
MAX_LIBRARY_BYTES = 256 << 20
_INFO = re.compile(re.escape(BUILD_INFO_MARKER.encode()) + rb"([ -9;-~]{1,1000}+)\x00")
"""The marker, then 1 to 1000 printable bytes other than ':' (kingen writes identifiers, numbers
and hex there), then a NUL. Excluding ':' (the marker's last byte) stops a candidate's text at
the next marker and the possessive repeat never gives bytes back, so one search looks at each
byte a bounded number of times: linear in the file's size, however many markers it repeats
(the old pattern re-read up to 1000 bytes after each marker, 1.1 s per MB of repeated markers)."""
_ELF_MACHINES = {3: "i386", 40: "arm", 62: "x86-64", 183: "aarch64"}
_PE_MACHINES = {0x14C: "i386", 0x8664: "x86-64", 0xAA64: "aarch64"}


def _read(path):
    return read_limited(path, MAX_LIBRARY_BYTES, "not a plugin library")


def build_info(path):
    """What the library's build-information string says, as {robot, routine, dof, postures,
    sha256, kingen, ...}, or None when it carries none. A label, not a proof: any file can carry
    such a string (the first in the file is read). One linear pass over at most
    MAX_LIBRARY_BYTES bytes (under 10 ms per MB, whatever the bytes); the library is never
    loaded."""
    match = _INFO.search(_read(path))
    if match is None:
        return None
    return dict(item.split("=", 1) for item in match.group(1).decode("ascii").split() if "=" in item)


def binary_format(path):
    """'ELF 64-bit shared object, x86-64', 'PE32+ DLL, x86-64', ... or 'not a library'."""
    data = _read(path)
    if data[:4] == b"\x7fELF" and len(data) >= 20:
        bits = {1: "32-bit", 2: "64-bit"}.get(data[4], "?-bit")
        endian = "<" if data[5] == 1 else ">"
        kind, machine = struct.unpack_from(endian + "HH", data, 16)
        shape = {2: "executable", 3: "shared object"}.get(kind, "object")
        return f"ELF {bits} {shape}, {_ELF_MACHINES.get(machine, f'machine {machine}')}"
    if data[:2] == b"MZ" and len(data) >= 0x40:
        offset = struct.unpack_from("<I", data, 0x3C)[0]
        if data[offset:offset + 4] == b"PE\0\0" and len(data) >= offset + 26:
            machine = struct.unpack_from("<H", data, offset + 4)[0]
            magic = struct.unpack_from("<H", data, offset + 24)[0]
            return f"{'PE32+' if magic == 0x20B else 'PE32'} DLL, {_PE_MACHINES.get(machine, f'machine {machine:#x}')}"
    return "not a library"
