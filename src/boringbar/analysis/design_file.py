"""Design files: a design study (docs/design.md) in TOML, checked key by key.

    [design]     bar, system (a system file, relative to this file), preset, objective,
                 band, ratios, forces_n, rpm, depth_mm, rpms, max_depth_mm,
                 depth_tolerance, criterion, duration_s, integrator, samples, statistic,
                 quantile, trials, sampler, seed
    [variables]  name = [low, high], or ball_material = ["carbide", "steel", ...]
    [uncertain]  name = { uniform = [low, high] } or { normal = [mean, sd] }

A file's lengths are in mm, as in every file a user writes (system and study files)
and on the command line: ``gap_mm``, ``depth_mm``; the Python API's are in m
(``gap_m``, ``depth_m``).  This module converts them, once, and checks a file's
lengths in mm, so that every error is one line naming the file, the key, the value
and what is allowed, in the file's own unit.
"""

from __future__ import annotations

import json
from dataclasses import fields
from pathlib import Path

from boringbar._validate import ParameterError, read_toml
from boringbar.analysis.design_options import (
    DISTRIBUTIONS,
    LENGTHS,
    UNCERTAIN,
    VARIABLES,
    DesignOptions,
    Uncertain,
    Variable,
    check_bounds,
    check_distribution,
    check_length,
)
from boringbar.model.system import published_system_spec
from boringbar.model.system_file import SystemSpec, load_system

SECTIONS = ("design", "variables", "uncertain")
#: A file's length per metre: its lengths are in mm.
MM_PER_M = 1e3


class DesignFileError(ParameterError):
    """A design file that cannot be run; one line naming file, key, value, allowed."""


def file_key(name: str) -> str:
    """The file's key of the API's ``name``: a length in mm ("gap_m" -> "gap_mm")."""
    return name.removesuffix("_m") + "_mm" if name.endswith("_m") else name


def api_name(key: str) -> str:
    """The API's name of the file's ``key`` ("gap_mm" -> "gap_m")."""
    return key.removesuffix("_mm") + "_m" if key.endswith("_mm") else key


def to_si(key: str, value: float) -> float:
    """The file's ``value`` of ``key`` in SI (a length in mm to m)."""
    return float(value) * 1e-3 if key.endswith("_mm") else value


def to_file(name: str, value):
    """The API's ``value`` of ``name`` in the file's unit (a length in m to mm)."""
    return float(value) * MM_PER_M if name.endswith("_m") else value


_OPTION_KEYS = tuple(file_key(f.name) for f in fields(DesignOptions)
                     if f.name not in ("variables", "uncertain")) + ("system",)
_VARIABLE_KEYS = tuple(file_key(n) for n in VARIABLES)
_UNCERTAIN_KEYS = tuple(file_key(n) for n in UNCERTAIN)


def load_design(path) -> tuple[DesignOptions, SystemSpec]:
    """Read and check the design file ``path``: (options, the bar's system file)."""
    return design_from_dict(read_toml(path, DesignFileError, "design file"), str(path))


def design_from_dict(d: dict, source: str = "<dict>") -> tuple[DesignOptions, SystemSpec]:
    """Check the design description ``d`` (a parsed TOML file): (options, the bar's
    system file, ``[design] system``, default the published bar)."""
    options = options_from_dict(d, source)
    return options, _system(d.get("design", {}).get("system"), source, _failer(source))


def options_from_dict(d: dict, source: str = "<dict>") -> DesignOptions:
    """The options of the design description ``d`` (its lengths in mm), checked; its
    ``[design] system`` is not read (:func:`design_from_dict` reads it)."""
    fail = _failer(source)
    for s in d:
        if s not in SECTIONS:
            fail(s, d[s], "unknown section; allowed: " + ", ".join(f"[{x}]" for x in SECTIONS))
    head = {}
    for k, v in d.get("design", {}).items():
        if k not in _OPTION_KEYS:
            fail(f"design.{k}", v, "unknown key; allowed: " + ", ".join(_OPTION_KEYS))
        if k in ("ratios", "forces_n", "rpms"):
            if not isinstance(v, list) or not v:
                fail(f"design.{k}", v, "a non-empty list of numbers")
            v = tuple(v)
        elif k == "objective" and isinstance(v, list):
            v = tuple(v)
        elif api_name(k) in LENGTHS:  # checked in the file's mm
            try:
                v = to_si(k, check_length(f"key 'design.{k}'", api_name(k), v, MM_PER_M,
                                          "mm"))
            except ParameterError as exc:
                raise DesignFileError(f"{source}: {exc}") from None
        head[api_name(k)] = v
    head.pop("system", None)
    variables = tuple(_variable(k, v, fail) for k, v in d.get("variables", {}).items())
    uncertain = tuple(_uncertain(k, v, fail) for k, v in d.get("uncertain", {}).items())
    try:
        return DesignOptions(variables=variables, uncertain=uncertain, **head)
    except (ParameterError, TypeError) as exc:
        raise DesignFileError(f"{source}: [design] {exc}") from None


def _failer(source: str):
    def fail(key, value, allowed):
        shown = repr(value) if isinstance(value, str) else json.dumps(value, default=str)
        raise DesignFileError(f"{source}: key '{key}' = {shown}: {allowed}")
    return fail


def _system(path, source: str, fail) -> SystemSpec:
    if path is None:
        return published_system_spec()
    if not isinstance(path, str):
        fail("design.system", path, "a path to a system file")
    p = Path(path)
    if not p.is_absolute() and source not in ("<dict>", ""):
        p = Path(source).parent / p
    return load_system(p)


def _variable(key: str, v, fail) -> Variable:
    if key not in _VARIABLE_KEYS:
        fail(f"variables.{key}", v, "unknown variable; allowed: " + ", ".join(_VARIABLE_KEYS))
    name = api_name(key)
    if name == "ball_material" and not (isinstance(v, list) and v):
        fail(f"variables.{key}", v, "a non-empty list of material names")
    if name != "ball_material" and not (isinstance(v, list) and len(v) == 2):
        fail(f"variables.{key}", v, "[low, high]")
    try:
        if name == "ball_material":
            return Variable(name, choices=tuple(v))
        if key != name:  # a length: checked in the file's mm
            check_bounds(key, name, v[0], v[1], MM_PER_M, "mm")
        return Variable(name, to_si(key, v[0]), to_si(key, v[1]))
    except ParameterError as exc:
        fail(f"variables.{key}", v, str(exc))


def _uncertain(key: str, v, fail) -> Uncertain:
    if key not in _UNCERTAIN_KEYS:
        fail(f"uncertain.{key}", v, "unknown parameter; allowed: " + ", ".join(_UNCERTAIN_KEYS))
    if not (isinstance(v, dict) and len(v) == 1 and next(iter(v)) in DISTRIBUTIONS):
        fail(f"uncertain.{key}", v, "{ uniform = [low, high] } or { normal = [mean, sd] }")
    (kind, ab), = v.items()
    if not (isinstance(ab, list) and len(ab) == 2):
        fail(f"uncertain.{key}", v, f"{kind} takes two numbers")
    try:
        check_distribution(key, kind, ab[0], ab[1])  # in the file's unit
        return Uncertain(api_name(key), kind, to_si(key, ab[0]), to_si(key, ab[1]))
    except ParameterError as exc:
        fail(f"uncertain.{key}", v, str(exc))
