"""Hypothesis strategies: robot files a designer could write, for every family the schema takes.

Each strategy draws a family's dimensionless proportions and a scale in the file's unit (mm,
metres or inches) and returns ``(family, document)``: the plain data of a robot file whose
verification home the machine reaches regularly (every limb within reach, not singular), a
working posture named where it has several. The homes are placed from the geometry written out
here (the carriage above its rod's joint, the platform on its manifold), not from kingen.
``coincident_tricept`` draws the one family that must fail: a Tricept whose first two legs are
one, singular everywhere.
"""

import math

from hypothesis import assume, strategies as st

UNITS = {"mm": 1.0, "m": 1000.0, "inch": 25.4}
"""mm per unit of the file."""


def _scale(draw, units):
    """The machine's size in the file's unit: 30 mm to 3 m."""
    return 10.0 ** draw(st.floats(1.5, 3.5)) / UNITS[units]


def _r(value):
    """A number as a drawing gives it: rounded to 12 significant digits (YAML and back)."""
    return float(f"{value:.12g}")


def _point(radius, angle, z=0.0):
    return [_r(radius * math.cos(angle)), _r(radius * math.sin(angle)), _r(z)]


def _angles(draw):
    """Three limbs' angles (radians): 120 degrees apart from a drawn start, each moved by up to 8 degrees."""
    start = draw(st.floats(0.0, 120.0))
    return [math.radians(start + 120.0 * index + draw(st.floats(-8.0, 8.0))) for index in range(3)]


def _document(name, family, units, body, home, spread):
    document = {"name": name, "description": f"A {family} drawn at random (tests/machines.py).", **body,
                "verification": {"home": [_r(value) for value in home], "range": [_r(value) for value in spread]}}
    if units != "mm":
        document["units"] = units
    return document


@st.composite
def hexapod(draw, units="mm"):
    """Six S-P-S legs on the Stewart-Gough layout; absolute lengths (reference 0) or a reference length."""
    s = _scale(draw, units)
    base_pair, platform_pair = draw(st.floats(10.0, 40.0)), draw(st.floats(80.0, 110.0))
    base, platform, height = s, s * draw(st.floats(0.4, 0.8)), s * draw(st.floats(0.7, 1.4))
    first_base, first_platform = math.radians(60.0 - base_pair / 2), math.radians(60.0 - platform_pair / 2)
    leg = math.dist(_point(base, first_base), _point(platform, first_platform, height))
    absolute = draw(st.booleans())
    layout = {"type": "stewart_gough", "base_radius": _r(base), "platform_radius": _r(platform),
              "base_pair_angle": _r(base_pair), "platform_pair_angle": _r(platform_pair),
              "reference_length": 0.0 if absolute else _r(round(leg * draw(st.floats(0.9, 1.0)), 3))}
    family = "hexapod (absolute lengths)" if absolute else "hexapod (reference length)"
    return family, _document("drawn_hexapod", family, units, {"layout": layout}, [0, 0, height, 0, 0, 0],
                             [0.05 * s, 0.05 * s, 0.05 * s, 3, 3, 3])


@st.composite
def linear_delta(draw, units="mm"):
    """Three vertical towers (lineardeltakins' layout), carriages above the effector."""
    s = _scale(draw, units)
    layout = {"type": "linear_delta", "R": _r(s), "L": _r(s * draw(st.floats(1.4, 2.5)))}
    body = {"layout": layout, "forward": {"free": ["x", "y", "z"]}, "working_posture": 7}
    return "linear delta", _document("drawn_linear_delta", "linear delta", units, body, [0, 0, 0, 0, 0, 0],
                                     [0.3 * s, 0.3 * s, 0.2 * s, 0, 0, 0])


@st.composite
def rotary_delta(draw, units="mm"):
    """Three cranks (rotarydeltakins' layout), knees out; the foot joints within 55 to 85 % of full reach."""
    s = _scale(draw, units)
    thigh, shin, foot = s * draw(st.floats(0.7, 1.2)), s * draw(st.floats(1.3, 1.8)), s * draw(st.floats(0.3, 0.7))
    across = s - foot
    reach = draw(st.floats(0.55, 0.85)) * (thigh + shin)
    layout = {"type": "rotary_delta", "platformradius": _r(s), "thighlength": _r(thigh), "shinlength": _r(shin),
              "footradius": _r(foot)}
    body = {"layout": layout, "forward": {"free": ["x", "y", "z"]}, "working_posture": 7}
    return "rotary delta", _document("drawn_rotary_delta", "rotary delta", units, body,
                                     [0, 0, -math.sqrt(reach * reach - across * across), 0, 0, 0],
                                     [0.05 * s, 0.05 * s, 0.05 * s, 0, 0, 0])


@st.composite
def prs(draw, units="mm", inclined=None):
    """3-PRS: rails at the base radius, vertical or leaning inwards going up by 15 to 40 degrees,
    tangential revolute joints on the carriages, rods to spherical joints on the platform; the
    home has every carriage above its rod's platform joint (posture 7)."""
    s = _scale(draw, units)
    lean = math.radians(draw(st.floats(15.0, 40.0))) if (draw(st.booleans()) if inclined is None else inclined) else 0.0
    platform, carriage = s * draw(st.floats(0.3, 0.6)), -s * draw(st.floats(0.2, 0.8))
    across = s - carriage * math.sin(lean) - platform  # carriage to platform joint, horizontally
    rod = across * draw(st.floats(1.15, 2.0))
    drop = math.sqrt(rod * rod - across * across)
    assume(drop * math.cos(lean) - across * math.sin(lean) > 0.05 * rod)  # the carriage above, along the rail
    limbs = []
    for index, angle in enumerate(_angles(draw)):
        radial, tangent = (math.cos(angle), math.sin(angle)), (-math.sin(angle), math.cos(angle))
        limbs.append({"name": f"rail{index + 1}", "model": "rail", "rail_point": _point(s, angle),
                      "direction": [_r(-math.sin(lean) * radial[0]), _r(-math.sin(lean) * radial[1]), _r(math.cos(lean))],
                      "carriage_offset": [0, 0, 0], "platform_point": _point(platform, angle), "link_length": _r(rod),
                      "revolute_axis": [_r(tangent[0]), _r(tangent[1]), 0.0]})
    family = "3-PRS (inclined rails)" if lean else "3-PRS (vertical rails)"
    body = {"limbs": limbs, "task": ["z", "roll", "pitch"], "working_posture": 7}
    return family, _document("drawn_prs", family, units, body, [0, 0, carriage * math.cos(lean) - drop, 0, 0, 0],
                             [0.01 * s, 0.01 * s, 0.1 * s, 5, 5, 1])


@st.composite
def rps(draw, units="mm"):
    """3-RPS: tangential revolute joints at the base, prismatic legs (absolute lengths), spherical joints."""
    s = _scale(draw, units)
    platform, height = s * draw(st.floats(0.3, 0.7)), s * draw(st.floats(0.8, 1.5))
    limbs = [{"name": f"leg{index + 1}", "model": "leg", "base_point": _point(s, angle),
              "platform_point": _point(platform, angle), "reference_length": 0.0,
              "revolute_axis": [_r(-math.sin(angle)), _r(math.cos(angle)), 0.0]}
             for index, angle in enumerate(_angles(draw))]
    return "3-RPS", _document("drawn_rps", "3-RPS", units, {"limbs": limbs, "task": ["z", "roll", "pitch"]},
                              [0, 0, height, 0, 0, 0], [0.01 * s, 0.01 * s, 0.1 * s, 5, 5, 1])


def _tricept_body(draw, s, coincident=False):
    """A Tricept's parallel part at scale ``s``: three U-P-S legs and the passive tube from the base
    origin, the universal joint's first axis horizontal; (body, home height)."""
    platform, height = s * draw(st.floats(0.3, 0.6)), s * draw(st.floats(1.8, 3.2))
    angles = _angles(draw)
    if coincident:
        angles[1] = angles[0]
    limbs = [{"name": f"leg{index + 1}", "model": "leg", "base_point": _point(s, angle),
              "platform_point": _point(platform, angle), "reference_length": 0.0}
             for index, angle in enumerate(angles)]
    first = math.radians(draw(st.floats(0.0, 180.0)))
    tube = {"base_point": [0, 0, 0], "first_axis": [_r(math.cos(first)), _r(math.sin(first)), 0.0],
            "tube_axis": [0, 0, -1]}
    return {"limbs": limbs, "passive_leg": tube, "task": ["x", "y", "z"]}, -height


@st.composite
def tricept(draw, units="mm"):
    """A Tricept-type machine: three U-P-S legs and the passive central tube (task x, y, z)."""
    s = _scale(draw, units)
    body, z = _tricept_body(draw, s)
    return "Tricept", _document("drawn_tricept", "Tricept", units, body, [0, 0, z, 0, 0, 0],
                                [0.15 * s, 0.15 * s, 0.15 * s, 10, 10, 10])


@st.composite
def coincident_tricept(draw, units="mm"):
    """A Tricept whose first two legs have the same base and platform points: singular everywhere."""
    s = _scale(draw, units)
    body, z = _tricept_body(draw, s, coincident=True)
    return "Tricept with coincident legs", _document("drawn_coincident", "Tricept with coincident legs", units, body,
                                                     [0, 0, z, 0, 0, 0], [0.15 * s, 0.15 * s, 0.15 * s, 10, 10, 10])


def _exechon_body(draw, s):
    """An Exechon-type parallel part at scale ``s``: legs 1 and 2 from (+-s, 0, 0) sharing the
    platform's y axis, leg 3 from the base's y axis with the platform's x axis; (body, home)
    with the home on its manifold (x 0, y the platform points' offset e, rotation none)."""
    half, offset, depth = s * draw(st.floats(0.3, 0.5)), s * draw(st.floats(0.0, 0.2)), s * draw(st.floats(0.5, 1.2))
    third, reach = s * draw(st.floats(1.2, 1.8)), s * draw(st.floats(0.3, 0.5))
    limbs = [{"name": "leg1", "model": "leg", "base_point": [_r(s), 0, 0], "platform_point": [_r(half), _r(-offset), _r(depth)],
              "reference_length": 0.0, "platform_revolute_axis": [0, 1, 0]},
             {"name": "leg2", "model": "leg", "base_point": [_r(-s), 0, 0], "platform_point": [_r(-half), _r(-offset), _r(depth)],
              "reference_length": 0.0, "platform_revolute_axis": [0, 1, 0]},
             {"name": "leg3", "model": "leg", "base_point": [0, _r(third), 0], "platform_point": [0, _r(reach), _r(depth)],
              "reference_length": 0.0, "platform_revolute_axis": [1, 0, 0]}]
    return {"limbs": limbs, "task": ["x", "y", "z"]}, [0, _r(offset), _r(-depth - s * draw(st.floats(0.8, 1.5))), 0, 0, 0]


@st.composite
def exechon(draw, units="mm"):
    """An Exechon-type machine: revolute axes fixed in the platform (task x, y, z)."""
    s = _scale(draw, units)
    body, home = _exechon_body(draw, s)
    return "Exechon type", _document("drawn_exechon", "Exechon type", units, body, home,
                                     [0.1 * s, 0.1 * s, 0.1 * s, 10, 10, 10])


@st.composite
def wrist(draw, units="mm"):
    """A Tricept or Exechon-type parallel part (in mm: a wrist needs it) with an RR wrist at the
    platform origin (about the platform's z axis, then the x axis it carries), or an RRR one (then
    about the z axis the second carries), and a tool."""
    s = _scale(draw, "mm")
    if draw(st.booleans()):
        body, z = _tricept_body(draw, s)
        home, family = [0, 0, z, 0, 0, 0], "Tricept with a wrist"
    else:
        body, home = _exechon_body(draw, s)
        family = "Exechon type with a wrist"
    joints = [{"name": "ax4", "axis": [0, 0, 1], "travel": [-270, 270]},
              {"name": "ax5", "axis": [1, 0, 0], "travel": [-110, 110]}]
    if draw(st.booleans()):  # a spherical wrist: the tool's turn too
        joints.append({"name": "ax6", "axis": [0, 0, 1], "travel": [-360, 360]})
        family = family.replace("a wrist", "a three-axis wrist")
    body.update({"wrist": joints, "tool": [0, 0, _r(-s * draw(st.floats(0.1, 0.4))), 180, 0, 0], "working_posture": 0})
    return family, _document("drawn_wrist", family, "mm", body, home, [0.1 * s, 0.1 * s, 0.1 * s, 10, 10, 10])


FAMILIES = {"hexapod": hexapod, "linear delta": linear_delta, "rotary delta": rotary_delta, "3-PRS": prs,
            "3-RPS": rps, "Tricept": tricept, "Exechon type": exechon, "wrist": wrist}
"""Every family a user may write that verify must pass."""


@st.composite
def machines(draw):
    """(family, document) of any family that must pass, in mm, metres or inches (a wrist: mm)."""
    units = draw(st.sampled_from(sorted(UNITS)))
    family, document = draw(FAMILIES[draw(st.sampled_from(sorted(FAMILIES)))](units))
    return (f"{family}, {document['units']}" if "units" in document else family), document


LENGTH_FIELDS = ("base_point", "platform_point", "rail_point", "carriage_offset", "link_length", "reference_length",
                 "base_radius", "platform_radius", "R", "L", "platformradius", "thighlength", "shinlength", "footradius")
"""The length fields of the families drawn here (a wrist's tool position and the region's positions aside)."""


def in_units(document, units):
    """``document`` (a drawn robot file in mm) with every length written in ``units``: the same machine."""
    scale = 1.0 / UNITS[units]

    def scaled(mapping):
        return {key: ([value * scale for value in item] if isinstance(item, list) else item * scale)
                if key in LENGTH_FIELDS else item for key, item in mapping.items()}

    converted = dict(document, units=units)
    if "limbs" in document:
        converted["limbs"] = [scaled(limb) for limb in document["limbs"]]
    if "layout" in document:
        converted["layout"] = scaled(document["layout"])
    if "passive_leg" in document:
        converted["passive_leg"] = scaled(document["passive_leg"])
    region = document["verification"]
    converted["verification"] = {key: [value * scale for value in region[key][:3]] + region[key][3:]
                                 for key in ("home", "range")}
    return converted
