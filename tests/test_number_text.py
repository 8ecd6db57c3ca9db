"""Numbers written for people (kingen.units.number_text, length_text): the values written out
here by hand, and, for any value, a text without exponent or -0 that reads back to the value
within its rounding."""

import math
import re

import pytest
from hypothesis import given
from hypothesis import strategies as st

from kingen.units import NEGLIGIBLE, fixed_text, length_text, number_text

MM_PER = {"mm": 1.0, "um": 1e-3, "nm": 1e-6, "pm": 1e-9}


@pytest.mark.parametrize("mm, text", [
    (7.28e-10, "0.728 pm"), (7.3e-7, "0.73 nm"), (7.28e-6, "7.28 nm"), (0.0073, "7.3 um"),
    (0.05, "50 um"), (0.5, "0.5 mm"), (1200.0, "1200 mm"), (1234.5678, "1235 mm"),
    (-0.0004, "-0.4 um"), (0.0, "0 mm"), (-0.0, "0 mm"), (-9.21313e-17, "0 mm"),
    (9.99941e-15, "0 mm"), (math.nan, "nan mm"),
])
def test_lengths_by_hand(mm, text):
    assert length_text(mm) == text


@pytest.mark.parametrize("value, text", [
    (1.91408, "1.91"), (-0.736636, "-0.737"), (-1.84842e-31, "0"), (-1e-13, "0"), (-0.0, "0"),
    (0.000123456, "0.000123"), (123456.0, "123456"), (0.9999, "1"), (2.0, "2"), (math.inf, "inf"),
])
def test_numbers_by_hand(value, text):
    assert number_text(value) == text


@pytest.mark.parametrize("value, decimals, sign, text", [
    (-1e-7, 6, False, "0.000000"), (-0.0, 3, False, "0.000"), (-0.0004, 3, True, "+0.000"),
    (-0.0006, 3, True, "-0.001"), (2040.3825494, 6, True, "+2040.382549"), (-4.5739212604, 9, False, "-4.573921260"),
])
def test_fixed_columns_never_show_minus_zero(value, decimals, sign, text):
    assert fixed_text(value, decimals, sign) == text


magnitudes = st.floats(min_value=-15, max_value=6).map(lambda power: 10.0 ** power)


@given(magnitudes, st.sampled_from([-1.0, 1.0]))
def test_a_length_reads_back_within_its_rounding(magnitude, sign):
    mm = sign * magnitude
    text = length_text(mm)
    assert re.fullmatch(r"-?\d+(\.\d+)? (mm|um|nm|pm)", text), text
    number, unit = text.split()
    assert number != "-0"
    if abs(mm) <= NEGLIGIBLE:
        assert text == "0 mm"
        return
    shown = float(number)
    # The first unit in which it reads at least 0.1: so at least 0.1 in it (pm the last resort)
    # and below 0.1 in the unit before it.
    units = list(MM_PER)
    assert abs(shown) >= 0.1 or unit == "pm", text
    assert unit == "mm" or abs(mm) / MM_PER[units[units.index(unit) - 1]] < 0.1, text
    assert shown * MM_PER[unit] == pytest.approx(mm, rel=5e-3), text
