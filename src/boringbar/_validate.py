"""Parameter checks at the boundary: every error names the parameter, its value
and the allowed range, so that a user knows what to change.

Every number checked here must be finite: NaN and +-inf are refused by every
helper, whatever the range (a NaN compares False with every bound, so a range
test alone would let it through), and so are booleans (``True`` is not 1.0 to
a user)."""

from __future__ import annotations

import math
import numbers
import tomllib
from pathlib import Path

import numpy as np


class ParameterError(ValueError):
    """A parameter outside its allowed range. The message is one line."""


#: Relative slack of a closed bound. A bound computed from other lengths (a cavity's
#: depth less its ball: 10.2 mm - 10 mm is 0.19999999999999973 mm) carries their
#: round-off, and a value typed as that bound must pass.
ROUND_OFF = 1e-9


def near(v: float, bound: float, scale: float = 0.0) -> bool:
    """Whether ``v`` equals ``bound`` up to :data:`ROUND_OFF` of the larger of |bound|
    and ``scale`` (the size of the lengths the two were computed from: a position 0
    on a bar 0.2 m long is 0 up to 0.2 ROUND_OFF m)."""
    return abs(v - bound) <= ROUND_OFF * max(abs(bound), scale)


def in_range(v: float, lo: float, hi: float, lo_open: bool = False, hi_open: bool = False,
             *, scale: float = 0.0) -> bool:
    """Whether the finite number ``v`` lies in the range, a closed end up to
    :data:`ROUND_OFF` beyond it (:func:`near`, with ``scale``); an open end is strict."""
    above = v > lo if lo_open else v >= lo or near(v, lo, scale)
    below = v < hi if hi_open else v <= hi or near(v, hi, scale)
    return above and below


def _interval(lo, hi, lo_open: bool, hi_open: bool, unit: str) -> str:
    left = "(" if lo_open else "["
    right = ")" if hi_open else "]"
    return f"{left}{lo:g}, {hi:g}{right}{unit}"


def check_range(name: str, value, lo: float, hi: float, *, lo_open: bool = False,
                hi_open: bool = False, unit: str = "", why: str = "") -> float:
    """Return ``value`` as float if it is finite and lo <= value <= hi (open ends as
    asked; a closed end up to :data:`ROUND_OFF` of itself), else raise ParameterError
    naming ``name``, the value and the range (and ``why``, where the range comes from)."""
    u = f" {unit}" if unit else ""
    if type(value) is float:  # the common case, without the conversions
        v = value
    else:
        value, v = _number(name, value, lo, hi, lo_open, hi_open, u)
    if not math.isfinite(v):
        raise ParameterError(f"{name} = {value!r}{u} is not a finite number (allowed range "
                             f"{_interval(lo, hi, lo_open, hi_open, u)})")
    if not in_range(v, lo, hi, lo_open, hi_open):
        raise ParameterError(f"{name} = {value!r}{u} is outside the allowed range "
                             f"{_interval(lo, hi, lo_open, hi_open, u)}"
                             + (f" ({why})" if why else ""))
    return v


def _number(name: str, value, lo, hi, lo_open: bool, hi_open: bool, u: str) -> tuple:
    """(``value`` as an error shows it, ``value`` as a float) for a value that is not a
    float already (a numpy scalar, an int, a numeric string), else ParameterError
    naming ``name``."""
    if hasattr(value, "item") and getattr(value, "ndim", None) == 0:
        value = value.item()  # a numpy scalar, shown as the number it is
    if isinstance(value, bool):
        raise ParameterError(f"{name} = {value!r} is not a number (allowed range "
                             f"{_interval(lo, hi, lo_open, hi_open, u)})")
    try:
        return value, float(value)
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(f"{name} = {value!r} is not a number") from None


def check_finite(name: str, value, unit: str = "") -> float:
    """Any finite number."""
    return check_range(name, value, -math.inf, math.inf, lo_open=True, hi_open=True, unit=unit)


def check_positive(name: str, value, unit: str = "") -> float:
    return check_range(name, value, 0.0, math.inf, lo_open=True, hi_open=True, unit=unit)


def check_nonnegative(name: str, value, unit: str = "") -> float:
    return check_range(name, value, 0.0, math.inf, hi_open=True, unit=unit)


def check_int(name: str, value, lo: int, hi: float) -> int:
    """Return ``value`` as int if it is a whole number in [lo, hi] (an integral
    float such as 3.0 is accepted; 2.5, NaN, inf and booleans are not)."""
    whole = isinstance(value, numbers.Integral) or (
        isinstance(value, numbers.Real) and math.isfinite(value) and float(value).is_integer())
    if isinstance(value, bool) or not whole:
        raise ParameterError(f"{name} = {value!r} is not a whole number (allowed range "
                             f"[{lo:g}, {hi:g}])")
    check_range(name, value, lo, hi)
    return int(value)


def check_bool(name: str, value) -> bool:
    """``value`` if it is a bool (NumPy's too): a string such as "off" is true to Python,
    so it is refused rather than read as on."""
    if not isinstance(value, bool | np.bool_):
        raise ParameterError(f"{name} = {value!r} must be True or False")
    return bool(value)


def check_choice(name: str, value, choices) -> str:
    if value not in choices:
        raise ParameterError(f"{name} = {value!r} is not one of {', '.join(map(str, choices))}")
    return value


def check_values(name: str, values, lo: float, hi: float, *, lo_open: bool = False,
                 hi_open: bool = False, unit: str = "") -> tuple[float, ...]:
    """A number or a non-empty sequence of numbers, each in the range of
    :func:`check_range`, as a tuple of floats."""
    seq = [values] if isinstance(values, int | float) else values
    try:
        items = list(seq)
    except TypeError:
        raise ParameterError(f"{name} = {values!r} is not a number or a list of "
                             "numbers") from None
    if not items:
        raise ParameterError(f"{name} is empty: give at least one value")
    return tuple(check_range(f"{name}[{i}]", v, lo, hi, lo_open=lo_open, hi_open=hi_open,
                             unit=unit) for i, v in enumerate(items))


def read_toml(path, error: type[ParameterError], what: str) -> dict:
    """The TOML file ``path`` as a dict; a file that cannot be read or parsed raises
    ``error`` with one line naming the file and ``what`` it is (e.g. "study file")."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except OSError as exc:
        raise error(f"{path}: cannot read the {what}: {exc.strerror}") from None
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML: {exc}") from None
