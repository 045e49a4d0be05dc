"""One vocabulary of names and units (boringbar.vocabulary): the unit-walk.

Every public name that holds a number says its unit or is declared dimensionless:
the arguments of every function and class in ``boringbar.__all__`` (their public
methods too), the fields of every option and description dataclass and their numeric
properties, the keys of a
run's summary, configuration and descriptions, and the variables, coordinates and
summary keys of every analysis on a tiny case.
"""

from __future__ import annotations

import dataclasses
import inspect
import re

import numpy as np
import xarray as xr

import boringbar as bb
from boringbar.analysis import (
    basins,
    bifurcation,
    chatter_map,
    continuation,
    design,
    lobes,
    sensitivity,
    sweep,
)
from boringbar.analysis.design_options import UNCERTAIN, VARIABLES
from boringbar.analysis.verdict import VerdictOptions
from boringbar.model.system_file import BallSpec, CavitySpec, TmdSpec
from boringbar.vocabulary import FILE_UNITS, unit_of

#: An annotation that says "a number" (or numbers): such a name must carry a unit.
NUMERIC = re.compile(r"\b(float|int|complex|ndarray|ArrayLike)\b")


def _quantity(annotation, default=None) -> bool:
    """A parameter or field annotated as a number (a factory ``Callable[[float], X]`` is
    not one), or not annotated and defaulting to a number."""
    if annotation is inspect.Parameter.empty:
        return isinstance(default, int | float) and not isinstance(default, bool)
    text = annotation if isinstance(annotation, str) else getattr(annotation, "__name__",
                                                                  str(annotation))
    return bool(NUMERIC.search(re.sub(r"Callable\[\[.*?\].*?\]", "", text)))


def _signature_names(where: str, func) -> list[tuple[str, str]]:
    try:
        params = inspect.signature(func).parameters.values()
    except (TypeError, ValueError):
        return []
    return [(f"{where}({p.name})", p.name) for p in params
            if p.name not in ("self", "cls") and p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)
            and _quantity(p.annotation, p.default)]


#: Public objects reached through another's fields, not exported on their own: the
#: parts of a system file's description (``load_system(...).cavity``, ...).
PARTS = {"CavitySpec": CavitySpec, "BallSpec": BallSpec, "TmdSpec": TmdSpec}


def _api_names() -> list[tuple[str, str]]:
    """(where, name) of every numeric name of the public API."""
    found = []
    for public, obj in [(p, getattr(bb, p)) for p in bb.__all__] + list(PARTS.items()):
        if inspect.isclass(obj):
            if dataclasses.is_dataclass(obj):
                found += [(f"{public}.{f.name}", f.name) for f in dataclasses.fields(obj)
                          if _quantity(f.type)]
            if issubclass(obj, BaseException):
                continue
            found += _signature_names(public, obj)
            for name, member in vars(obj).items():
                if name.startswith("_"):
                    continue
                if isinstance(member, property) and _quantity(
                        inspect.signature(member.fget).return_annotation):
                    found.append((f"{public}.{name}", name))
                func = getattr(member, "__func__", member)
                if inspect.isfunction(func):
                    found += _signature_names(f"{public}.{name}", func)
        elif callable(obj):
            found += _signature_names(public, obj)
    return found


#: Echoes of input files kept in a configuration: their keys are the file's own
#: (docs/systems.md), not this vocabulary's.
FILE_ECHOES = ("system_file",)


def _keys(where: str, value) -> list[tuple[str, str]]:
    """(where, key) of every key of a JSON-able mapping whose value holds numbers."""
    found = []
    if isinstance(value, dict):
        for key, item in value.items():
            if key in FILE_ECHOES:
                continue
            if isinstance(key, str) and _holds_numbers(item):
                found.append((f"{where}[{key!r}]", key))
            found += _keys(f"{where}[{key!r}]", item)
    elif isinstance(value, (list, tuple)):
        for item in value:
            found += _keys(f"{where}[]", item)
    return found


def _holds_numbers(value) -> bool:
    if isinstance(value, bool) or value is None:
        return False
    if isinstance(value, (int, float, np.number)):
        return True
    if isinstance(value, (list, tuple)):
        return any(_holds_numbers(v) for v in value)
    return False


def _dataset_names(where: str, ds) -> list[tuple[str, str]]:
    return [(f"{where}.{name}", str(name)) for name, var in {**ds.data_vars, **ds.coords}.items()
            if var.dtype.kind in "iufcm"]


def _design_names() -> list[tuple[str, str]]:
    """(where, name) of the design search's variables and uncertain parameters: names
    the Python API takes as strings (``Variable("gap_m", ...)``)."""
    return ([(f"VARIABLES[{n!r}]", n) for n, (_, unit, _, _) in VARIABLES.items() if unit]
            + [(f"UNCERTAIN[{n!r}]", n) for n in UNCERTAIN])


def _missing(found: list[tuple[str, str]]) -> list[str]:
    return sorted({where for where, name in found if unit_of(name) is None})


def _not_si(found: list[tuple[str, str]]) -> list[str]:
    """Where a name carries a unit of the input files and the command line (mm, MPa,
    g): the Python API is SI."""
    return sorted({where for where, name in found if unit_of(name) in FILE_UNITS})


def test_every_public_argument_and_field_says_its_unit():
    found = _api_names() + _design_names()
    assert len(found) > 150  # the walk reaches the API
    assert ("DesignOptions.depth_m", "depth_m") in found
    missing = _missing(found)
    assert not missing, f"numbers without a unit in their name: {missing}"


def test_the_python_api_is_si():
    """mm, MPa and g are for the files a user writes and the command line; every name
    of the Python API, the design search's variables included, is SI."""
    not_si = _not_si(_api_names() + _design_names())
    assert not not_si, f"names in a file's unit, not SI: {not_si}"


def test_a_run_says_the_unit_of_every_number_it_reports():
    system = bb.make_system("ball", "physical")
    run = bb.simulate(system, bb.Harmonic(20.0, 1.0), duration_s=0.02, record_every=10)
    cut = bb.simulate(bb.make_system("solid"), bb.Regenerative(depth_m=0.05e-3, rpm=1200),
                      duration_s=0.05, record_every=0)
    tmd = bb.make_system("tmd")
    found = (_keys("summary", run.summary()) + _keys("config", run.config())
             + _keys("summary", cut.summary()) + _keys("config", cut.config())
             + _keys("tmd", tmd.to_dict()) + _dataset_names("run", run.to_xarray()))
    missing = _missing(found)
    assert not missing, f"numbers without a unit in their name: {missing}"


def _tiny_analyses():
    """(name, Dataset, summary) of each analysis on a tiny case."""
    quick = bb.Integration(duration_s=0.02)
    ball = bb.make_system("ball")
    solid = bb.make_system("solid")
    cases = bb.published_cases(bars=("solid", "ball"), gaps_m=(0.5e-3,))
    yield "sweep", sweep, bb.sweep(cases, bb.SweepOptions([0.99, 1.01]), integration=quick)
    yield "lobes", lobes, bb.lobes(solid, bb.LobesOptions([1000.0, 1200.0], depth_step_m=0.05e-3,
                                                           max_depth_m=0.2e-3),
                                   integration=bb.Integration(duration_s=0.05))
    yield "lobes with draws", lobes, bb.lobes(solid, bb.LobesOptions(
        [20000.0], uncertainty=bb.Uncertainty(draws=2), analytic=False))
    yield "chatter_map", chatter_map, bb.chatter_map(solid, bb.ChatterMapOptions(
        [1200.0], [0.02e-3, 0.1e-3], verdict=VerdictOptions(knocks_m=(20e-6,))))
    yield "bifurcation", bifurcation, bb.bifurcation(ball, bb.BifurcationOptions(
        "force", [5.0, 10.0]), integration=quick)
    yield "basins", basins, bb.basins(ball, bb.BasinOptions((-1e-3, 1e-3, 2), (-1.0, 1.0, 2),
                                                            force_n=10.0, ratio=1.0),
                                      integration=quick)
    yield "sensitivity", sensitivity, bb.sensitivity(bb.SensitivityOptions("ball"),
                                                     integration=quick)
    yield "continuation", continuation, bb.continuation(
        solid, bb.Harmonic(10.0, 0.9),
        options=bb.ContinuationOptions(parameter="ratio", stop=0.95, max_points=4, seeds=0,
                                       switch=False))
    yield "design", design, bb.design(bb.DesignOptions(
        "ball", (bb.Variable("gap_m", 0.1e-3, 0.5e-3), bb.Variable("ball_diameter_m", 8e-3, 10e-3),
                 bb.Variable("ball_material", choices=("carbide", "steel"))),
        ratios=(1.0,), duration_s=0.02, trials=2, samples=2,
        uncertain=(bb.Uncertain("ball_position_m", "uniform", -0.05e-3, 0.05e-3),)))


def test_every_analysis_says_the_unit_of_its_variables_and_summary():
    found = []
    for name, module, ds in _tiny_analyses():
        found += _dataset_names(name, ds) + _keys(f"{name} summary", module.summary(ds))
    assert ("design.gap_m", "gap_m") in found and ("design.ball_diameter_m",
                                                   "ball_diameter_m") in found
    missing = _missing(found)
    assert not missing, f"numbers without a unit in their name: {missing}"
    not_si = _not_si(found)
    assert not not_si, f"names in a file's unit, not SI: {not_si}"


def test_the_walk_fails_on_a_quantity_without_a_unit():
    """The test can fail: an old name (``gap``, ``duration``, ``limit_depth``) is caught,
    a declared dimensionless one and a unit-suffixed one pass."""
    assert _missing([("make_system(gap)", "gap"), ("simulate(duration)", "duration"),
                     ("lobes.limit_depth", "limit_depth")]) == [
        "lobes.limit_depth", "make_system(gap)", "simulate(duration)"]
    assert _missing([("a", "gap_m"), ("b", "ratio"), ("c", "n_modes"), ("d", "rpm"),
                     ("e", "stiffness_n_m"), ("f", "values")]) == []
    # mm (and MPa, g) name a file's key or a flag, never a name of the Python API
    assert _not_si([("DesignOptions.depth_mm", "depth_mm"), ("Variable", "gap_m"),
                    ("LobesOptions.kr_mpa", "kr_mpa"), ("design.gap_mm", "gap_mm")]) == [
        "DesignOptions.depth_mm", "LobesOptions.kr_mpa", "design.gap_mm"]

    @dataclasses.dataclass(frozen=True)
    class OldOptions:
        depth: float = 1e-4
        label: str = ""

    assert [n for _, n in _signature_names("OldOptions", OldOptions)] == ["depth"]
    assert _missing(_keys("old", {"force": 10.0, "label": "x", "rms_tip_m": 1e-5})) == [
        "old['force']"]
    old = xr.Dataset({"rms_tip_m": ("force", [1e-5]), "case": ("force", ["a"])},
                     coords={"force": [10.0]})
    assert _missing(_dataset_names("old", old)) == ["old.force"]
