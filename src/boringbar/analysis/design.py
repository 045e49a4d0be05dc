"""Design search under uncertainty: the damper that works best for a bar, robust to
what cannot be measured well (docs/design.md).

A design study (:class:`~boringbar.analysis.design_options.DesignOptions`) names
variables within the bar's geometry, one objective or several
(:mod:`boringbar.analysis.design_objectives`: harmonic band RMS, cut amplitude,
minimum chatter-free depth, FRF peak, most negative real part), uncertain
parameters whose Monte Carlo samples every candidate shares (common random
numbers), and a statistic of those samples with its error.

Optuna searches: TPE, CMA-ES, or NSGA-II for several objectives (a Pareto
front), the seed fixed. Its journal beside the result makes the search
resumable: each trial's sampler is seeded by the number of trials finished
before it, so a search killed and run again asks for the same candidates as an
uninterrupted one. A trial still marked running after a kill is failed and
asked again. The runs of one candidate fan out on the usual executors.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import optuna
import pandas as pd
import xarray as xr
from optuna.storages.journal import JournalFileBackend, JournalFileOpenLock

from boringbar._validate import ParameterError
from boringbar.analysis.cases import Case
from boringbar.analysis.design_interval import CONFIDENCE, improvement, wilson
from boringbar.analysis.design_objectives import (
    FRF_LINES,
    FRF_SPAN,
    depth_lobes,
    objective_samples,
    rms_runs,
    statistic,
)
from boringbar.analysis.design_options import (
    OBJECTIVE_SI,
    OBJECTIVES,
    DesignOptions,
    nominal_sample,
    nominal_words,
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
    ``samples`` (objective, sample), ``statistic`` and ``error``; ``wall_time_s``;
    ``chatter``, whether each sample's cut chattered (cut_amplitude; else None)."""

    values: dict
    samples: np.ndarray
    statistic: np.ndarray
    error: np.ndarray
    wall_time_s: float = 0.0
    system: dict = field(default_factory=dict)
    chatter: np.ndarray | None = None


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


def check_space(spec: SystemSpec, options: DesignOptions, samples: np.ndarray) -> None:
    """Builds the candidate at every corner of the variables' box (each choice of a
    categorical one) under every uncertain sample, so that a design space reaching a
    system that cannot be built (a gap beyond the cavity's room, a restitution a Hertz
    contact refuses, a preset the ball's motion refuses) is refused before any run or
    file, not halfway through the search."""
    axes = [v.choices or (v.low, v.high) for v in options.variables]
    names = tuple(p.name for p in options.uncertain)
    for corner in itertools.product(*axes):
        values = dict(zip((v.name for v in options.variables), corner, strict=True))
        row = None
        try:
            system = candidate_system(spec, options, values)
            for row in samples:
                sampled_system(system, names, row)
        except ParameterError as exc:
            where = ", ".join(shown(k, v) for k, v in values.items())
            if row is not None and names:
                where += " with " + ", ".join(f"{n} = {float(x):.4g}"
                                              for n, x in zip(names, row, strict=True))
            raise ParameterError(f"the design space reaches a system that cannot be built, "
                                 f"at {where}: {exc}") from None


def _tmd(system: System, values: dict) -> TunedMassDamper:
    """The absorber of the TMD variables: mass m, frequency ratio f = omega_a/omega_n,
    damping ratio zeta_a = c / (2 m omega_a) (the absorber's own); the system's own
    (:func:`tmd_tuning`) where a variable is not given."""
    own = {**tmd_tuning(system), **values}
    m = float(own["tmd_mass_kg"])
    wa = float(own["tmd_frequency_ratio"]) * system.bar.natural_frequency_rad_s
    zeta = float(own["tmd_damping_ratio"])
    return TunedMassDamper(m, m * wa**2, 2 * zeta * m * wa, system.damper.position_m, "design")


def tmd_tuning(system: System) -> dict:
    """The TMD bar's absorber as the design variables read it: its mass, omega_a /
    omega_n and c / (2 m omega_a)."""
    d = system.damper
    wa = math.sqrt(d.stiffness_n_m / d.mass_kg)
    return {"tmd_mass_kg": d.mass_kg,
            "tmd_frequency_ratio": wa / system.bar.natural_frequency_rad_s,
            "tmd_damping_ratio": d.damping_n_s_m / (2 * d.mass_kg * wa)}


# --- one candidate -------------------------------------------------------------------
def evaluate(spec: SystemSpec, options: DesignOptions, values: dict, samples: np.ndarray,
             execution: Execution | None = None) -> Candidate:
    """Each objective of the design ``values`` over the uncertain ``samples``."""
    t0 = time.perf_counter()
    system = candidate_system(spec, options, values)
    names = tuple(p.name for p in options.uncertain)
    sampled = [sampled_system(system, names, row) for row in samples]
    per, stats, errors, flags = [], [], [], None
    for objective in options.objectives:
        x, chatter = objective_samples(options, objective, sampled, execution)
        stat, err = statistic(x, options, chatter)
        per.append(x)
        stats.append(stat)
        errors.append(err)
        flags = chatter if chatter is not None else flags
    return Candidate(dict(values), np.array(per), np.array(stats), np.array(errors),
                     time.perf_counter() - t0, system.to_dict(), flags)


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
           storage: str | Path | optuna.storages.BaseStorage | None = None,
           execution: Execution | None = None,
           progress=None, stop_after: int | None = None) -> xr.Dataset:
    """Search ``options.variables`` for the best statistic of the objective.

    ``spec``: the bar (default the published one); ``storage``: a file that keeps the
    trials (Optuna's journal, :func:`design_storage`; a rerun resumes it), or an Optuna
    storage of your own (``optuna.storages.RDBStorage("sqlite:///trials.db")``);
    ``execution``: where each candidate's runs go; ``progress(done, total)``;
    ``stop_after``: end after this many new trials (tests of resume). Returns the trial
    table as a Dataset with the best design and the published design under the same
    objective."""
    spec = spec or published_system_spec()
    t0 = time.perf_counter()
    samples = uncertain_samples(options)
    check_space(spec, options, samples)
    kept = (storage if storage is None or isinstance(storage, optuna.storages.BaseStorage)
            else design_storage(storage))
    study = _study(options, kept, storage, _fingerprint(options, spec))
    done = _search(study, spec, options, samples, execution, progress, stop_after)
    # trials a killed run left failed: trials.csv lists them, so no number is missing
    failed = study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.FAIL,))
    published = _published_candidate(spec, options, samples, execution)
    return assemble(options, done, published, time.perf_counter() - t0, samples=samples,
                    failed=failed)


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
        if cand.chatter is not None:
            trial.set_user_attr("chatter", cand.chatter.tolist())
        study.tell(trial, cand.statistic.tolist())
        new += 1
        done = _complete(study)
        if progress is not None:
            progress(len(done), options.trials)
    return done


def design_storage(path: str | Path, *, writer: bool = True) -> optuna.storages.JournalStorage:
    """The search's trials in the file ``path``: Optuna's journal, each ask and tell a
    line appended and synced, so that a rerun resumes from every trial that finished.
    For the ``writer`` (the search), a line that a killed run left half written, never
    acknowledged, is cut off first: the next line appended to it would make the file
    unreadable.  A reader beside a running search (the design page) leaves it be."""
    path = Path(path)
    if writer:
        path.parent.mkdir(parents=True, exist_ok=True)
        _cut_torn_tail(path)
    name = str(path)
    return optuna.storages.JournalStorage(
        JournalFileBackend(name, lock_obj=JournalFileOpenLock(name)))


def _cut_torn_tail(path: Path) -> None:
    if not path.exists():
        return
    with open(path, "rb+") as f:
        data = f.read()
        if data and not data.endswith(b"\n"):
            f.truncate(data.rfind(b"\n") + 1)
            os.fsync(f.fileno())


def _fingerprint(options: DesignOptions, spec: SystemSpec) -> str:
    """What a stored search must match to be resumed: the options (but the number of
    trials, which a rerun may raise) and the bar."""
    text = json.dumps([repr(replace(options, trials=1)), spec.to_dict()], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _study(options: DesignOptions, kept, storage, fingerprint: str) -> optuna.Study:
    """The search's study in the Optuna storage ``kept`` (None: in memory), checked to
    be this one's (``fingerprint``), its trials killed mid-run failed."""
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(storage=kept, study_name="boringbar-design",
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
    d = system.damper
    own = (tmd_tuning(system) if options.bar == "tmd" else
           {"gap_m": d.gap_m, "ball_material": d.material})
    values = {v.name: own[v.name] for v in options.variables if v.name in own}
    # run as the file gives it (an absorber rebuilt from its ratios would differ in its
    # last bits); its tuning is read out for the tables
    run = {k: v for k, v in values.items() if not k.startswith("tmd_")}
    return replace(evaluate(spec, options, run, samples, execution), values=values)


def assemble(options: DesignOptions, trials: list, published: Candidate,
             wall_time_s: float, *, samples: np.ndarray | None = None,
             failed: list = ()) -> xr.Dataset:
    """The trial table (trial, numbered as Optuna numbers it, x variable values; per
    objective the samples, statistic, error; wall time; whether each sample's cut
    chattered, for cut_amplitude), the best trial (one objective) or the Pareto set
    (several), the file's own design under the same objectives with its samples, and
    the uncertain parameters' ``samples`` as drawn, as a Dataset. ``failed``: trials a
    killed run left failed (listed in the attributes)."""
    names = [v.name for v in options.variables]
    coords = {"trial": np.array([t.number for t in trials], dtype=int),
              "objective": list(options.objectives), "sample": np.arange(options.samples)}
    data = {name: ("trial", [t.params[name] for t in trials]) for name in names}
    data["statistic"] = (("trial", "objective"), np.reshape([t.values for t in trials],
                                                            (len(trials), -1)))
    data["error"] = (("trial", "objective"), np.reshape([t.user_attrs["error"] for t in trials],
                                                        (len(trials), -1)))
    data["wall_time_s"] = ("trial", [t.user_attrs["wall_time_s"] for t in trials])
    data["objective_samples"] = (("trial", "objective", "sample"),
                                 np.reshape([t.user_attrs["samples"] for t in trials],
                                            (len(trials), len(options.objectives), -1)))
    data["published_samples"] = (("objective", "sample"), published.samples)
    if published.chatter is not None:
        unknown = [math.nan] * options.samples  # a trial an older storage kept without flags
        data["chatter"] = (("trial", "sample"), np.reshape(
            [t.user_attrs.get("chatter", unknown) for t in trials],
            (len(trials), options.samples)).astype(float), {"codes": "1 chatter, 0 none"})
        data["published_chatter"] = ("sample", published.chatter.astype(float))
    if samples is not None and options.uncertain:
        coords["uncertain"] = [p.name for p in options.uncertain]
        data["uncertain_value"] = (("sample", "uncertain"), samples, {
            "long_name": "the uncertain parameters as drawn (SI, the unit in the name)"})
    ds = xr.Dataset(data, coords=coords)
    ds["published_statistic"] = ("objective", published.statistic)
    ds["published_error"] = ("objective", published.error)
    ds["pareto"] = ("trial", _pareto(ds["statistic"].values, options.directions))
    sign = np.array([1 if d == "minimize" else -1 for d in options.directions])
    best = int(np.argmin(ds["statistic"].values[:, 0] * sign[0])) if trials else -1
    ds.attrs = {
        "boringbar_version": __version__, "objectives": list(options.objectives),
        "directions": list(options.directions), "band": options.band,
        "statistic": options.statistic, "quantile": options.quantile,
        "sampler": options.sampler, "seed": options.seed,
        "samples": options.samples, "bar": options.bar, "preset": options.preset,
        "published_system": json.dumps(published.system), "best_trial": best,
        "wall_time_s": wall_time_s, "published_values": json.dumps(published.values),
        "failed_trials": json.dumps([{"number": t.number, "values": t.params} for t in failed]),
        "confidence": CONFIDENCE, "options": repr(options),
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


def variable_names(ds: xr.Dataset) -> list[str]:
    """The design variables of the trial table ``ds``."""
    return [k for k in ds.data_vars if ds[k].dims == ("trial",) and k not in
            ("wall_time_s", "pareto")]


def improvement_of(ds: xr.Dataset) -> dict:
    """The best trial's improvement on the file's own design in the first objective,
    on the same draws, with its interval
    (:func:`~boringbar.analysis.design_interval.improvement`)."""
    b = int(ds.attrs["best_trial"])
    statistic = str(ds.attrs["statistic"])
    chatter = {}
    if statistic == "chatter_probability":
        chatter = {"best_chatter": ds["chatter"].values[b],
                   "published_chatter": ds["published_chatter"].values}
    return improvement(ds["objective_samples"].values[b, 0], ds["published_samples"].values[0],
                       statistic, maximize=np.atleast_1d(ds.attrs["directions"])[0] == "maximize",
                       quantile=float(ds.attrs.get("quantile", 0.9)),
                       seed=int(ds.attrs["seed"]) + 2, **chatter)


def summary(ds: xr.Dataset) -> dict:
    """What ``boringbar design --json`` prints: ``best`` (variable -> value; with several
    objectives, the best in the first), ``objective`` and ``published_objective`` (the
    first objective's statistic), the ``improvement`` on the file's own design (SI;
    positive: better), its ``improvement_percent``, its ``improvement_interval`` and
    ``improvement_interval_percent`` at ``confidence`` (None without one: then
    ``interval_note`` says why), ``interval_method`` and ``significant`` (the interval
    excludes 0; None without an interval), ``trials``, ``samples``, ``wall_time_s``;
    ``pareto`` with several objectives."""
    b = int(ds.attrs["best_trial"])
    names = variable_names(ds)

    def values(i):
        return {k: (ds[k].values[i].item() if hasattr(ds[k].values[i], "item")
                    else ds[k].values[i]) for k in names}

    objectives = [str(o) for o in np.atleast_1d(ds.attrs["objectives"])]
    obj = float(ds["statistic"].values[b, 0])
    pub = float(ds["published_statistic"].values[0])
    imp = improvement_of(ds)
    interval = imp["interval"]

    def percent(v):  # no relative change from zero (a probability of chatter of 0)
        return None if pub == 0 else 100 * v / abs(pub) + 0.0  # + 0.0: no "-0.0"

    out = {"best": values(b), "objective": obj, "objective_error": float(ds["error"].values[b, 0]),
           "published_objective": pub, "improvement": imp["improvement"] + 0.0,
           "improvement_percent": percent(imp["improvement"]),
           "improvement_interval": None if interval is None else list(interval),
           "improvement_interval_percent": (None if interval is None or pub == 0
                                            else [percent(v) for v in interval]),
           "confidence": imp["level"], "interval_method": imp["method"],
           "significant": imp["significant"], "interval_note": imp["note"],
           "trials": int(ds.sizes["trial"]), "samples": int(ds.sizes["sample"]),
           "best_trial_number": int(ds["trial"].values[b]),
           "wall_time_s": float(ds.attrs["wall_time_s"]),
           "objective_name": objectives[0], "statistic_name": str(ds.attrs["statistic"])}
    if len(objectives) > 1:
        out["objectives"] = objectives
        out["published_objectives"] = ds["published_statistic"].values.tolist()
        front = [{"values": values(int(i)), "objectives": ds["statistic"].values[int(i)].tolist()}
                 for i in np.flatnonzero(ds["pareto"].values)]
        out["pareto"] = [p for k, p in enumerate(front) if p not in front[:k]]  # distinct
    return out


# --- the tables of trials.csv and samples.csv ------------------------------------------
def statistic_column(ds: xr.Dataset, objective: str, error: bool = False) -> str:
    """The trial table's column of an objective's statistic (or of its ``error``), its SI
    unit last: "mean_rms_band_m", "quantile0.9_min_depth_error_m", "chatter_probability"."""
    stat = str(ds.attrs["statistic"])
    if stat == "chatter_probability":
        return "chatter_probability_error" if error else stat
    if stat == "quantile":
        stat = f"quantile{float(ds.attrs.get('quantile', 0.9)):g}"
    return f"{stat}_{objective}{'_error' if error else ''}_{OBJECTIVE_SI[objective]}"


def trial_table(ds: xr.Dataset) -> pd.DataFrame:
    """One row per trial (trials.csv): its number, the variables (SI, the unit in the
    name), each objective's statistic and error, wall time, whether it is the best (and,
    with several objectives, on the Pareto front) and its state: COMPLETE, or FAIL for a
    trial a killed run left unfinished (its variables only)."""
    objectives = [str(o) for o in np.atleast_1d(ds.attrs["objectives"])]
    rows = {"trial": ds["trial"].values}
    rows.update({name: ds[name].values for name in variable_names(ds)})
    for j, o in enumerate(objectives):
        rows[statistic_column(ds, o)] = ds["statistic"].values[:, j]
        rows[statistic_column(ds, o, error=True)] = ds["error"].values[:, j]
    rows["wall_time_s"] = ds["wall_time_s"].values
    rows["best"] = np.arange(ds.sizes["trial"]) == int(ds.attrs["best_trial"])
    if len(objectives) > 1:
        rows["pareto"] = ds["pareto"].values
    rows["state"] = "COMPLETE"
    table = pd.DataFrame(rows)
    failed = json.loads(ds.attrs.get("failed_trials", "[]"))
    if failed:
        lost = pd.DataFrame([{"trial": f["number"], **f["values"], "best": False,
                              "state": "FAIL"} for f in failed])
        table = pd.concat([table, lost], ignore_index=True).sort_values("trial")
    return table.reset_index(drop=True)


def sample_table(ds: xr.Dataset) -> pd.DataFrame:
    """One row per trial and sample (samples.csv), then the file's own design's samples
    (``design`` "file", no trial): the sample's index, the uncertain parameters as drawn
    (SI, the unit in the name), each objective's value (``rms_band_m``, ...) and, for
    cut_amplitude, whether the cut chattered."""
    objectives = [str(o) for o in np.atleast_1d(ds.attrs["objectives"])]
    n = ds.sizes["sample"]
    drawn = ({str(u): ds["uncertain_value"].values[:, k]
              for k, u in enumerate(ds["uncertain"].values)} if "uncertain_value" in ds else {})

    def block(design_, trial, values, chatter) -> pd.DataFrame:
        rows = {"design": design_, "trial": trial, "sample": np.arange(n), **drawn}
        rows.update({f"{o}_{OBJECTIVE_SI[o]}": values[j] for j, o in enumerate(objectives)})
        if chatter is not None:
            rows["chatter"] = chatter
        return pd.DataFrame(rows)

    has = "chatter" in ds
    blocks = [block("search", t, ds["objective_samples"].values[i],
                    ds["chatter"].values[i] if has else None)
              for i, t in enumerate(ds["trial"].values)]
    blocks.append(block("file", pd.NA, ds["published_samples"].values,
                        ds["published_chatter"].values if has else None))
    table = pd.concat(blocks, ignore_index=True)
    table["trial"] = table["trial"].astype("Int64")
    if has:
        table["chatter"] = table["chatter"].astype("boolean")
    return table


# --- the best design beside the file's own (best.png) ----------------------------------
def nominal(system: System, options: DesignOptions) -> tuple[System, Initial]:
    """``system`` and its initial state at the nominal sample (each uncertain parameter at
    its centre: :func:`~boringbar.analysis.design_options.nominal_sample`); a bar without
    a damper takes the bar's damping ratio alone."""
    names = tuple(p.name for p in options.uncertain)
    row = nominal_sample(options)
    if system.damper is None:
        keep = [i for i, name in enumerate(names) if name == "damping_ratio"]
        names, row = tuple(names[i] for i in keep), row[keep]
    return sampled_system(system, names, row)


def comparison(spec: SystemSpec, options: DesignOptions, ds: xr.Dataset, n: int = 21,
               execution: Execution | None = None) -> dict:
    """The best trial of ``ds`` beside the file's own design, as the first objective
    reads it (``kind``; :func:`boringbar.plot.design.plot_best` draws each):

    - ``"lobes"`` (min_depth): each design's chatter-free depth at the design's speeds,
      by the lobes' search the objective runs (:meth:`DesignOptions.lobes_options`),
      at the nominal sample;
    - ``"cut"`` (cut_amplitude): each design's cut amplitude and chatter per sample,
      and its probability of chatter with its Wilson interval;
    - ``"response"`` (rms_band, frf_peak, min_real): :func:`response_comparison`."""
    best = summary(ds)["best"]
    objective = options.objectives[0]
    if objective == "min_depth":
        return depth_comparison(spec, options, best, execution)
    if objective == "cut_amplitude":
        return cut_comparison(ds, options)
    return response_comparison(spec, options, best, n, execution)


def response_comparison(spec: SystemSpec, options: DesignOptions, best: dict, n: int = 21,
                        execution: Execution | None = None) -> dict:
    """The best design beside the file's own and the bare bar, at the nominal sample
    (:func:`nominal`):
    tip RMS (m) over ``n`` ratios across the band at the first force (a ball damper),
    else the tip FRF over 0.8-1.2 x f1, widened to hold each curve's extreme: |G| (m/N),
    or Re G (m/N) for min_real. Returns ``kind`` "response", ``x`` (Omega/omega_n),
    ``quantity`` ("rms_tip_m", "receptance_m_n" or "real_m_n"), ``force_n`` (None for
    the FRF), ``bar`` (the damper's kind), ``curves``, one a bar, and ``nominal`` (the
    nominal sample in words: :func:`nominal`)."""
    bars = {"best design": nominal(candidate_system(spec, options, best), options),
            "file's design": nominal(make_system(options.bar, options.preset, spec=spec),
                                     options),
            "bare bar": nominal(make_system("solid", options.preset, spec=spec), options)}
    initial = {k: ini for k, (_, ini) in bars.items()}
    bars = {k: s for k, (s, _) in bars.items()}
    if options.bar == "ball":
        lo, hi = min(options.ratios), max(options.ratios)
        x = np.linspace(lo - 0.02, hi + 0.02, n) if lo == hi else np.linspace(lo, hi, n)
        force = options.forces_n[0]
        tasks = [(s, tuple(x), (force,), initial[k], options.duration_s, options.integrator)
                 for k, s in bars.items()]
        y = np.array(run_points(rms_runs, tasks, execution=execution))
        return {"kind": "response", "x": x, "quantity": "rms_tip_m", "force_n": force,
                "bar": options.bar, "curves": dict(zip(bars, y, strict=True)),
                "nominal": nominal_words(options)}
    real = options.objectives[0] == "min_real"
    wn = bars["bare bar"].bar.natural_frequency_rad_s
    wide = np.linspace(FRF_SPAN[0] * wn, FRF_SPAN[1] * wn, FRF_LINES)
    extremes = [wide[np.argmin(g.real) if real else np.argmax(np.abs(g))] / wn
                for g in (system_receptance(s, wide) for s in bars.values())]
    lo, hi = min(0.8, 0.9 * min(extremes)), max(1.2, 1.1 * max(extremes))
    w = np.linspace(max(lo, FRF_SPAN[0]) * wn, min(hi, FRF_SPAN[1]) * wn, 801)
    curves = {k: (system_receptance(s, w).real if real else np.abs(system_receptance(s, w)))
              for k, s in bars.items()}
    return {"kind": "response", "x": w / wn, "quantity": "real_m_n" if real else
            "receptance_m_n", "force_n": None, "bar": options.bar, "curves": curves,
            "nominal": nominal_words(options)}


def depth_comparison(spec: SystemSpec, options: DesignOptions, best: dict,
                     execution: Execution | None = None) -> dict:
    """min_depth's own figure: the best design's and the file's chatter-free depth (m) at
    each of ``options.rpms``, by the objective's lobes search, at the nominal sample
    (:func:`nominal`).
    Returns ``kind`` "lobes", ``rpm``, per design ``limit_m`` (NaN: no chatter up to
    ``max_depth_m``), ``first_unstable_m`` and ``min_depth_m`` (the objective at the
    nominal sample), ``max_depth_m``, ``criterion``, ``duration_s``,
    ``depth_tolerance``, ``nominal`` and ``bar``."""
    cases = [Case.of(nominal(candidate_system(spec, options, best), options)[0], "best design"),
             Case.of(nominal(make_system(options.bar, options.preset, spec=spec), options)[0],
                     "file's design")]
    lb = depth_lobes(cases, options, execution)
    labels = [c.label for c in cases]
    return {"kind": "lobes", "rpm": lb["rpm"].values, "bar": options.bar,
            "limit_m": dict(zip(labels, lb["limit_depth_m"].values, strict=True)),
            "first_unstable_m": dict(zip(labels, lb["first_unstable_depth_m"].values,
                                         strict=True)),
            "min_depth_m": {k: min(float(v), options.max_depth_m) for k, v in
                            zip(labels, lb["min_chatter_free_depth_m"].values, strict=True)},
            "max_depth_m": options.max_depth_m, "criterion": options.criterion,
            "duration_s": options.duration_s, "depth_tolerance": options.depth_tolerance,
            "nominal": nominal_words(options)}


def cut_comparison(ds: xr.Dataset, options: DesignOptions) -> dict:
    """cut_amplitude's own figure, from the samples of ``ds``: per design (the best
    trial, the file's) the cut's amplitude (m) and chatter at each sample, the
    statistic, and the probability of chatter with its Wilson interval at
    :data:`~boringbar.analysis.design_interval.CONFIDENCE`; the cut's ``rpm`` and
    ``depth_m`` (``options``). Returns ``kind`` "cut"."""
    b = int(ds.attrs["best_trial"])
    amplitude = {"best design": ds["objective_samples"].values[b, 0],
                 "file's design": ds["published_samples"].values[0]}
    chatter = {"best design": ds["chatter"].values[b],
               "file's design": ds["published_chatter"].values}
    wilson_ = {k: (wilson(int(np.nansum(v)), len(v)) if np.isfinite(v).all() else None)
               for k, v in chatter.items()}
    return {"kind": "cut", "amplitude_m": amplitude, "chatter": chatter, "wilson": wilson_,
            "statistic": str(ds.attrs["statistic"]),
            "value": {"best design": float(ds["statistic"].values[b, 0]),
                      "file's design": float(ds["published_statistic"].values[0])},
            "confidence": CONFIDENCE, "bar": str(ds.attrs["bar"]), "rpm": options.rpm,
            "depth_m": options.depth_m}


# --- the summary line ------------------------------------------------------------------
def summary_line(s: dict) -> str:
    """What the search found, as far as its samples can tell: 'best design X improves the
    objective by Y % over the file's own design', 'no design better than the file's own
    found in N trials', or, when the improvement's interval holds 0, 'best design X: a
    against b, improvement g (95 % CI lo to hi): within noise'; without an interval (one
    sample, or no spread) it says so.  A search of several objectives is judged in its
    first, and the line says what its Pareto front holds in all of them."""
    return _first_objective_line(s) + (_front_words(s) if "pareto" in s else "")


def _front_words(s: dict) -> str:
    """'; judged in its first objective ...: the Pareto front ... holds N designs, M of
    them better than the file's own in at least one objective'."""
    def better(values) -> bool:
        return any(a < b if OBJECTIVES[name][1] == "minimize" else a > b for name, a, b
                   in zip(s["objectives"], values, s["published_objectives"], strict=True))

    m = sum(better(p["objectives"]) for p in s["pareto"])
    return (f"; judged in its first objective, {s['objective_name']}: the Pareto front of "
            f"{' and '.join(s['objectives'])} holds {len(s['pareto'])} design"
            f"{'s' if len(s['pareto']) != 1 else ''}, {m} of them better than the file's "
            "own in at least one (design.png)")


def _first_objective_line(s: dict) -> str:
    best = ", ".join(shown(k, v) for k, v in s["best"].items())
    unit, k = objective_reading(s["objective_name"], s["statistic_name"])
    u = f" {unit}" if unit else ""
    gain, pct, interval = s["improvement"], s["improvement_percent"], s["improvement_interval"]
    n = s["samples"]
    noise = interval is not None and not s["significant"]
    numbers = (f"{s['objective'] * k:.4g} against {s['published_objective'] * k:.4g}{u}, "
               f"improvement {gain * k:+.3g}{u}"
               + ("" if pct is None or not noise else f" ({pct:+.1f} %)"))
    if interval is None:
        sure = f"; {s['interval_note']}"
    else:
        level = round(100 * s["confidence"])
        lo, hi = interval_ends(interval[0] * k, interval[1] * k)
        sure = (f", {level} % CI {lo} to {hi}{u}"
                + (": within noise" if not s["significant"] else ""))
    tail = (f" ({s['statistic_name']} of {s['objective_name']} over {n} sample"
            f"{'s' if n != 1 else ''}{', ' + s['interval_method'] if interval else ''}; "
            f"{s['trials']} trial{'s' if s['trials'] != 1 else ''})")
    if noise:
        tried = "best design" if gain >= 0 else "best design tried"
        return f"{tried} {best}: {numbers}{sure}{tail}"
    if gain < 0:  # the search did not reach the file's own design
        worse = "" if pct is None else f" {-pct:.1f} %"
        return (f"no design better than the file's own found in {s['trials']} trials: the "
                f"best tried, {best}, is{worse} worse: {numbers}{sure}{tail}")
    verb = ("equals the file's own design" if gain == 0
            else "compares with the file's own design as" if pct is None
            else f"improves the objective by {pct:.1f} % over the file's own design")
    return f"best design {best} {verb}: {numbers}{sure}{tail}"


def interval_ends(lo: float, hi: float) -> tuple[str, str]:
    """An interval's ends, signed, to two significant digits or as many more (up to
    five) as it takes to tell them apart."""
    for digits in range(2, 6):
        a, b = f"{lo:+.{digits}g}", f"{hi:+.{digits}g}"
        if a != b:
            break
    return a, b
