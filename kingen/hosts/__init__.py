"""The hosts a robot file can be built for, found through this registry as limb models are
through :mod:`kingen.robot.limbs`.

``HOSTS`` maps each ``--host`` name to a :class:`~kingen.hosts.base.Host` instance.
``register`` adds one at run time (tests do, with a toy host); ``get_host`` is how every
command finds the host it was asked for. DELMIA V5 / IGRIP (``delmia``), LinuxCNC (``linuxcnc``), a portable C library (``c``) and that library compiled to
WebAssembly (``wasm``) are built in.
"""

from ..defaults import DEFAULT_HOST
from ..errors import KingenError
from ..robot.file_schema import NAME_CHECKS
from .base import BuildResult, Host, LoadedRoutine
from .delmia import DelmiaHost
from .c import CHost
from .linuxcnc import LinuxcncHost
from .wasm import WasmHost

HOSTS = {}


def register(host):
    """Add ``host`` (a Host instance) under ``host.name``, and its name check to what reading
    a robot file asks (kingen.robot.model.NAME_CHECKS); returns it."""
    HOSTS[host.name] = host
    NAME_CHECKS[host.name] = host.name_problem
    return host


def unregister(host):
    """Remove ``host`` again."""
    if HOSTS.get(host.name) is host:
        del HOSTS[host.name]
        del NAME_CHECKS[host.name]


def get_host(name=DEFAULT_HOST):
    """The registered host called ``name``; KingenError naming the known ones otherwise."""
    try:
        return HOSTS[name]
    except KeyError:
        raise KingenError(f"unknown host '{name}' (known: {', '.join(sorted(HOSTS))})") from None


def name_problems(robot_name):
    """Why ``robot_name`` cannot name a routine, one reason per host that refuses it."""
    return [problem for host in HOSTS.values() if (problem := host.name_problem(robot_name))]


register(DelmiaHost())
register(LinuxcncHost())
register(CHost())
register(WasmHost())

__all__ = ["BuildResult", "DEFAULT_HOST", "HOSTS", "Host", "LoadedRoutine", "get_host", "name_problems",
           "register", "unregister"]
