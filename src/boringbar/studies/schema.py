"""Study files: a whole study (many runs of one analysis) described in TOML.

A study file has the sections ``[study]`` (which analysis, name, preset,
output, and the system file it runs: ``system = "bar.toml"``, or an inline
``[system]`` table in the system file's format; default: the published bar),
``[bar]`` and ``[damper]`` (overrides of the system file's values) (the keys of
:func:`~boringbar.model.system.make_system`, units in the names), ``[forcing]``
(harmonic force and ratio, or a cut: rpm, depth, Kr, feed ...), ``[run]``
(duration, step, integrator, initial conditions), ``[analysis]`` (the
options of the chosen analysis) and ``[grid]``: any gridable setting given
as a list or as ``{start, stop, step}`` becomes an axis, and the study is
the cartesian product of its axes.  Defaults are the published study
(docs/model.md, section 6), but for what belongs to the bar: a lobes study's speeds
and depth grid are the library's, of the study's own bars.  Every key is checked
before any work starts: an unknown key, a wrong type or a value out of range raises
:class:`StudyError` with the file, the key, the value and what is allowed.

The schema (``SETTINGS`` and each analysis's ``OPTIONS``) is the single
source of truth; docs/studies.md describes it for users.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from boringbar._validate import ParameterError
from boringbar.model.cutting import WORKPIECES
from boringbar.model.dampers import MAX_FRICTION_FORCE, MAX_GAP
from boringbar.model.forcing import MAX_DEPTH, MAX_FEED, MAX_FORCE, MAX_KR, MAX_RATIO
from boringbar.model.materials import MATERIALS
from boringbar.simulate import MAX_INITIAL_DISPLACEMENT, MAX_INITIAL_VELOCITY

SECTIONS = ("study", "system", "bar", "damper", "forcing", "run", "analysis", "grid")
FORMATS = ("netcdf", "zarr")
#: The file name ending of each output format.
SUFFIXES = {"netcdf": ".nc", "zarr": ".zarr"}
#: The longest bar a position may name (mm); the bar's own length is checked when
#: the system is built.
MAX_BAR_LENGTH_MM = 10_000.0
#: Most points (runs or columns) of one study, the product of its axes.
MAX_POINTS = 10_000_000


class StudyError(ParameterError):
    """A study file (or dict) that cannot be run; the message is one line:
    ``FILE: key 'a.b' = VALUE: what is allowed``."""


@dataclass(frozen=True)
class Setting:
    """One key of the schema: its type, default and allowed values.

    ``kind``: "float", "int", "bool", "str" or "onoff" (true/false or
    "on"/"off", stored as a bool).  ``lo``/``hi``: closed range for numbers
    (``lo_open``: lo excluded).  ``choices``: allowed strings.  ``default``
    None: unset (the library's own default applies).
    """

    kind: str
    default: object = None
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    choices: tuple = ()
    doc: str = ""

    def allowed(self) -> str:
        if self.choices:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        if self.kind == "bool":
            return "true or false"
        if self.kind == "onoff":
            return "true/false or 'on'/'off'"
        if self.kind == "str":
            return "a string"
        what = "an integer" if self.kind == "int" else "a number"
        if self.lo is not None or self.hi is not None:
            lo = "-inf" if self.lo is None else f"{self.lo:g}"
            hi = "inf" if self.hi is None else f"{self.hi:g}"
            what += f" in {'(' if self.lo_open else '['}{lo}, {hi}{')' if self.hi is None else ']'}"
        return what

    def check(self, value):
        """The value as stored, or raise ValueError (the caller adds file and key)."""
        k = self.kind
        if k == "bool":
            if not isinstance(value, bool):
                raise ValueError
            return value
        if k == "onoff":
            if isinstance(value, bool):
                return value
            if value in ("on", "off"):
                return value == "on"
            raise ValueError
        if k == "str":
            if not isinstance(value, str) or (self.choices and value not in self.choices):
                raise ValueError
            return value
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError
        if k == "int":
            if isinstance(value, float) and not value.is_integer():
                raise ValueError
            value = int(value)
        else:
            value = float(value)
        if not math.isfinite(value):
            raise ValueError
        if self.lo is not None and (value <= self.lo if self.lo_open else value < self.lo):
            raise ValueError
        if self.hi is not None and value > self.hi:
            raise ValueError
        return value


def _f(default=None, lo=None, hi=None, lo_open=False, doc=""):
    return Setting("float", default, lo, hi, lo_open, (), doc)


def _pos(default=None, hi=None, doc=""):
    return Setting("float", default, 0.0, hi, True, (), doc)


_D, _V = MAX_INITIAL_DISPLACEMENT * 1e3, MAX_INITIAL_VELOCITY


#: Every scalar setting, by section.  Flat key names are unique across the
#: sections, so a [grid] axis is named by its key alone.
SETTINGS: dict[str, dict[str, Setting]] = {
    "study": {
        "analysis": Setting("str", None, doc="the analysis (see ANALYSES)"),
        "name": Setting("str", None, doc="a label; default: the file's stem"),
        "preset": Setting("str", "physical", choices=("physical", "paper")),
        "out": Setting("str", None, doc="result path (.nc or .zarr); default NAME.nc"),
        "format": Setting("str", None, choices=FORMATS, doc="default: from the suffix of out"),
        "system": Setting("str", None, doc="a system file (docs/systems.md), relative to the "
                          "study file; or an inline [system] table; default: the published "
                          "bar"),
    },
    "bar": {
        "kind": Setting("str", "ball", choices=("solid", "ball", "tmd")),
        "n_modes": Setting("int", None, 1, 8, doc="default: 2 (physical), 1 (paper)"),
        "tmd_design": Setting("str", None, choices=("given", "published", "den-hartog", "sims")),
        "tmd_mass_kg": _pos(0.39),
        "z_absorber_mm": _pos(96.0, MAX_BAR_LENGTH_MM, doc="within the bar"),
    },
    "damper": {
        "gap_mm": _pos(0.5, MAX_GAP * 1e3),
        "friction": Setting("onoff", True),
        "ball": Setting("str", "carbide", choices=tuple(MATERIALS)),
        "restitution": _f(0.7, 0.0, 1.0),
        "friction_number": _f(None, 0.0, 100.0, doc="published rolling-resistance number"),
        "friction_force_n": _f(None, 0.0, MAX_FRICTION_FORCE,
                               doc="Coulomb force, overrides the number"),
        "friction_reaction": Setting("str", None, choices=("reciprocal", "printed")),
        "locked": Setting("bool", False),
        "static_ratio": Setting("float", 1.0, 1.0, None, doc="F_s / F_c of true stick-slip "
                                "(integrator 'exact' only)"),
    },
    "forcing": {
        "force_n": _f(10.0, 0.0, MAX_FORCE),
        "ratio": _pos(1.0, MAX_RATIO, doc="Omega / omega_n of the host bar"),
        "rpm": _pos(1200.0),
        "depth_mm": _f(0.05, 0.0, MAX_DEPTH * 1e3),
        "kr_mpa": _pos(850.0, MAX_KR * 1e-6, doc="the linear law's Kr"),
        "workpiece": Setting("str", None, choices=tuple(WORKPIECES),
                             doc="Kienzle's law of this material, instead of kr_mpa"),
        "feed_mm": _pos(0.1, MAX_FEED * 1e3),
        "revolutions": Setting("int", 3, 1, 50),
        "interpolation": Setting("str", "cubic", choices=("cubic", "linear")),
        "start": Setting("str", "rest", choices=("rest", "static")),
        "bounded_fraction": _pos(0.1),
    },
    "run": {
        "duration_s": _pos(2.0),
        "dt_s": _f(None, 0.0, 1e-3, lo_open=True,
                   doc="the RK4 step in s (unset: the published 1e-6, or a judged "
                       "cut's own)"),
        "integrator": Setting("str", "auto", doc="auto (exact for harmonic runs, rk4 "
                              "under the paper preset and in cuts), rk4 (published) or exact"),
        "steady_fraction": _f(0.8, 0.0, 1.0, lo_open=True),
        "tip_displacement_mm": _f(0.0, -_D, _D),
        "tip_velocity_m_s": _f(0.0, -_V, _V),
        "ball_position_mm": _f(0.0, -MAX_GAP / 2 * 1e3, MAX_GAP / 2 * 1e3,
                              doc="within [-gap/2, gap/2]"),
        "ball_velocity_m_s": _f(0.0, -_V, _V),
    },
}

#: The section of every flat key.
SECTION_OF = {k: s for s, keys in SETTINGS.items() for k in keys if s != "study"}
#: Keys that describe the System (one case per distinct combination).
SYSTEM_KEYS = tuple(SETTINGS["bar"]) + tuple(SETTINGS["damper"])


@dataclass(frozen=True)
class Study:
    """A resolved study: every setting with its value (defaults filled in).

    ``settings``: section -> key -> value for bar, damper, forcing, run;
    ``options``: the analysis's options; ``axes``: grid key -> tuple of values,
    in the file's order; ``given``: the flat keys the file set (in a section
    or the grid), so an analysis can tell a default from a choice.
    """

    analysis: str
    name: str
    preset: str
    settings: dict
    options: dict
    axes: dict
    source: str = "<dict>"
    out: str | None = None
    format: str | None = None
    given: frozenset = field(default_factory=frozenset)
    #: the system file (a SystemSpec), or None: the published bar
    system: object = None

    def value(self, key: str):
        """The fixed value of a flat setting (its [section] value or default)."""
        return self.settings[SECTION_OF[key]][key]

    def to_dict(self) -> dict:
        """The full resolved configuration (JSON-able); :func:`study_from_dict`
        of it gives the same study.  ``out`` and ``format`` are where the result
        goes, not what it is, and are left out."""
        return {
            "study": {"analysis": self.analysis, "name": self.name, "preset": self.preset},
            **{s: {k: v for k, v in self.settings[s].items()
                   if v is not None and k not in self.axes}
               for s in ("bar", "damper", "forcing", "run")},
            **({} if self.system is None else {"system": self.system.to_dict()}),
            "analysis": _jsonable(self.options),
            "grid": {k: list(v) for k, v in self.axes.items()},
        }

    def config_hash(self) -> str:
        """SHA-256 of the resolved configuration: what a result store is keyed by."""
        text = json.dumps(self.to_dict(), sort_keys=True, allow_nan=False)
        return hashlib.sha256(text.encode()).hexdigest()

    def output_path(self, out=None) -> Path:
        """``out``, or the file's ``[study] out`` (relative to the file), or NAME.nc."""
        if out is not None:
            return Path(out)
        if self.out is not None:
            p = Path(self.out)
            if not p.is_absolute() and self.source not in ("<dict>", ""):
                p = Path(self.source).parent / p
            return p
        return Path(self.name + SUFFIXES[self.format or "netcdf"])


def _jsonable(obj):
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_jsonable(v) for v in obj]
    return obj


def output_format(out: Path, fmt: str | None, name: str = "out") -> str:
    """The format of the result path ``out``: its suffix must be .nc (NetCDF) or .zarr
    (Zarr) and match ``fmt`` if given; else ParameterError naming ``name``."""
    by_suffix = {v: k for k, v in SUFFIXES.items()}
    suffix = Path(out).suffix
    if suffix not in by_suffix:
        raise ParameterError(f"{name} = {str(out)!r} must end in .nc (NetCDF) or .zarr (Zarr)")
    if fmt is not None and by_suffix[suffix] != fmt:
        raise ParameterError(f"{name} = {str(out)!r} is {by_suffix[suffix]} by its suffix but "
                             f"format = {fmt!r} (a {fmt} result ends in {SUFFIXES[fmt]})")
    return by_suffix[suffix]
