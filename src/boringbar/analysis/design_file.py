"""Design files: a design study (docs/design.md) in TOML, checked key by key.

    [design]     bar, system (a system file, relative to this file), preset, objective,
                 band, ratios, forces_n, duration_s, integrator, samples, statistic,
                 quantile, trials, sampler, seed
    [variables]  name = [low, high], or ball_material = ["carbide", "steel", ...]
    [uncertain]  name = { uniform = [low, high] } or { normal = [mean, sd] }

Every error is one line: the file, the key, the value and what is allowed.
"""

from __future__ import annotations

import json
from dataclasses import fields
from pathlib import Path

from boringbar._validate import ParameterError, read_toml
from boringbar.analysis.design_options import (
    DISTRIBUTIONS,
    UNCERTAIN,
    VARIABLES,
    DesignOptions,
    Uncertain,
    Variable,
)
from boringbar.model.system import published_system_spec
from boringbar.model.system_file import SystemSpec, load_system

SECTIONS = ("design", "variables", "uncertain")
_OPTION_KEYS = tuple(f.name for f in fields(DesignOptions)
                     if f.name not in ("variables", "uncertain")) + ("system",)


class DesignFileError(ParameterError):
    """A design file that cannot be run; one line naming file, key, value, allowed."""


def load_design(path) -> tuple[DesignOptions, SystemSpec]:
    """Read and check the design file ``path``: (options, the bar's system file)."""
    return design_from_dict(read_toml(path, DesignFileError, "design file"), str(path))


def design_from_dict(d: dict, source: str = "<dict>") -> tuple[DesignOptions, SystemSpec]:
    """Check the design description ``d`` (a parsed TOML file)."""
    def fail(key, value, allowed):
        shown = repr(value) if isinstance(value, str) else json.dumps(value, default=str)
        raise DesignFileError(f"{source}: key '{key}' = {shown}: {allowed}")

    for s in d:
        if s not in SECTIONS:
            fail(s, d[s], "unknown section; allowed: " + ", ".join(f"[{x}]" for x in SECTIONS))
    head = dict(d.get("design", {}))
    for k in head:
        if k not in _OPTION_KEYS:
            fail(f"design.{k}", head[k], "unknown key; allowed: " + ", ".join(_OPTION_KEYS))
    spec = _system(head.pop("system", None), source, fail)
    for k in ("ratios", "forces_n", "rpms"):
        if k in head:
            if not isinstance(head[k], list) or not head[k]:
                fail(f"design.{k}", head[k], "a non-empty list of numbers")
            head[k] = tuple(head[k])
    if isinstance(head.get("objective"), list):
        head["objective"] = tuple(head["objective"])
    variables = tuple(_variable(k, v, fail) for k, v in d.get("variables", {}).items())
    uncertain = tuple(_uncertain(k, v, fail) for k, v in d.get("uncertain", {}).items())
    try:
        return DesignOptions(variables=variables, uncertain=uncertain, **head), spec
    except (ParameterError, TypeError) as exc:
        raise DesignFileError(f"{source}: [design] {exc}") from None


def _system(path, source: str, fail) -> SystemSpec:
    if path is None:
        return published_system_spec()
    if not isinstance(path, str):
        fail("design.system", path, "a path to a system file")
    p = Path(path)
    if not p.is_absolute() and source not in ("<dict>", ""):
        p = Path(source).parent / p
    return load_system(p)


def _variable(name: str, v, fail) -> Variable:
    if name not in VARIABLES:
        fail(f"variables.{name}", v, "unknown variable; allowed: " + ", ".join(VARIABLES))
    try:
        if name == "ball_material":
            if not isinstance(v, list) or not v:
                fail(f"variables.{name}", v, "a non-empty list of material names")
            return Variable(name, choices=tuple(v))
        if not (isinstance(v, list) and len(v) == 2):
            fail(f"variables.{name}", v, "[low, high]")
        return Variable(name, v[0], v[1])
    except ParameterError as exc:
        fail(f"variables.{name}", v, str(exc))


def _uncertain(name: str, v, fail) -> Uncertain:
    if name not in UNCERTAIN:
        fail(f"uncertain.{name}", v, "unknown parameter; allowed: " + ", ".join(UNCERTAIN))
    if not (isinstance(v, dict) and len(v) == 1 and next(iter(v)) in DISTRIBUTIONS):
        fail(f"uncertain.{name}", v, "{ uniform = [low, high] } or { normal = [mean, sd] }")
    (kind, ab), = v.items()
    if not (isinstance(ab, list) and len(ab) == 2):
        fail(f"uncertain.{name}", v, f"{kind} takes two numbers")
    try:
        return Uncertain(name, kind, ab[0], ab[1])
    except ParameterError as exc:
        fail(f"uncertain.{name}", v, str(exc))
