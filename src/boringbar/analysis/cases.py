"""What the analyses are given: the cases (a bar, labelled, with what distinguishes it) and
the value grids of their axes.

:class:`Case` is one bar of an analysis; :func:`as_cases` takes what a caller gave (a
System, a Case, a sequence or a mapping of them) and :func:`published_cases` builds the
published bars.  :func:`parse_range` reads a grid from text, START:STOP:STEP or a comma
list, as the command line and the study files give it.  Nothing here imports the
analyses' own libraries (xarray, SciPy's optimisers), so that the command line's
parsing stays light.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from boringbar._validate import ParameterError
from boringbar.model.oriented import CutGeometry, for_bar
from boringbar.model.system import System, make_system, published_system_spec
from boringbar.model.system_file import PUBLISHED_NAME, SystemSpec
from boringbar.simulate import Initial

#: Most values of one START:STOP:STEP range or list (:func:`parse_range`; the
#: published sweep has 11 ratios, the bifurcation 46 forces).
MAX_GRID_VALUES = 100_000


@dataclass(frozen=True, eq=False)
class Case:
    """One bar of a sweep: a ``label``, the ``system``, and what distinguishes it:
    ``bar`` kind, ``gap_m`` (m, NaN without a ball) and ``friction`` ("on", "off",
    "n/a"); ``initial``: this case's initial conditions (default: the
    integration's).  :meth:`of` makes one from a system alone; the bar, gap and
    friction given must be the system's (a ParameterError says which is not)."""

    label: str
    system: System
    bar: str
    gap_m: float = math.nan
    friction: str = "n/a"
    initial: Initial | None = None

    def __post_init__(self):
        if not isinstance(self.system, System):
            raise TypeError(_not_a_system("Case system", self.system))
        given = (self.bar, self.gap_m, self.friction)
        for name, mine, value in zip(("bar", "gap_m", "friction"), given,
                                     _describe(self.system), strict=True):
            if not (mine == value or name == "gap_m" and math.isnan(mine) and math.isnan(value)):
                raise ParameterError(f"Case {self.label!r}: {name} = {mine!r}, but its system "
                                     f"has {name} = {value!r}; Case.of(system) labels it")

    @classmethod
    def of(cls, system: System, label: str | None = None,
           initial: Initial | None = None) -> Case:
        """The case of ``system``: its bar, gap and friction read from it, labelled
        as :func:`published_cases` labels (or ``label``)."""
        if not isinstance(system, System):
            raise TypeError(_not_a_system("system", system))
        bar, gap, friction = _describe(system)
        auto = (f"{bar} gap={gap * 1e3:g}mm friction={friction}" if bar == "ball" else bar)
        # a bar of one's own is named by its file (the published one's labels stay short)
        own = system.spec is not None and system.spec.name != PUBLISHED_NAME
        return cls(label or (f"{system.spec.name} {auto}" if own else auto), system, bar,
                   gap, friction, initial)


def _describe(system: System) -> tuple[str, float, str]:
    """(bar kind, gap m or NaN, friction "on"/"off"/"n/a") of ``system``."""
    if system.kind != "ball":
        return system.kind, math.nan, "n/a"
    return "ball", system.damper.gap_m, "off" if system.damper.friction.kind == "none" else "on"


def as_cases(systems, name: str = "systems") -> list[Case]:
    """The cases of what an analysis was given: a :class:`System` or a :class:`Case`,
    a sequence of them, or a mapping of label to either. Labels are unique."""
    if isinstance(systems, System | Case):
        systems = [systems]
    if isinstance(systems, Mapping):
        cases = [Case.of(v, str(k)) if isinstance(v, System) else _relabel(v, str(k))
                 for k, v in systems.items()]
    elif isinstance(systems, Sequence) and not isinstance(systems, str):
        cases = [v if isinstance(v, Case) else Case.of(v) for v in systems]
    else:
        raise TypeError(_not_a_system(name, systems, "a System, a Case, a sequence of them or "
                                                    "a mapping of label to System"))
    if not cases:
        raise ParameterError(f"{name} is empty: give at least one System")
    labels = [c.label for c in cases]
    twice = sorted({x for x in labels if labels.count(x) > 1})
    if twice:
        raise ParameterError(f"{name}: the label {twice[0]!r} is given twice; give a mapping "
                             "of label to System to name them")
    return cases


def _not_a_system(name: str, value, expected: str = "a System (make_system)") -> str:
    """The TypeError's message for ``value`` given where a System is expected: a system
    file's description (what load_system returns) is told how to get its bars."""
    if isinstance(value, SystemSpec):
        return (f"{name} = the system file {value.name!r} (a SystemSpec, what load_system "
                f"returns) must be {expected}: bb.variants(spec) gives its solid, ball and "
                "TMD bars, bb.make_system(kind, spec=spec) one of them")
    shown = repr(value) if len(repr(value)) <= 80 else f"a {type(value).__name__}"
    return f"{name} = {shown} must be {expected}"


def _relabel(case, label: str) -> Case:
    if not isinstance(case, Case):
        raise TypeError(_not_a_system(f"systems[{label!r}]", case, "a System or a Case"))
    return replace(case, label=label)


#: what published_cases passes on to make_system
_OVERRIDABLE = set(inspect.signature(make_system).parameters) - {"bar", "preset", "gap_m",
                                                                 "friction"}
#: those of them that describe the host bar, its absorber and the cut, which the solid and
#: TMD bars take too (the rest are the ball's): a comparison under two planes and an
#: oriented cut holds the three bars to the same planes and cut
HOST_OVERRIDES = ("n_modes", "z_absorber_m", "tmd_mass_kg", "tmd_design", "modal", "spec",
                  "planes", "cut_geometry")


def published_cases(bars: tuple[str, ...] = ("solid", "tmd", "ball"),
                    gaps_m: tuple[float, ...] = (0.5e-3, 0.1e-3),
                    frictions: tuple[bool, ...] = (False, True), preset: str = "physical",
                    **overrides) -> list[Case]:
    """The bars of the published sweeps under ``preset``: those of ``bars`` among solid,
    TMD, and the ball damper for every gap of ``gaps_m`` (m) x friction of ``frictions``
    (off/on).  ``overrides`` go to :func:`make_system` (which refuses unknown ones): all
    of them to the ball cases, those of :data:`HOST_OVERRIDES` to the solid and TMD bars
    too; each bar takes the keys of ``cut_geometry`` that it uses (the hole's angle the
    ball and TMD bars, the principal plane and the stiffness ratio the solid and TMD
    bars)."""
    unknown = sorted(set(overrides) - _OVERRIDABLE)
    if unknown:
        raise TypeError(f"published_cases() got unexpected keyword arguments {unknown}; "
                        f"make_system takes {sorted(_OVERRIDABLE)}")
    cases = []
    for bar in bars:
        kw = _bar_overrides(bar, overrides)
        if bar == "ball":
            for gap in gaps_m:
                for fr in frictions:
                    s = make_system("ball", preset, gap_m=gap, friction=fr, **kw)
                    label = f"ball gap={gap * 1e3:g}mm friction={'on' if fr else 'off'}"
                    cases.append(Case.of(s, label))
        else:
            cases.append(Case.of(make_system(bar, preset, **kw), bar))
    return cases


def _bar_overrides(bar: str, overrides: dict) -> dict:
    """The overrides ``bar`` takes: all of them for the ball, :data:`HOST_OVERRIDES` for
    the others; the oriented cut's keys that ``bar`` uses (a comparison's one cut,
    :func:`~boringbar.model.oriented.for_bar`)."""
    kw = dict(overrides) if bar == "ball" else {
        k: v for k, v in overrides.items() if k in HOST_OVERRIDES}
    if isinstance(kw.get("cut_geometry"), CutGeometry):
        base = (kw.get("spec") or published_system_spec()).orientation
        kw["cut_geometry"] = for_bar(kw["cut_geometry"], bar, base)
    return kw


def parse_range(text: str, name: str = "ratios") -> np.ndarray:
    """'0.95:1.05:0.01' (inclusive) or '0.95,1.0,1.05' -> array."""
    try:
        if ":" in text:
            start, stop, step = (float(v) for v in text.split(":"))
            if not (math.isfinite(start) and math.isfinite(stop) and step > 0
                    and stop >= start):
                raise ValueError
            n = math.floor((stop - start) / step + 1e-9) + 1
            if n > MAX_GRID_VALUES:
                raise ParameterError(f"{name} = {text!r} has {n:.3g} values; the allowed "
                                     f"maximum is {MAX_GRID_VALUES}")
            return np.round(start + step * np.arange(n), 12)
        values = np.array([float(v) for v in text.split(",")])
    except (ValueError, OverflowError) as exc:
        if isinstance(exc, ParameterError):
            raise
        raise ParameterError(f"{name} = {text!r} must be START:STOP:STEP with STEP > 0 and "
                             "STOP >= START, or a comma-separated list of numbers") from None
    if len(values) > MAX_GRID_VALUES or not np.all(np.isfinite(values)):
        raise ParameterError(f"{name} = {text!r} must be at most {MAX_GRID_VALUES} finite "
                             "numbers")
    return values


__all__ = ["MAX_GRID_VALUES", "Case", "as_cases", "parse_range", "published_cases"]
