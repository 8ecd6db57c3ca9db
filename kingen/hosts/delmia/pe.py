"""Reading the export table of a Windows DLL (PE32 or PE32+), to check what a
cross-compiled plugin offers DELMIA without needing Windows or objdump."""

import struct
from pathlib import Path

from ...errors import KingenError


def dll_exports(path):
    """The names a DLL exports, as a sorted list; KingenError when it is not a PE DLL."""
    data = Path(path).read_bytes()
    try:
        return _exports(data)
    except (struct.error, IndexError, KeyError, ValueError, OverflowError) as error:
        raise KingenError(f"{path}: not a readable Windows DLL ({error})") from None


def _exports(data):
    if data[:2] != b"MZ":
        raise ValueError("no MZ header")
    pe = struct.unpack_from("<I", data, 0x3C)[0]
    if data[pe:pe + 4] != b"PE\0\0":
        raise ValueError("no PE signature")
    sections, optional_size = struct.unpack_from("<H12xH", data, pe + 6)
    optional = pe + 24
    magic = struct.unpack_from("<H", data, optional)[0]
    if magic not in (0x10B, 0x20B):
        raise ValueError(f"unknown optional header magic {magic:#x}")
    directories = optional + {0x10B: 96, 0x20B: 112}[magic]
    export_rva, export_size = struct.unpack_from("<II", data, directories)
    if export_size == 0:
        return []
    table = optional + optional_size
    spans = [struct.unpack_from("<8xIIII", data, table + 40 * i) for i in range(sections)]

    def offset(rva):
        for virtual_size, virtual_address, raw_size, raw_pointer in spans:
            if virtual_address <= rva < virtual_address + max(virtual_size, raw_size):
                return rva - virtual_address + raw_pointer
        raise ValueError(f"address {rva:#x} outside every section")

    directory = offset(export_rva)
    count, _, names = struct.unpack_from("<III", data, directory + 24)
    exported = []
    for index in range(count):
        start = offset(struct.unpack_from("<I", data, offset(names) + 4 * index)[0])
        exported.append(data[start:data.index(b"\0", start)].decode("ascii"))
    return sorted(exported)
