"""A LinuxCNC ``.ini`` read as LinuxCNC reads it: through LinuxCNC's own reader (the ``ini``
class of its Python module ``linuxcnc``, in a child process of the Python that has it) where it
is installed, otherwise by :func:`read_ini`, which keeps the same rules: section and key names
are case-sensitive, the first value of a key repeated in a section wins, a section repeated is
read where it first stands only (the keys under its later headers are not read), a line whose
first character past its indentation is ``#`` or ``;`` is a comment, a value runs from past
the ``=`` to the end of its line (a ``#`` or ``;`` in it is part of it), trimmed, and an
empty value is no value. Every line is accepted: one without ``=`` is no key.
"""

import json
import os
import subprocess
from dataclasses import dataclass

from ..errors import KingenError
from ..runtime.file_gate import read_limited
from .interpreter import linuxcnc_python

INI_BYTES = 1 << 20
LINUXCNC_READER = """
import json, sys
import linuxcnc
ini = linuxcnc.ini(sys.argv[1])
print(json.dumps([ini.find(section, key) for section, key in json.loads(sys.argv[2])]))
"""
READER_SECONDS = 30.0


@dataclass(frozen=True)
class Ini:
    """An ``.ini``'s values: ``values`` {(section, key): value text} of the keys asked for
    (absent: not given), ``lines`` {(section, key) or (section, None): its line (1-based)} from
    kingen's reading, ``length`` its number of lines, ``reader`` whose reader gave the values
    ("LinuxCNC's linuxcnc.ini" or "kingen's"), which check-path's report names."""

    path: str
    values: dict
    lines: dict
    length: int
    reader: str

    def get(self, section, key):
        return self.values.get((section, key))

    def line(self, section, key=None):
        """The line of ``key`` in ``section`` (or of the section's header), else None."""
        return self.lines.get((section, key), self.lines.get((section, None)))

    def has_section(self, section):
        return (section, None) in self.lines


def read_ini(text):
    """({(section, key): value}, {(section, key) or (section, None): line}) of an ``.ini``'s
    ``text`` by LinuxCNC's rules (the module docstring): the first value of a key wins, a
    section is read where its header first stands."""
    values, lines, section = {}, {}, None
    for number, raw in enumerate(text.splitlines(), start=1):
        stripped = raw.strip()
        if not stripped or stripped[0] in "#;":
            continue
        if stripped.startswith("[") and "]" in stripped:
            section = stripped[1:stripped.index("]")]
            if (section, None) in lines:
                section = None  # a repeated header: what follows it is not read
            else:
                lines[section, None] = number
            continue
        if section is None or "=" not in stripped:
            continue
        key, value = (part.strip() for part in stripped.split("=", 1))
        if key and value and (section, key) not in values:
            values[section, key] = value
            lines[section, key] = number
    return values, lines


def linuxcnc_values(path, wanted):
    """{(section, key): value} of the ``wanted`` (section, key) pairs as LinuxCNC's own reader
    finds them, or None where LinuxCNC's Python module is not installed."""
    python = linuxcnc_python()
    if python is None:
        return None
    wanted = list(wanted)
    try:
        done = subprocess.run([python, "-I", "-c", LINUXCNC_READER, os.path.abspath(path), json.dumps(wanted)],
                              capture_output=True, text=True, timeout=READER_SECONDS, stdin=subprocess.DEVNULL,
                              env={"PATH": "/usr/bin:/bin", "LANG": "C.UTF-8"})
    except (OSError, subprocess.TimeoutExpired):
        return None
    if done.returncode != 0:
        return None
    found = json.loads(done.stdout)
    return {tuple(pair): value for pair, value in zip(wanted, found) if value is not None}


def load_ini(path, wanted):
    """The Ini of the file at ``path`` for the ``wanted`` (section, key) pairs: values from
    LinuxCNC's reader where installed, else kingen's; lines from kingen's. KingenError when
    the file cannot be read."""
    try:
        text = read_limited(path, INI_BYTES, "LinuxCNC .ini").decode("utf-8", "replace")
    except OSError as error:
        raise KingenError(f"{path}: {error.strerror or error}") from None
    values, lines = read_ini(text)
    wanted = list(wanted)
    theirs = linuxcnc_values(path, wanted)
    if theirs is None:
        return Ini(str(path), {pair: values[pair] for pair in wanted if pair in values}, lines,
                   len(text.splitlines()), "kingen's")
    return Ini(str(path), theirs, lines, len(text.splitlines()), "LinuxCNC's linuxcnc.ini")
