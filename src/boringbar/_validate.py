"""Parameter checks at the boundary: every error names the parameter, its value
and the allowed range (STYLE.md rule 6)."""

from __future__ import annotations

import math


class ParameterError(ValueError):
    """A parameter outside its allowed range. The message is one line."""


def check_range(name: str, value, lo: float, hi: float, *, lo_open: bool = False,
                hi_open: bool = False, unit: str = "") -> float:
    """Return ``value`` as float if lo <= value <= hi (open ends as asked), else raise."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} = {value!r} is not a number") from None
    ok = math.isfinite(v) or (v == hi == math.inf)
    ok = ok and (v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi)
    if not ok:
        u = f" {unit}" if unit else ""
        left = "(" if lo_open else "["
        right = ")" if hi_open else "]"
        raise ParameterError(f"{name} = {value!r}{u} is outside the allowed range "
                             f"{left}{lo:g}, {hi:g}{right}{u}")
    return v


def check_positive(name: str, value, unit: str = "") -> float:
    return check_range(name, value, 0.0, math.inf, lo_open=True, hi_open=True, unit=unit)


def check_nonnegative(name: str, value, unit: str = "") -> float:
    return check_range(name, value, 0.0, math.inf, hi_open=True, unit=unit)


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
