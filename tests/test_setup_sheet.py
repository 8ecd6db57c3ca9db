"""The setup sheet: what a user types into DELMIA's Inverse Kinematics dialog."""

import re

from kingen.model import load_robot
from kingen.hosts.delmia.package import render_package


def sheet(name, target="windows"):
    return render_package(load_robot(name), target)["SETUP.md"]


def test_tau_sheet_names_library_routine_postures_and_actuators():
    text = sheet("tau")
    assert "| Library | `libtau` |" in text and "| Routine | `kin_tau` |" in text
    assert "User Inverse" in text
    assert "8 postures" in text
    assert "| 5 (101) | branch 1 | branch 0 | branch 1 |" in text
    rows = re.findall(r"^\| (\d) \| dof\(\d\) \| Translational \| Trans Z \| (carriage\d) \|$", text, flags=re.MULTILINE)
    assert rows == [("1", "carriage1"), ("2", "carriage2"), ("3", "carriage3")]
    assert "| carriage3 | -1 | 2600 | mm |" in text


def test_ceart_sheet_lists_64_postures_and_rotational_actuators():
    text = sheet("ceart")
    assert "64 postures" in text
    assert len(re.findall(r"^\| \d+ \([01]{6}\) \|", text, flags=re.MULTILINE)) == 64
    assert "| 63 (111111) | branch 1 | branch 1 | branch 1 | branch 1 | branch 1 | branch 1 |" in text
    assert text.count("| Rotational | Rot Z |") == 6


def test_sheet_lists_calibration_fields_with_units_and_built_in_values():
    text = sheet("exechon")
    assert "| Length 3 | leg3.reference_length | mm | 886.021 |" in text
    assert "| Length 3 | read, see below |" in text and "| Length 4 | leave empty |" in text
    ceart = sheet("ceart")
    assert "| Offset 6 | crank6.zero_offset | degrees | 0 |" in ceart


def test_sheet_says_when_nothing_is_read_and_no_limits_exist():
    text = sheet("hexapod", "linux")
    assert "The routine reads no Length or Offset field" in text
    assert "No travel limits are declared" in text
    assert "libhexapod.so" in text
