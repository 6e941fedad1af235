"""The number formatter every emitter writes through (robotkit.emit.env.fmt): sums of the
decimals a recipe gives print as those decimals; the resolution is 15 significant digits."""

import pytest

from robotkit.emit.env import SIGNIFICANT_DIGITS, fmt, vec


@pytest.mark.parametrize("value, text", [
    (0.1 + 0.0175, "0.1175"),          # repr: 0.11750000000000001
    (0.1 + 0.2, "0.3"),                # repr: 0.30000000000000004
    (0.05 * 3, "0.15"),                # repr: 0.15000000000000002
    (1.1 * 1.1, "1.21"),               # repr: 1.2100000000000002
    (-(0.1 + 0.2), "-0.3"),
    (2.0, "2"),
    (-0.0, "0"),
    (1e-20, "1e-20"),
    (1.5e-5, "1.5e-05"),
    (1 / 3, "0.333333333333333"),           # repr: 0.3333333333333333
    (0.013152801243029269, "0.0131528012430293"),
    (123456.7890123456, "123456.789012346"),
    (1e12, "1000000000000"),
    (0.0254, "0.0254"),
])
def test_numbers_print_as_written(value, text):
    assert fmt(value) == text


def test_resolution_is_fifteen_significant_digits():
    assert SIGNIFICANT_DIGITS == 15
    x = 0.123456789012345678
    assert abs(float(fmt(x)) - x) <= 0.5e-15  # half a unit in the 15th significant digit
    assert fmt(x) == "0.123456789012346"
    assert fmt(1 + 4e-16) == "1"
    assert fmt(1 + 6e-15) == "1.00000000000001"


def test_vec_and_non_finite():
    assert vec([0.05, 0.1 + 0.0175, 0.05]) == "0.05 0.1175 0.05"
    with pytest.raises(ValueError):
        fmt(float("nan"))
