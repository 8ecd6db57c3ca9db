"""kingen: robot YAML to verified DELMIA V5 / IGRIP user-inverse-kinematics plugins.

Phases, one module each: ``model`` (load and validate YAML) -> ``render``
(C source text) -> ``build`` (compile) -> ``host`` (load as DELMIA does) ->
``verify`` (compare with ``reference``). Conventions live in ``conventions``.
"""

__version__ = "0.1.0"
