"""Loading a study file: the TOML read, every key checked against the schema
(:mod:`boringbar.studies.schema`) and the analysis's own options and axes
(:mod:`boringbar.studies.registry`), into a :class:`~boringbar.studies.schema.Study`."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

from boringbar._validate import ParameterError, read_toml
from boringbar.model.system_file import SystemSpec, load_system, parse_system
from boringbar.studies.registry import ANALYSES
from boringbar.studies.schema import (
    MAX_POINTS,
    SECTION_OF,
    SECTIONS,
    SETTINGS,
    Setting,
    Study,
    StudyError,
    output_format,
)


def load_study(path) -> Study:
    """Read and validate the TOML study file ``path``."""
    return study_from_dict(read_toml(path, StudyError, "study file"), str(path))


def study_from_dict(d: dict, source: str = "<dict>") -> Study:
    """Validate the study description ``d`` (the parsed TOML) into a :class:`Study`."""
    def fail(key: str, value, allowed: str):
        shown = json.dumps(value, default=str) if not isinstance(value, str) else repr(value)
        raise StudyError(f"{source}: key '{key}' = {shown}: {allowed}")

    if not isinstance(d, dict):
        raise StudyError(f"{source}: a study is a table of sections, not {type(d).__name__}")
    for s in d:
        if s not in SECTIONS:
            fail(s, d[s], "unknown section; allowed: " + ", ".join(f"[{x}]" for x in SECTIONS))
        if not isinstance(d[s], dict):
            fail(s, d[s], f"[{s}] must be a table")
    given: set[str] = set()
    resolved = _settings(d, given, fail)
    study = resolved.pop("study")
    system = _system(d, study["system"], source, fail)
    if system is not None:
        _system_defaults(resolved, system, given)
    analysis = _analysis(study, resolved, source, fail)
    options = _options(d.get("analysis", {}), analysis, fail)
    axes = _axes(d, analysis, given, fail)
    name = study["name"] or (Path(source).stem if source not in ("<dict>", "") else "study")
    result = Study(analysis=analysis.name, name=name, preset=study["preset"],
                   settings=resolved, options=options, axes=axes, source=source,
                   out=study["out"], format=study["format"], given=frozenset(given),
                   system=system)
    try:
        result = _with_default_axes(result, analysis, fail)
        analysis.check(result)
    except StudyError:
        raise
    except ParameterError as exc:
        raise StudyError(f"{source}: {exc}") from None
    return result


def _system(d: dict, path: str | None, source: str, fail) -> SystemSpec | None:
    """The study's system file: ``[study] system`` (a path, relative to the study
    file) or an inline ``[system]`` table; None: the published bar."""
    if "system" in d and path is not None:
        fail("study.system", path, "give the system file or an inline [system] table, not "
                                   "both")
    if "system" in d:
        return parse_system(d["system"], f"{source} [system]")
    if path is None:
        return None
    p = Path(path)
    if not p.is_absolute() and source not in ("<dict>", ""):
        p = Path(source).parent / p
    return load_system(p)


def _system_defaults(resolved: dict, system: SystemSpec, given: set) -> None:
    """The system file's values for the bar and damper keys the study did not set."""
    data = system.data
    defaults = {}
    if system.ball is not None:
        defaults.update(gap_mm=data["ball"]["gap_mm"], ball=system.ball.material,
                        restitution=system.ball.restitution)
    if system.tmd is not None:
        defaults.update(tmd_mass_kg=system.tmd.mass_kg, z_absorber_mm=data["tmd"]["position_mm"])
    for k, v in defaults.items():
        if k not in given:
            resolved[SECTION_OF[k]][k] = v


def _settings(d: dict, given: set, fail) -> dict[str, dict]:
    """Every section's settings, checked, with the defaults of those not given (whose
    names go into ``given``)."""
    resolved: dict[str, dict] = {}
    for s in ("study", "bar", "damper", "forcing", "run"):
        table = d.get(s, {})
        out = {}
        for k, v in table.items():
            if k not in SETTINGS[s]:
                fail(f"{s}.{k}", v, "unknown key; allowed: " + ", ".join(SETTINGS[s]))
        for k, spec in SETTINGS[s].items():
            if k in table:
                v = table[k]
                try:
                    out[k] = spec.check(v)
                except ValueError:
                    fail(f"{s}.{k}", v, spec.allowed())
                given.add(k)
            else:
                out[k] = spec.default
        resolved[s] = out
    return resolved


def _analysis(study: dict, resolved: dict, source: str, fail):
    """The study's analysis (its registry adapter), its integrator and output checked."""
    if study["analysis"] is None:
        fail("study.analysis", None, "required; one of " + ", ".join(map(repr, ANALYSES)))
    if study["analysis"] not in ANALYSES:
        fail("study.analysis", study["analysis"], "one of " + ", ".join(map(repr, ANALYSES)))
    analysis = ANALYSES[study["analysis"]]
    allowed = analysis.integrators()
    if resolved["run"]["integrator"] not in allowed:
        fail("run.integrator", resolved["run"]["integrator"],
             f"one of {', '.join(map(repr, allowed))} for a {analysis.name} study")
    if study["out"] is not None:
        try:
            output_format(Path(study["out"]), study["format"], "key 'study.out'")
        except ParameterError as exc:
            raise StudyError(f"{source}: {exc}") from None
    return analysis


def _options(table: dict, analysis, fail) -> dict:
    """The ``[analysis]`` options, checked, with the defaults of those not given."""
    options = {}
    for k, v in table.items():
        if k not in analysis.options:
            allowed = ", ".join(analysis.options) or "none"
            fail(f"analysis.{k}", v, f"unknown key for a {analysis.name} study; allowed: "
                 f"{allowed}")
    for k, spec in analysis.options.items():
        if table.get(k) is not None:  # None (JSON null): unset, as a configuration keeps it
            try:
                options[k] = spec.check(table[k])
            except ValueError as exc:
                fail(f"analysis.{k}", table[k], str(exc) or spec.allowed())
        else:
            options[k] = spec.default
    return options


def _axes(d: dict, analysis, given: set, fail) -> dict:
    """The ``[grid]`` axes, checked (their keys go into ``given``)."""
    axes = {}
    for k, v in d.get("grid", {}).items():
        if k not in SECTION_OF:
            fail(f"grid.{k}", v, "unknown setting; a grid axis is one of the [bar], [damper], "
                 "[forcing] or [run] keys")
        if k not in analysis.grid_keys:
            fail(f"grid.{k}", v, f"cannot be an axis of a {analysis.name} study; allowed axes: "
                 + ", ".join(analysis.grid_keys))
        if k in d.get(SECTION_OF[k], {}):
            fail(f"grid.{k}", v, f"also set in [{SECTION_OF[k]}]; give it in one place")
        axes[k] = tuple(_axis_values(v, SETTINGS[SECTION_OF[k]][k], f"grid.{k}", fail))
        given.add(k)
    return axes


def _with_default_axes(study: Study, analysis, fail) -> Study:
    """``study`` with the analysis's default axes (of the study's bars: the lobes'
    speeds) for the keys it set neither in a section nor in ``[grid]``; at most
    :data:`MAX_POINTS` points in all."""
    axes = dict(study.axes)
    for k, values in analysis.default_axes(study).items():
        if k not in study.given:
            axes[k] = tuple(values)
    points = math.prod(len(v) for v in axes.values())
    if points > MAX_POINTS:
        fail("grid", {k: f"{len(v)} values" for k, v in axes.items()},
             f"{points} grid points; the allowed maximum is {MAX_POINTS}")
    return replace(study, axes=axes)


def _axis_values(v, spec: Setting, key: str, fail) -> list:
    """A grid axis: a non-empty list of distinct allowed values, or
    {start, stop, step} (numbers; stop included when on the grid)."""
    if isinstance(v, dict):
        if spec.kind not in ("float", "int") or set(v) != {"start", "stop", "step"}:
            fail(key, v, "a list of values, or {start, stop, step} for a number")
        try:
            start, stop, step = (float(v[x]) for x in ("start", "stop", "step"))
        except (TypeError, ValueError):
            fail(key, v, "start, stop and step must be numbers")
        if not (math.isfinite(start) and math.isfinite(stop) and step > 0 and stop >= start):
            fail(key, v, "{start, stop, step} needs step > 0 and stop >= start")
        n = int(math.floor((stop - start) / step + 1e-9)) + 1
        if n > 1_000_000:
            fail(key, v, "at most 1000000 values on one axis")
        v = [round(start + i * step, 12) for i in range(n)]
    if not isinstance(v, list) or not v:
        fail(key, v, "a non-empty list of values, or {start, stop, step}")
    out = []
    for x in v:
        try:
            out.append(spec.check(x))
        except ValueError:
            fail(key, x, f"each value must be {spec.allowed()}")
    if len(set(out)) != len(out):
        fail(key, v, "the values of an axis must be distinct")
    return out
