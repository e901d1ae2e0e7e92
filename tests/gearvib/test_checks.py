"""gearvib.checks: the number checks of the descriptions and the exact wording of their errors.

The messages below are those the gear-set tables, run settings, study recipes and fault and
sensor descriptions gave before they shared one checker; users and other tests rely on them.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from gearvib.checks import ITEM, RECIPE, RUN, TABLE, check_integer, check_number, short

BIG = 10**320  # an integer too large for a float
NUMPY = (int, float, np.integer, np.floating)


def _message(**kw) -> str:
    with pytest.raises(ValueError) as info:
        check_number(**kw)
    return str(info.value)


@pytest.mark.parametrize("kw, message", [
    # gear-set tables
    ({"value": "1", "name": "[x].y"}, "[x].y must be a number, got '1'"),
    ({"value": True, "name": "[x].y"}, "[x].y must be a number, got True"),
    ({"value": np.int64(3), "name": "[x].y"}, "[x].y must be a number, got np.int64(3)"),
    ({"value": "a" * 60, "name": "[x].y"}, f"[x].y must be a number, got '{'a' * 36}..."),
    ({"value": BIG, "name": "[x].y"},
     f"[x].y = {str(BIG)[:37]}... is not admissible (admissible: a finite number)"),
    ({"value": math.nan, "name": "[x].y"}, "[x].y is NaN; admissible: a finite number"),
    ({"value": -math.inf, "name": "[x].y"},
     "[x].y = -inf is not admissible (admissible: a finite number)"),
    ({"value": 0, "name": "[x].y", "low": 0.0, "low_open": True},
     "[x].y = 0.0 is not admissible (admissible: > 0)"),
    ({"value": -1, "name": "[x].y", "low": 0.0, "high": 5.0},
     "[x].y = -1.0 is not admissible (admissible: >= 0)"),
    ({"value": 6, "name": "[x].y", "low": 0.0, "high": 5.0},
     "[x].y = 6.0 is not admissible (admissible: <= 5)"),
    # run settings: NaN and infinity "finite", the upper bound on the magnitude
    ({"value": math.nan, "name": "[simulation].dt", "wording": RUN},
     "[simulation].dt = nan is not admissible (admissible: finite)"),
    ({"value": -2e13, "name": "[simulation].motor.breakdown_torque", "high": 1e12,
      "magnitude": True, "symbol": "breakdown_torque", "wording": RUN},
     "[simulation].motor.breakdown_torque = -20000000000000.0 is not admissible "
     "(admissible: |breakdown_torque| <= 1e+12)"),
    ({"value": 0.0, "name": "[simulation].duration", "low": 1e-6, "high": 1e7,
      "magnitude": True, "symbol": "duration", "wording": RUN},
     "[simulation].duration = 0.0 is not admissible (admissible: >= 1e-06)"),
    # study recipes: terse, the value as given
    ({"value": 0, "name": "[analysis].tolerance", "low": 0.0, "low_open": True,
      "wording": RECIPE}, "[analysis].tolerance = 0; admissible: a number > 0"),
    ({"value": 2000, "name": "[analysis].x", "high": 1e3, "wording": RECIPE},
     "[analysis].x = 2000; admissible: a number <= 1000"),
    ({"value": BIG, "name": "[analysis].x", "wording": RECIPE},
     f"[analysis].x = {str(BIG)[:37]}...; admissible: a finite number"),
    ({"value": math.inf, "name": "[analysis].x", "wording": RECIPE},
     "[analysis].x = inf; admissible: a finite number"),
    # fault and sensor items: whole values, the range written whole around the key
    ({"value": [1] * 30, "name": "s: gain", "types": NUMPY, "wording": ITEM},
     f"s: gain must be a number, got {[1] * 30!r}"),
    ({"value": BIG, "name": "s: gain", "types": NUMPY, "wording": ITEM},
     f"s: gain = {str(BIG)[:20]}... (321 digits) is not admissible "
     "(admissible: a finite number)"),
    ({"value": np.float64(np.inf), "name": "s: gain", "types": NUMPY, "wording": ITEM},
     "s: gain = inf is not admissible (admissible: finite)"),
    ({"value": 1.0, "name": "t: duty", "low": 0.0, "high": 1.0, "low_open": True,
      "high_open": True, "symbol": "duty", "types": NUMPY, "wording": ITEM},
     "t: duty = 1.0 is not admissible (admissible: 0 < duty < 1)"),
    ({"value": 2e-3, "name": "f: e", "low": -1e-3, "high": 1e-3, "symbol": "e",
      "wording": ITEM}, "f: e = 0.002 is not admissible (admissible: -0.001 <= e <= 0.001)"),
    ({"value": -1, "name": "f: depth", "low": 0.0, "symbol": "depth", "wording": ITEM},
     "f: depth = -1.0 is not admissible (admissible: 0 <= depth)"),
])
def test_number_messages_keep_each_wording(kw, message):
    assert _message(**kw) == message


@pytest.mark.parametrize("value", [0, 0.5, -3, np.float64(2.0), 1e308, 5e-324])
def test_admissible_numbers_come_back_as_floats(value):
    got = check_number(value, "x", low=-10.0, high=1e308)
    assert type(got) is float and got == float(value)
    # the bounds themselves are admissible unless open
    assert check_number(1.0, "x", low=1.0, high=1.0) == 1.0
    assert check_number(np.int32(4), "x", types=NUMPY, wording=ITEM) == 4.0


def test_the_callers_error_class_is_raised():
    class Custom(ValueError):
        pass

    with pytest.raises(Custom, match=re.escape("k = 2.0 is not admissible (admissible: <= 1)")):
        check_number(2, "k", high=1.0, error=Custom)
    with pytest.raises(Custom, match="k must be an integer"):
        check_integer(2.5, "k", error=Custom)


@pytest.mark.parametrize("kw, message", [
    ({"value": 2.5, "name": "[x].z"}, "[x].z must be an integer, got 2.5"),
    ({"value": True, "name": "[x].z"}, "[x].z must be an integer, got True"),
    ({"value": 2, "name": "[x].z", "low": 3}, "[x].z = 2 is not admissible (admissible: >= 3)"),
    ({"value": 10**50, "name": "[x].z", "high": 1000},
     f"[x].z = {str(10**50)[:37]}... is not admissible (admissible: <= 1000)"),
    ({"value": 10**50, "name": "f: tooth", "low": 0, "high": 10, "wording": ITEM},
     f"f: tooth = {10**50} is not admissible (admissible: <= 10)"),
    ({"value": 3.0, "name": "[analysis].n", "low": 1, "types": (int,), "wording": RECIPE},
     "[analysis].n = 3.0; admissible: an integer >= 1"),
    ({"value": 0, "name": "[analysis].n", "low": 1, "high": 80, "types": (int,),
      "wording": RECIPE}, "[analysis].n = 0; admissible: an integer >= 1 and <= 80"),
])
def test_integer_messages_keep_each_wording(kw, message):
    with pytest.raises(ValueError) as info:
        check_integer(**kw)
    assert str(info.value) == message


def test_admissible_integers_come_back_as_ints():
    assert check_integer(33.0, "z", low=3) == 33 and type(check_integer(33.0, "z")) is int
    assert check_integer(np.int64(7), "z", types=(int, np.integer), wording=ITEM) == 7
    assert check_integer(5, "n", low=1, high=5, types=(int,), wording=RECIPE) == 5


def test_short_keeps_40_characters():
    assert short("ab") == "'ab'"
    assert short("x" * 100) == "'" + "x" * 36 + "..."
    assert len(short(list(range(100)))) == 40
    assert TABLE.shown("x" * 100) == short("x" * 100) and ITEM.shown("x" * 100) == repr("x" * 100)
