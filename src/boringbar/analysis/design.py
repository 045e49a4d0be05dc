"""Design search under uncertainty: the damper that works best for a bar, robust to
what cannot be measured well (docs/design.md).

A design study (:class:`~boringbar.analysis.design_options.DesignOptions`) names
variables within the bar's geometry, one objective or several
(:mod:`boringbar.analysis.design_objectives`: harmonic band RMS, cut amplitude,
minimum chatter-free depth, FRF peak, most negative real part), uncertain
parameters whose Monte Carlo samples every candidate shares (common random
numbers), and a statistic of those samples with its error.

Optuna searches: TPE, CMA-ES, or NSGA-II for several objectives (a Pareto
front), the seed fixed. Its SQLite storage beside the result makes the search
resumable: each trial's sampler is seeded by the number of trials finished
before it, so a search killed and run again asks for the same candidates as an
uninterrupted one. A trial still marked running after a kill is failed and
asked again. The runs of one candidate fan out on the usual executors.
"""

from __future__ import annotations

import hashlib
import json
import math
import sqlite3
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import optuna
import xarray as xr

from boringbar._validate import ParameterError
from boringbar.analysis.design_objectives import objective_samples, rms_runs, statistic
from boringbar.analysis.design_options import (
    DesignOptions,
    objective_reading,
    sampled_system,
    shown,
    uncertain_samples,
)
from boringbar.execute import Execution, run_points
from boringbar.model.dampers import TunedMassDamper
from boringbar.model.system import System, make_system, published_system_spec
from boringbar.model.system_file import SystemSpec, cavity_moved, parse_system
from boringbar.reference.stability import system_receptance
from boringbar.simulate import Initial
from boringbar.version import __version__


@dataclass
class Candidate:
    """One evaluated design: ``values`` (variable -> value), per objective its
    ``samples`` (objective, sample), ``statistic`` and ``error``; ``wall_time_s``."""

    values: dict
    samples: np.ndarray
    statistic: np.ndarray
    error: np.ndarray
    wall_time_s: float = 0.0
    system: dict = field(default_factory=dict)


# --- building a candidate's system ---------------------------------------------------
def candidate_system(spec: SystemSpec, options: DesignOptions, values: dict) -> System:
    """The system of the design ``values`` on the bar of ``spec``."""
    data = spec.to_dict()  # a system file's description: lengths in mm
    if "ball_diameter_m" in values:
        data["ball"]["diameter_mm"] = float(values["ball_diameter_m"]) * 1e3
        data["ball"].pop("mass_g", None)
    if "cavity_position_m" in values:
        data = cavity_moved(data, float(values["cavity_position_m"]) * 1e3)
    if "ball_diameter_m" in values or "cavity_position_m" in values:
        spec = parse_system(data, f"{spec.source} (design)")
    kw = {}
    if "gap_m" in values:
        kw["gap_m"] = float(values["gap_m"])
    if "ball_material" in values:
        kw["ball"] = values["ball_material"]
    if "restitution" in values:
        kw["restitution"] = float(values["restitution"])
    system = make_system(options.bar, options.preset, spec=spec, **kw)
    if options.bar == "tmd" and any(k.startswith("tmd_") for k in values):
        system = replace(system, damper=_tmd(system, values))
    return system


def _tmd(system: System, values: dict) -> TunedMassDamper:
    """The absorber of the TMD variables: mass m, frequency ratio f = omega_a/omega_n,
    damping ratio zeta_a = c / (2 m omega_a) (the absorber's own)."""
    d = system.damper
    m = float(values.get("tmd_mass_kg", d.mass_kg))
    wn = system.bar.natural_frequency_rad_s
    f = float(values.get("tmd_frequency_ratio", math.sqrt(d.stiffness_n_m / d.mass_kg) / wn))
    wa = f * wn
    zeta = float(values.get("tmd_damping_ratio", d.damping_n_s_m / (2 * d.mass_kg * math.sqrt(
        d.stiffness_n_m / d.mass_kg))))
    return TunedMassDamper(m, m * wa**2, 2 * zeta * m * wa, d.position_m, "design")


# --- one candidate -------------------------------------------------------------------
def evaluate(spec: SystemSpec, options: DesignOptions, values: dict, samples: np.ndarray,
             execution: Execution | None = None) -> Candidate:
    """Each objective of the design ``values`` over the uncertain ``samples``."""
    t0 = time.perf_counter()
    system = candidate_system(spec, options, values)
    names = tuple(p.name for p in options.uncertain)
    sampled = [sampled_system(system, names, row) for row in samples]
    per, stats, errors = [], [], []
    for objective in options.objectives:
        x, chatter = objective_samples(options, objective, sampled, execution)
        stat, err = statistic(x, options, chatter)
        per.append(x)
        stats.append(stat)
        errors.append(err)
    return Candidate(dict(values), np.array(per), np.array(stats), np.array(errors),
                     time.perf_counter() - t0, system.to_dict())


def _sampler(options: DesignOptions, k: int):
    """The sampler of trial ``k``: seeded by the number of trials finished before it,
    so a resumed search asks what an uninterrupted one would."""
    seed = options.seed * 1_000_003 + k
    startup = min(10, options.trials)
    if options.sampler == "cmaes":
        return optuna.samplers.CmaEsSampler(seed=seed, n_startup_trials=startup)
    if options.sampler == "nsga2":
        return optuna.samplers.NSGAIISampler(seed=seed, population_size=max(4, startup))
    return optuna.samplers.TPESampler(seed=seed, n_startup_trials=startup)


def _suggest(trial, variables) -> dict:
    out = {}
    for v in variables:
        if v.choices:
            out[v.name] = trial.suggest_categorical(v.name, list(v.choices))
        else:
            out[v.name] = trial.suggest_float(v.name, v.low, v.high)
    return out


def design(options: DesignOptions, *, spec: SystemSpec | None = None,
           storage: str | Path | None = None, execution: Execution | None = None,
           progress=None, stop_after: int | None = None) -> xr.Dataset:
    """Search ``options.variables`` for the best statistic of the objective.

    ``spec``: the bar (default the published one); ``storage``: an SQLite file
    that keeps the trials (a rerun resumes it); ``execution``: where each
    candidate's runs go; ``progress(done, total)``; ``stop_after``: end after this
    many new trials (tests of resume). Returns the trial table as a Dataset with
    the best design and the published design under the same objective."""
    spec = spec or published_system_spec()
    t0 = time.perf_counter()
    samples = uncertain_samples(options)
    rdb = None if storage is None else _sqlite(Path(storage))
    try:
        study = _study(options, rdb, storage, _fingerprint(options, spec))
        done = _search(study, spec, options, samples, execution, progress, stop_after)
    finally:
        if rdb is not None:
            rdb.engine.dispose()  # closes the file: SQLite folds its write-ahead log back
    published = _published_candidate(spec, options, samples, execution)
    return assemble(options, done, published, time.perf_counter() - t0)


def _search(study, spec, options, samples, execution, progress, stop_after) -> list:
    """Ask and tell until ``options.trials`` are complete (or ``stop_after`` new
    ones); returns the complete trials."""
    done = _complete(study)
    new = 0
    while len(done) < options.trials and (stop_after is None or new < stop_after):
        study.sampler = _sampler(options, len(done))
        trial = study.ask()
        cand = evaluate(spec, options, _suggest(trial, options.variables), samples, execution)
        trial.set_user_attr("samples", cand.samples.tolist())
        trial.set_user_attr("error", cand.error.tolist())
        trial.set_user_attr("wall_time_s", cand.wall_time_s)
        study.tell(trial, cand.statistic.tolist())
        new += 1
        done = _complete(study)
        if progress is not None:
            progress(len(done), options.trials)
    return done


def _sqlite(path: Path) -> optuna.storages.RDBStorage:
    """Optuna's storage in the SQLite file ``path``, written ahead to a log and synced
    at checkpoints rather than at every one of a trial's dozen commits (a crash can
    lose the last trials, never the file's consistency; a rerun resumes from it)."""
    path.parent.mkdir(parents=True, exist_ok=True)

    def connect() -> sqlite3.Connection:
        connection = sqlite3.connect(path, check_same_thread=False)
        connection.execute("PRAGMA journal_mode=WAL")
        connection.execute("PRAGMA synchronous=NORMAL")
        return connection

    return optuna.storages.RDBStorage(f"sqlite:///{path.resolve()}",
                                      engine_kwargs={"creator": connect})


def _fingerprint(options: DesignOptions, spec: SystemSpec) -> str:
    """What a stored search must match to be resumed: the options (but the number of
    trials, which a rerun may raise) and the bar."""
    text = json.dumps([repr(replace(options, trials=1)), spec.to_dict()], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _study(options: DesignOptions, rdb, storage, fingerprint: str) -> optuna.Study:
    """The search's study in ``rdb`` (None: in memory), checked to be this one's
    (``fingerprint``), its trials killed mid-run failed."""
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(storage=rdb, study_name="boringbar-design",
                                directions=options.directions, load_if_exists=True,
                                sampler=_sampler(options, 0))
    stored = study.user_attrs.get("fingerprint")
    if stored is None:
        study.set_user_attr("fingerprint", fingerprint)
    elif stored != fingerprint:
        raise ParameterError(f"storage = {str(storage)!r} holds the trials of another design "
                             "study (other options or another bar); give another output "
                             "folder, or remove it to start again")
    for t in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.RUNNING,)):
        study.tell(t.number, state=optuna.trial.TrialState.FAIL)  # killed mid-trial
    return study


def _complete(study) -> list:
    return study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))


def _published_candidate(spec, options, samples, execution) -> Candidate:
    """The file's own design (the published one for the published bar)."""
    system = make_system(options.bar, options.preset, spec=spec)
    values = {}
    for v in options.variables:
        if v.name == "gap_m":
            values[v.name] = system.damper.gap_m
        elif v.name == "ball_material":
            values[v.name] = system.damper.material
    return evaluate(spec, options, values, samples, execution)


def assemble(options: DesignOptions, trials: list, published: Candidate,
             wall_time_s: float) -> xr.Dataset:
    """The trial table (trial x variable values; per objective the samples, statistic,
    error; wall time), the best trial (one objective) or the Pareto set (several),
    and the file's own design under the same objectives, as a Dataset."""
    names = [v.name for v in options.variables]
    coords = {"trial": np.arange(len(trials)), "objective": list(options.objectives),
              "sample": np.arange(options.samples)}
    data = {name: ("trial", [t.params[name] for t in trials]) for name in names}
    data["statistic"] = (("trial", "objective"), np.reshape([t.values for t in trials],
                                                            (len(trials), -1)))
    data["error"] = (("trial", "objective"), np.reshape([t.user_attrs["error"] for t in trials],
                                                        (len(trials), -1)))
    data["wall_time_s"] = ("trial", [t.user_attrs["wall_time_s"] for t in trials])
    data["objective_samples"] = (("trial", "objective", "sample"),
                                 np.reshape([t.user_attrs["samples"] for t in trials],
                                            (len(trials), len(options.objectives), -1)))
    ds = xr.Dataset(data, coords=coords)
    ds["published_statistic"] = ("objective", published.statistic)
    ds["published_error"] = ("objective", published.error)
    ds["pareto"] = ("trial", _pareto(ds["statistic"].values, options.directions))
    sign = np.array([1 if d == "minimize" else -1 for d in options.directions])
    best = int(np.argmin(ds["statistic"].values[:, 0] * sign[0])) if trials else -1
    ds.attrs = {
        "boringbar_version": __version__, "objectives": list(options.objectives),
        "directions": list(options.directions), "band": options.band,
        "statistic": options.statistic, "sampler": options.sampler, "seed": options.seed,
        "samples": options.samples, "bar": options.bar, "preset": options.preset,
        "published_system": json.dumps(published.system), "best_trial": best,
        "wall_time_s": wall_time_s, "published_values": json.dumps(published.values),
        "options": repr(options),
    }
    return ds


def _pareto(stat: np.ndarray, directions: list[str]) -> np.ndarray:
    """Whether each trial is on the Pareto front (no other trial at least as good in
    every objective and better in one)."""
    y = stat * np.array([1.0 if d == "minimize" else -1.0 for d in directions])
    front = np.ones(len(y), dtype=bool)
    for i in range(len(y)):
        dominated = np.all(y <= y[i], axis=1) & np.any(y < y[i], axis=1)
        front[i] = not dominated.any()
    return front


def summary(ds: xr.Dataset) -> dict:
    """What ``boringbar design --json`` prints: ``best`` (variable -> value; with several
    objectives, the best in the first), ``objective`` and ``published_objective`` (the
    first objective's statistic), ``trials``, ``wall_time_s``; ``pareto`` with
    several objectives."""
    b = int(ds.attrs["best_trial"])
    names = [k for k in ds.data_vars if ds[k].dims == ("trial",) and k not in
             ("wall_time_s", "pareto")]

    def values(i):
        return {k: (ds[k].values[i].item() if hasattr(ds[k].values[i], "item")
                    else ds[k].values[i]) for k in names}

    objectives = list(ds.attrs["objectives"])
    obj = float(ds["statistic"].values[b, 0])
    pub = float(ds["published_statistic"].values[0])
    if pub == 0:
        better = None  # no relative change from zero (a probability of chatter of 0)
    else:
        better = 100 * ((1 - obj / pub) if ds.attrs["directions"][0] == "minimize"
                        else (obj / pub - 1))
    out = {"best": values(b), "objective": obj, "objective_error": float(ds["error"].values[b, 0]),
           "published_objective": pub, "improvement_percent": better,
           "trials": int(ds.sizes["trial"]), "wall_time_s": float(ds.attrs["wall_time_s"]),
           "objective_name": objectives[0], "statistic_name": ds.attrs["statistic"]}
    if len(objectives) > 1:
        out["objectives"] = objectives
        out["published_objectives"] = ds["published_statistic"].values.tolist()
        front = [{"values": values(int(i)), "objectives": ds["statistic"].values[int(i)].tolist()}
                 for i in np.flatnonzero(ds["pareto"].values)]
        out["pareto"] = [p for k, p in enumerate(front) if p not in front[:k]]  # distinct
    return out


def comparison(spec: SystemSpec, options: DesignOptions, best: dict, n: int = 21,
               execution: Execution | None = None) -> dict:
    """The best design beside the file's own and the bare bar, at the nominal values:
    tip RMS (m) over ``n`` ratios across the band at the first force (a ball
    damper), or |G| (m/N) over 0.8-1.2 x f1 (a TMD). Returns ``x`` (Omega/omega_n),
    ``quantity`` ("rms_tip_m" or "receptance_m_n"), ``force_n`` (None for |G|), ``bar``
    (the damper's kind) and ``curves``, one a bar."""
    bars = {"best design": candidate_system(spec, options, best),
            "file's design": make_system(options.bar, options.preset, spec=spec),
            "bare bar": make_system("solid", options.preset, spec=spec)}
    if options.bar == "ball":
        lo, hi = min(options.ratios), max(options.ratios)
        x = np.linspace(lo - 0.02, hi + 0.02, n) if lo == hi else np.linspace(lo, hi, n)
        force = options.forces_n[0]
        tasks = [(s, tuple(x), (force,), Initial(), options.duration_s, options.integrator)
                 for s in bars.values()]
        y = np.array(run_points(rms_runs, tasks, execution=execution))
        return {"x": x, "quantity": "rms_tip_m", "force_n": force, "bar": options.bar,
                "curves": dict(zip(bars, y, strict=True))}
    wn = bars["bare bar"].bar.natural_frequency_rad_s
    w = np.linspace(0.8 * wn, 1.2 * wn, 801)
    curves = {k: np.abs(system_receptance(s, w))
              for k, s in bars.items()}
    return {"x": w / wn, "quantity": "receptance_m_n", "force_n": None, "bar": options.bar,
            "curves": curves}


def summary_line(s: dict) -> str:
    """'best design X improves the objective by Y % over the file's own design', or, when
    no trial beat it, 'no design better than the file's own found in N trials'."""
    best = ", ".join(shown(k, v) for k, v in s["best"].items())
    gain = s["improvement_percent"]
    unit, k = objective_reading(s["objective_name"], s["statistic_name"])
    unit = f" {unit}" if unit else ""
    numbers = (f"({s['statistic_name']} of {s['objective_name']}: {s['objective'] * k:.4g} "
               f"+- {s['objective_error'] * k:.2g}{unit} against "
               f"{s['published_objective'] * k:.4g}{unit}; {s['trials']} trials)")
    if gain is not None and gain < 0:  # the search did not reach the file's own design
        return (f"no design better than the file's own found in {s['trials']} trials: the "
                f"best tried, {best}, is {-gain:.1f} % worse on the objective {numbers}")
    verb = ("compares with the file's own design as" if gain is None
            else f"improves the objective by {gain:.1f} % over the file's own design")
    return f"best design {best} {verb} {numbers}"
