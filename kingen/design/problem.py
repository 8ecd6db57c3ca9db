"""A robot's design problem: the ``optimize:`` section of a robot file, the designs it spans
and the objective that judges them.

The design variables are a layout's numeric fields (a list field, such as a 6-RUS layout's
``crank_directions``, gives one variable per entry) and the home's depth below the base
(``depth``: home z = -depth) or height above it (``height``). The objective is the largest
tilt the platform reaches in every direction: the least, over the azimuths, of the tilt
limit :func:`kingen.design.analysis.tilt_limits` finds in the working posture, with the
objective's tilt convention, steps, cap and collision model (defaults: the 6-RUS thesis's,
``../shared/optimisation.md``). It is computed by the compiled tilt judge where that
applies (six cranks) and by the numpy reference otherwise; the two agree exactly.
"""

import copy
import io

import numpy as np

from .analysis import Settings, tilt_limits
from ..robot.design_schema import Optimize
from ..errors import KingenError
from ..robot.located import Locator
from ..robot.schema import MAX_DEGREES, MAX_NAME
from .tilt_judge import judges, tilt_table

POSITION_FIELDS = {"depth": -1.0, "height": 1.0}
"""Variables that set the verification home's z: depth below the base (z = -depth), height above."""
OPTIMIZED = "_optimized"
"""What an optimised design's name ends in."""


class Problem:
    """The design problem of a robot file's data: its variables (names, bounds, whether each
    is an angle), the data each design makes, and the objective. ``lines`` (the file's
    {field path: line}) put the line into the errors, which name file, field and problem."""

    def __init__(self, data, path, lines=None):
        self.data, self.path = data, path
        self.section = Optimize.model_validate(data["optimize"])
        locate = Locator(str(path), lines or {})
        layout = data.get("layout") or {}
        self.names, self.lower, self.upper, self.angles, self._targets = [], [], [], [], []
        for number, variable in enumerate(self.section.variables):
            where = ["optimize", "variables", number, "field"]
            if variable.field in POSITION_FIELDS:
                targets, angle = [(variable.field, None)], False
            elif variable.field.startswith("layout.") and variable.field[7:] in layout:
                name = variable.field[7:]
                value = layout[name]
                if isinstance(value, bool) or not isinstance(value, (int, float, list)):
                    raise locate.error(where, f"layout.{name} is not a number or a list of numbers")
                targets = [(name, index) for index in range(len(value))] if isinstance(value, list) else [(name, None)]
                angle = "direction" in name or "angle" in name
            else:
                raise locate.error(where, f"'{variable.field}' is neither a field of the layout "
                                          f"(layout.<field>) nor one of {', '.join(POSITION_FIELDS)}")
            if angle and max(map(abs, variable.bounds)) > MAX_DEGREES:
                raise locate.error(["optimize", "variables", number, "bounds"],
                                   f"an angle's bounds must be within +/-{MAX_DEGREES:g} degrees")
            for target in targets:
                self.names.append(variable.field if target[1] is None else f"{variable.field}[{target[1]}]")
                self.lower.append(variable.bounds[0])
                self.upper.append(variable.bounds[1])
                self.angles.append(angle)
                self._targets.append(target)
        self.lower, self.upper, self.angles = np.array(self.lower), np.array(self.upper), np.array(self.angles)

    def start(self):
        """The design the robot file holds, as a vector."""
        layout = self.data.get("layout") or {}
        home_z = float(self.data["verification"]["home"][2])
        return np.array([home_z * POSITION_FIELDS[name] if index is None and name in POSITION_FIELDS
                         else float(layout[name] if index is None else layout[name][index])
                         for name, index in self._targets])

    def design_data(self, x):
        """The robot file's data with design ``x`` put in (golden values dropped: they were
        published for the file's own design)."""
        data = copy.deepcopy(self.data)
        data.pop("golden", None)
        for (name, index), value in zip(self._targets, np.asarray(x, dtype=float)):
            value = float(value)
            if name in POSITION_FIELDS and index is None:
                data["verification"]["home"][2] = value * POSITION_FIELDS[name]
            elif index is None:
                data["layout"][name] = value
            else:
                data["layout"][name][index] = value
        return data

    def robot(self, x):
        from ..robot.model import robot_from_data

        return robot_from_data(self.design_data(x), self.path)

    def posture(self, robot):
        posture = self.section.objective.posture
        return robot.working_posture if posture is None else posture


def settings_of(objective):
    """analyze's Settings for an ``optimize.objective``."""
    return Settings(objective.tilt_convention, objective.tilt_step, objective.azimuth_step, objective.tilt_max,
                    objective.collision)


def evaluate(problem, x):
    """(objective_deg, [(max_tilt_deg, cause)] per azimuth, poses judged) of design ``x``;
    an invalid design (a layout the robot file's schema refuses) scores 0 with cause 'invalid'."""
    settings = settings_of(problem.section.objective)
    try:
        robot = problem.robot(x)
    except KingenError:
        return 0.0, [(0.0, "invalid")] * len(settings.azimuths), 0
    posture = problem.posture(robot)
    if judges(robot):
        table, judged = tilt_table(robot, posture, settings)
    else:
        rows = tilt_limits(robot, posture, settings)
        table, judged = [(row["max_tilt_deg"], row["cause"]) for row in rows], len(rows) * len(settings.tilts)
    return min((tilt for tilt, _ in table), default=0.0), table, judged


def optimized_name(name):
    """``<name>_optimized``, the name cut short where it must be for the whole to stay within
    MAX_NAME characters: a name kingen accepts."""
    return suffixed_name(name, OPTIMIZED)


def suffixed_name(name, suffix):
    """``<name><suffix>``, the name cut short where it must be for the whole to stay within
    MAX_NAME characters: a name kingen accepts."""
    return f"{name[:MAX_NAME - len(suffix)]}{suffix}"


def design_yaml(problem, x, objective, header):
    """The robot file of design ``x``: the file's data with the design in it, renamed
    optimized_name(name), ``header`` (lines) as comments on top."""
    data = problem.design_data(x)
    data["name"] = optimized_name(data["name"])
    data["description"] = f"{' '.join(str(data.get('description', '')).split())} Optimised by kingen: " \
                          f"least tilt {objective:g} degrees."
    data["source"] = " ".join(header)
    return robot_yaml(data, header)


def robot_yaml(data, header):
    """A robot file's text from its plain ``data``, ``header`` (lines) as comments on top;
    floats rounded to 1e-9."""
    from ruamel.yaml import YAML

    buffer = io.StringIO()
    writer = YAML()
    writer.default_flow_style = None
    writer.width = 100
    writer.dump(_plain(data), buffer)
    return "".join(f"# {line}\n" for line in header) + buffer.getvalue()


def _plain(value):
    """Data as YAML writes it: dicts, lists, floats rounded to 1e-9, no numpy types."""
    if isinstance(value, dict):
        return {key: _plain(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(item) for item in value]
    if isinstance(value, (float, np.floating)):
        return round(float(value), 9)
    if isinstance(value, np.integer):
        return int(value)
    return value
