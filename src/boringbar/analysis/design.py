"""Design search under uncertainty: the damper that works best for a bar, robust to
what cannot be measured well (docs/design.md).

A design study names:

- **variables** (:class:`Variable`): the ball's gap, material, diameter, the
  cavity's position, the restitution; the absorber's mass, frequency ratio and
  damping ratio. Each has a range within the bar's geometry;
- **an objective** (:data:`OBJECTIVES`): the tip RMS over a band of frequency
  ratios and forces under harmonic forcing (its worst or its mean), the peak of
  the tip FRF, or its most negative real part (the chatter limit's
  denominator; linear bars);
- **uncertain parameters** (:class:`Uncertain`): the friction force, the
  restitution, the ball's initial position and velocity, the bar's damping
  ratio, each uniform or normal. Their Monte Carlo samples are drawn once, from
  the seed, and every candidate sees the same samples (common random numbers),
  so candidates are compared on the same draws;
- **a statistic** over the samples: the mean (with its standard error), a
  quantile (with a bootstrap error) or the worst sample.

Optuna searches (TPE or CMA-ES; the seed fixed). Its SQLite storage beside the
result makes the search resumable: each trial's sampler is seeded by the
number of trials finished before it, so a search killed and run again asks
for the same candidates as an uninterrupted one. A trial still marked running
after a kill is failed and asked again. The runs of one candidate (samples x
forces x ratios) fan out on the usual executors.
"""

from __future__ import annotations

import hashlib
import json
import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import optuna
import scipy.special
import xarray as xr

from boringbar import __version__
from boringbar._validate import ParameterError, check_choice, check_int, check_range
from boringbar.execute import Execution, run_points
from boringbar.model.bar import ModalModel
from boringbar.model.dampers import MAX_GAP, Friction, TunedMassDamper
from boringbar.model.forcing import Harmonic
from boringbar.model.materials import MATERIALS
from boringbar.model.system import System, make_system, published_system_spec
from boringbar.model.system_file import SystemSpec, parse_system
from boringbar.reference.linear import tip_frf
from boringbar.simulate import Initial, simulate

OBJECTIVES = ("rms_band", "frf_peak", "min_real")
BAND_REDUCTIONS = ("worst", "mean")
STATISTICS = ("mean", "quantile", "max")
SAMPLERS = ("tpe", "cmaes")
#: variable -> (bars it applies to, unit, lowest allowed, highest allowed)
VARIABLES = {
    "gap_mm": (("ball",), "mm", 0.0, MAX_GAP * 1e3),
    "ball_material": (("ball",), "", None, None),
    "ball_diameter_mm": (("ball",), "mm", 1.0, 100.0),
    "cavity_position_mm": (("ball",), "mm", 0.0, math.inf),
    "restitution": (("ball",), "", 0.0, 1.0),
    "tmd_mass_kg": (("tmd",), "kg", 0.0, 100.0),
    "tmd_frequency_ratio": (("tmd",), "", 0.1, 10.0),
    "tmd_damping_ratio": (("tmd",), "", 0.0, 2.0),
}
UNCERTAIN = ("friction_force_n", "restitution", "ball_position_mm", "ball_velocity_m_s",
             "damping_ratio")
DISTRIBUTIONS = ("uniform", "normal")
#: Frequency lines of the FRF objectives, over FRF_SPAN x the host's f1.
FRF_LINES = 6001
FRF_SPAN = (0.3, 2.0)
BOOTSTRAP = 400


@dataclass(frozen=True)
class Variable:
    """A design variable: ``name`` (one of :data:`VARIABLES`), its range
    ``low``-``high`` (units as in the name), or ``choices`` (ball_material)."""

    name: str
    low: float | None = None
    high: float | None = None
    choices: tuple = ()

    def __post_init__(self):
        check_choice("design variable", self.name, tuple(VARIABLES))
        _, unit, lo, hi = VARIABLES[self.name]
        if self.name == "ball_material":
            if not self.choices:
                raise ParameterError("ball_material needs choices, e.g. ['carbide', 'steel']")
            for c in self.choices:
                check_choice("ball_material choice", c, tuple(MATERIALS))
            return
        check_range(f"{self.name} low", self.low, lo, hi, unit=unit)
        check_range(f"{self.name} high", self.high, self.low, hi, lo_open=True, unit=unit)


@dataclass(frozen=True)
class Uncertain:
    """An uncertain parameter ``name`` (one of :data:`UNCERTAIN`) and its
    ``distribution``: ``uniform`` on [a, b], or ``normal`` with mean a and standard
    deviation b (0: fixed at a)."""

    name: str
    distribution: str
    a: float
    b: float

    def __post_init__(self):
        check_choice("uncertain parameter", self.name, UNCERTAIN)
        check_choice(f"{self.name} distribution", self.distribution, DISTRIBUTIONS)
        check_range(f"{self.name} a", self.a, -math.inf, math.inf, lo_open=True, hi_open=True)
        if self.distribution == "uniform":
            check_range(f"{self.name} b", self.b, self.a, math.inf, hi_open=True)
        else:
            check_range(f"{self.name} standard deviation", self.b, 0.0, math.inf,
                        hi_open=True)

    def draw(self, u: np.ndarray) -> np.ndarray:
        """Values for the standard samples ``u`` (uniform on (0, 1))."""
        if self.distribution == "uniform":
            return self.a + (self.b - self.a) * u
        return self.a + self.b * math.sqrt(2.0) * scipy.special.erfinv(2.0 * u - 1.0)


@dataclass(frozen=True)
class DesignOptions:
    """A design study: ``bar`` ("ball" or "tmd"), ``variables``, ``objective``
    (:data:`OBJECTIVES`; ``band``: worst or mean over ``ratios`` x ``forces_n`` for
    rms_band), ``uncertain`` parameters and ``samples`` Monte Carlo samples,
    ``statistic`` (:data:`STATISTICS`; ``quantile`` q), ``trials`` and
    ``sampler`` (:data:`SAMPLERS`) with ``seed``; runs of ``duration_s`` with
    ``integrator``; ``preset``."""

    bar: str
    variables: tuple[Variable, ...]
    objective: str = "rms_band"
    band: str = "worst"
    ratios: tuple[float, ...] = (0.95, 1.0, 1.05)
    forces_n: tuple[float, ...] = (10.0,)
    uncertain: tuple[Uncertain, ...] = ()
    samples: int = 1
    statistic: str = "mean"
    quantile: float = 0.9
    trials: int = 50
    sampler: str = "tpe"
    seed: int = 1
    duration_s: float = 2.0
    integrator: str = "exact"
    preset: str = "physical"

    def __post_init__(self):
        check_choice("bar", self.bar, ("ball", "tmd"))
        check_choice("objective", self.objective, OBJECTIVES)
        check_choice("band", self.band, BAND_REDUCTIONS)
        check_choice("statistic", self.statistic, STATISTICS)
        check_choice("sampler", self.sampler, SAMPLERS)
        check_int("samples", self.samples, 1, 100_000)
        check_int("trials", self.trials, 1, 100_000)
        check_int("seed", self.seed, 0, 2**31 - 1)
        check_range("quantile", self.quantile, 0.0, 1.0, lo_open=True, hi_open=True)
        if not self.variables:
            raise ParameterError("a design study needs at least one variable")
        for v in self.variables:
            if self.bar not in VARIABLES[v.name][0]:
                raise ParameterError(f"variable {v.name!r} applies to a "
                                     f"{VARIABLES[v.name][0][0]} bar, not bar = {self.bar!r}")
        if self.objective != "rms_band" and self.bar == "ball":
            raise ParameterError(f"objective = {self.objective!r} is a linear bar's (the "
                                 "tip FRF); a ball damper takes objective 'rms_band'")


@dataclass
class Candidate:
    """One evaluated design: ``values`` (variable -> value), the objective's
    ``samples``, its ``statistic`` and ``error``, ``wall_time_s``."""

    values: dict
    samples: np.ndarray
    statistic: float
    error: float
    wall_time_s: float = 0.0
    system: dict = field(default_factory=dict)


# --- building a candidate's system ---------------------------------------------------
def candidate_system(spec: SystemSpec, options: DesignOptions, values: dict) -> System:
    """The system of the design ``values`` on the bar of ``spec``."""
    data = spec.to_dict()
    if "ball_diameter_mm" in values:
        data["ball"]["diameter_mm"] = float(values["ball_diameter_mm"])
        data["ball"].pop("mass_g", None)
    if "cavity_position_mm" in values:
        data = _cavity_moved(data, float(values["cavity_position_mm"]))
    if "ball_diameter_mm" in values or "cavity_position_mm" in values:
        spec = parse_system(data, f"{spec.source} (design)")
    kw = {}
    if "gap_mm" in values:
        kw["gap"] = float(values["gap_mm"]) * 1e-3
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
    m = float(values.get("tmd_mass_kg", d.mass))
    wn = system.bar.natural_frequency
    f = float(values.get("tmd_frequency_ratio", math.sqrt(d.stiffness / d.mass) / wn))
    wa = f * wn
    zeta = float(values.get("tmd_damping_ratio", d.damping / (2 * d.mass * math.sqrt(
        d.stiffness / d.mass))))
    return TunedMassDamper(m, m * wa**2, 2 * zeta * m * wa, d.position, "design")


def _cavity_moved(data: dict, position_mm: float) -> dict:
    """The system description with the cavity at ``position_mm``; neighbouring sections
    of one diameter and bore are merged first, so the cavity may move along them."""
    merged = []
    for s in data["bar"]["sections"]:
        if merged and (merged[-1]["diameter_mm"], merged[-1]["bore_mm"]) == (
                s["diameter_mm"], s["bore_mm"]):
            merged[-1] = dict(merged[-1], end_mm=s["end_mm"])
        else:
            merged.append(dict(s))
    data["bar"]["sections"] = merged
    data["cavity"]["position_mm"] = position_mm
    return data


# --- one candidate -------------------------------------------------------------------
def uncertain_samples(options: DesignOptions) -> np.ndarray:
    """(samples, uncertain) values: the common random numbers of every candidate."""
    rng = np.random.default_rng(options.seed)
    u = rng.random((options.samples, len(options.uncertain)))
    u = np.clip(u, 1e-12, 1 - 1e-12)
    return np.column_stack([p.draw(u[:, j]) for j, p in enumerate(options.uncertain)]) \
        if options.uncertain else np.zeros((options.samples, 0))


def sampled_system(system: System, names: tuple, row) -> tuple[System, Initial]:
    """``system`` and the initial state with one sample of the uncertain parameters."""
    d, bar, ini = system.damper, system.bar, {}
    for name, v in zip(names, row, strict=True):
        if name == "friction_force_n":
            d = replace(d, friction=Friction("force", max(float(v), 0.0), d.friction.reaction,
                                             d.friction.static_ratio))
        elif name == "restitution":
            d = replace(d, restitution=float(np.clip(v, 0.0, 1.0)))
        elif name == "damping_ratio":
            bar = ModalModel(mass=bar.mass, stiffness=bar.stiffness,
                             damping_ratio=np.full(bar.n_modes, float(np.clip(v, 0.0, 0.99))),
                             psi_tip=bar.psi_tip, psi_damper=bar.psi_damper,
                             psi_absorber=bar.psi_absorber, z_damper=bar.z_damper,
                             z_absorber=bar.z_absorber, source=bar.source, info=bar.info)
        elif name == "ball_position_mm":
            half = d.gap / 2
            ini["ball_position"] = float(np.clip(v * 1e-3, -half, half))
        elif name == "ball_velocity_m_s":
            ini["ball_velocity"] = float(v)
    return replace(system, bar=bar, damper=d), Initial(**ini)


def _rms_runs(task) -> list[float]:
    """The tip RMS of one system over forces x ratios: one executor task (a sample's
    band), coarse enough that a process or Dask worker spends its time running."""
    system, ratios, forces, initial, duration, integrator = task
    return [simulate(system, Harmonic(f, r), duration=duration, initial=initial,
                     integrator=integrator).rms_tip for f in forces for r in ratios]


def frf_objective(system: System, objective: str) -> float:
    """The FRF peak |G| (m/N), or -min Re G (m/N), of a linear bar, on FRF_LINES
    lines over FRF_SPAN x the host's f1, refined by a parabola at the extreme."""
    wn = system.bar.natural_frequency
    w = np.linspace(FRF_SPAN[0] * wn, FRF_SPAN[1] * wn, FRF_LINES)
    kw = {"tmd": system.damper} if system.kind == "tmd" else {}
    g = tip_frf(system.bar, w, **kw)
    y = np.abs(g) if objective == "frf_peak" else -g.real
    i = int(np.clip(np.argmax(y), 1, len(y) - 2))
    a, b, c = y[i - 1], y[i], y[i + 1]
    denom = a - 2 * b + c
    return float(b - 0.125 * (a - c) ** 2 / denom) if denom < 0 else float(b)


def evaluate(spec: SystemSpec, options: DesignOptions, values: dict, samples: np.ndarray,
             execution: Execution | None = None) -> Candidate:
    """The objective of the design ``values`` over the uncertain ``samples``."""
    t0 = time.perf_counter()
    system = candidate_system(spec, options, values)
    names = tuple(p.name for p in options.uncertain)
    sampled = [sampled_system(system, names, row) for row in samples]
    if options.objective == "rms_band":
        tasks = [(s, options.ratios, options.forces_n, ini, options.duration_s,
                  options.integrator) for s, ini in sampled]
        rms = np.array(run_points(_rms_runs, tasks, execution=execution))
        values_per_sample = rms.max(axis=1) if options.band == "worst" else rms.mean(axis=1)
    else:
        values_per_sample = np.array([frf_objective(s, options.objective) for s, _ in sampled])
    stat, err = statistic(values_per_sample, options)
    return Candidate(dict(values), values_per_sample, stat, err, time.perf_counter() - t0,
                     system.to_dict())


def statistic(x: np.ndarray, options: DesignOptions) -> tuple[float, float]:
    """The statistic of the samples ``x`` and its sampling error."""
    n = len(x)
    if options.statistic == "max":
        return float(np.max(x)), 0.0
    if options.statistic == "mean":
        return float(np.mean(x)), float(np.std(x, ddof=1) / math.sqrt(n)) if n > 1 else 0.0
    q = float(np.quantile(x, options.quantile))
    if n == 1:
        return q, 0.0
    rng = np.random.default_rng(options.seed + 1)
    boot = np.quantile(x[rng.integers(0, n, (BOOTSTRAP, n))], options.quantile, axis=1)
    return q, float(np.std(boot, ddof=1))


# --- the search --------------------------------------------------------------------
def _sampler(options: DesignOptions, k: int):
    seed = options.seed * 1_000_003 + k
    if options.sampler == "cmaes":
        return optuna.samplers.CmaEsSampler(seed=seed, n_startup_trials=min(10, options.trials))
    return optuna.samplers.TPESampler(seed=seed, n_startup_trials=min(10, options.trials))


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
    study = _study(options, storage, _fingerprint(options, spec))
    done = _complete(study)
    new = 0
    while len(done) < options.trials and (stop_after is None or new < stop_after):
        study.sampler = _sampler(options, len(done))
        trial = study.ask()
        cand = evaluate(spec, options, _suggest(trial, options.variables), samples, execution)
        trial.set_user_attr("samples", cand.samples.tolist())
        trial.set_user_attr("error", cand.error)
        trial.set_user_attr("wall_time_s", cand.wall_time_s)
        study.tell(trial, cand.statistic)
        new += 1
        done = _complete(study)
        if progress is not None:
            progress(len(done), options.trials)
    published = _published_candidate(spec, options, samples, execution)
    return assemble(options, done, published, time.perf_counter() - t0)


def _fingerprint(options: DesignOptions, spec: SystemSpec) -> str:
    """What a stored search must match to be resumed: the options (but the number of
    trials, which a rerun may raise) and the bar."""
    text = json.dumps([repr(replace(options, trials=1)), spec.to_dict()], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _study(options: DesignOptions, storage, fingerprint: str) -> optuna.Study:
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    url = None if storage is None else f"sqlite:///{Path(storage).resolve()}"
    if storage is not None:
        Path(storage).parent.mkdir(parents=True, exist_ok=True)
    study = optuna.create_study(storage=url, study_name="boringbar-design",
                                direction="minimize", load_if_exists=True,
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
        if v.name == "gap_mm":
            values[v.name] = system.damper.gap * 1e3
        elif v.name == "ball_material":
            values[v.name] = system.damper.material
    return evaluate(spec, options, values, samples, execution)


def assemble(options: DesignOptions, trials: list, published: Candidate,
             wall_time_s: float) -> xr.Dataset:
    """The trial table (trial x variable values, objective samples, statistic, error,
    wall time), the best design and the published one, as a Dataset."""
    names = [v.name for v in options.variables]
    n = len(trials)
    coords = {"trial": np.arange(n), "sample": np.arange(options.samples)}
    data = {name: ("trial", [t.params[name] for t in trials]) for name in names}
    data["statistic"] = ("trial", [t.value for t in trials])
    data["error"] = ("trial", [t.user_attrs["error"] for t in trials])
    data["wall_time_s"] = ("trial", [t.user_attrs["wall_time_s"] for t in trials])
    data["objective_samples"] = (("trial", "sample"), [t.user_attrs["samples"] for t in trials])
    ds = xr.Dataset(data, coords=coords)
    best = int(np.argmin(ds["statistic"].values)) if n else -1
    ds.attrs = {
        "boringbar_version": __version__, "objective": options.objective,
        "band": options.band, "statistic": options.statistic, "sampler": options.sampler,
        "seed": options.seed, "samples": options.samples, "bar": options.bar,
        "best_trial": best, "wall_time_s": wall_time_s,
        "published_statistic": published.statistic, "published_error": published.error,
        "published_values": str(published.values),
        "options": repr(options),
    }
    return ds


def summary(ds: xr.Dataset) -> dict:
    """What ``boringbar design --json`` prints."""
    b = int(ds.attrs["best_trial"])
    names = [k for k in ds.data_vars if ds[k].dims == ("trial",) and k not in
             ("statistic", "error", "wall_time_s")]
    best = {k: (ds[k].values[b].item() if hasattr(ds[k].values[b], "item")
                else ds[k].values[b]) for k in names}
    obj, pub = float(ds["statistic"].values[b]), float(ds.attrs["published_statistic"])
    return {"best": best, "objective": obj, "objective_error": float(ds["error"].values[b]),
            "published_objective": pub, "improvement_percent": (1 - obj / pub) * 100,
            "trials": int(ds.sizes["trial"]), "wall_time_s": float(ds.attrs["wall_time_s"]),
            "objective_name": ds.attrs["objective"], "statistic_name": ds.attrs["statistic"]}


def comparison(spec: SystemSpec, options: DesignOptions, best: dict, n: int = 21,
               execution: Execution | None = None) -> dict:
    """The best design beside the file's own and the bare bar, at the nominal values:
    tip RMS (m) over ``n`` ratios across the band at the first force (rms_band), or
    |G| (m/N) over 0.8-1.2 x f1 (the FRF objectives). Returns x, its label, and
    a curve per bar."""
    bars = {"best design": candidate_system(spec, options, best),
            "file's design": make_system(options.bar, options.preset, spec=spec),
            "bare bar": make_system("solid", options.preset, spec=spec)}
    if options.objective == "rms_band":
        lo, hi = min(options.ratios), max(options.ratios)
        x = np.linspace(lo - 0.02, hi + 0.02, n) if lo == hi else np.linspace(lo, hi, n)
        force = options.forces_n[0]
        tasks = [(s, tuple(x), (force,), Initial(), options.duration_s, options.integrator)
                 for s in bars.values()]
        y = np.array(run_points(_rms_runs, tasks, execution=execution))
        return {"x": x, "xlabel": "Omega / omega_n", "ylabel": f"tip RMS (m), F0 = {force:g} N",
                "curves": dict(zip(bars, y, strict=True))}
    wn = bars["bare bar"].bar.natural_frequency
    w = np.linspace(0.8 * wn, 1.2 * wn, 801)
    curves = {k: np.abs(tip_frf(s.bar, w, **({"tmd": s.damper} if s.kind == "tmd" else {})))
              for k, s in bars.items()}
    return {"x": w / wn, "xlabel": "omega / omega_n", "ylabel": "|G| (m/N)", "curves": curves}


def summary_line(s: dict) -> str:
    """'best design X improves the objective by Y % over the published design'."""
    best = ", ".join(f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}"
                     for k, v in s["best"].items())
    gain = s["improvement_percent"]
    verb = f"improves the objective by {gain:.1f} %" if gain >= 0 else \
        f"is {-gain:.1f} % worse on the objective"
    return (f"best design {best} {verb} ({s['statistic_name']} of {s['objective_name']}) "
            f"against the file's own design ({s['objective']:.4g} +- "
            f"{s['objective_error']:.2g} against {s['published_objective']:.4g}; "
            f"{s['trials']} trials)")
