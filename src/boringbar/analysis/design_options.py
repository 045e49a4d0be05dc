"""A design study's description: its variables, uncertain parameters and options, each
checked, and the Monte Carlo samples every candidate shares (docs/design.md)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.special

from boringbar._validate import ParameterError, check_choice, check_int, check_range
from boringbar.model.dampers import MAX_GAP
from boringbar.model.materials import MATERIALS
from boringbar.model.system import System
from boringbar.simulate import Initial

#: objective -> (what it needs, Optuna's direction); the FRF ones are linear bars'
OBJECTIVES = {"rms_band": ("harmonic runs", "minimize"),
              "cut_amplitude": ("cuts", "minimize"),
              "min_depth": ("cuts", "maximize"),
              "frf_peak": ("the linear tip FRF", "minimize"),
              "min_real": ("the linear tip FRF", "minimize")}
BAND_REDUCTIONS = ("worst", "mean")
STATISTICS = ("mean", "quantile", "max", "chatter_probability")
SAMPLERS = ("tpe", "cmaes", "nsga2")
CRITERIA = ("zero", "bounded")
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
UNCERTAIN = ("friction_force_n", "friction_number", "restitution", "ball_position_mm",
             "ball_velocity_m_s", "damping_ratio")
DISTRIBUTIONS = ("uniform", "normal")


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
    """A design study: ``bar`` ("ball" or "tmd"), ``variables``, ``objective`` (one of
    :data:`OBJECTIVES`, or a tuple of them: a Pareto search), ``uncertain``
    parameters and ``samples`` Monte Carlo samples, ``statistic``
    (:data:`STATISTICS`; ``quantile`` q), ``trials`` and ``sampler``
    (:data:`SAMPLERS`; several objectives take nsga2) with ``seed``.

    rms_band: the tip RMS over ``ratios`` x ``forces_n``, its ``band`` worst or
    mean. cut_amplitude: the steady amplitude of a cut at ``rpm`` and
    ``depth_mm``. min_depth: the minimum chatter-free depth over ``rpms`` (a
    bisection of each speed's limit up to ``max_depth_mm`` in ``depth_step_mm``,
    by ``criterion``: "zero", the force reaches zero, or "bounded"). Runs last
    ``duration_s`` with ``integrator`` (a cut takes rk4); ``preset``."""

    bar: str
    variables: tuple[Variable, ...]
    objective: str | tuple[str, ...] = "rms_band"
    band: str = "worst"
    ratios: tuple[float, ...] = (0.95, 1.0, 1.05)
    forces_n: tuple[float, ...] = (10.0,)
    rpm: float = 1200.0
    depth_mm: float = 0.05
    rpms: tuple[float, ...] = (900.0, 1200.0, 1500.0)
    max_depth_mm: float = 1.0
    depth_step_mm: float = 0.01
    criterion: str = "zero"
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
        objectives = (self.objective,) if isinstance(self.objective, str) else \
            tuple(self.objective)
        object.__setattr__(self, "objective", objectives[0] if len(objectives) == 1
                           else objectives)
        if not objectives or len(set(objectives)) != len(objectives):
            raise ParameterError(f"objective = {self.objective!r}: one objective, or "
                                 "several different ones")
        for o in objectives:
            check_choice("objective", o, tuple(OBJECTIVES))
            if OBJECTIVES[o][0] == "the linear tip FRF" and self.bar == "ball":
                raise ParameterError(f"objective = {o!r} is a linear bar's (the tip FRF); a "
                                     "ball damper takes rms_band, cut_amplitude or min_depth")
        check_choice("band", self.band, BAND_REDUCTIONS)
        check_choice("statistic", self.statistic, STATISTICS)
        check_choice("sampler", self.sampler, SAMPLERS)
        check_choice("criterion", self.criterion, CRITERIA)
        if self.statistic == "chatter_probability" and objectives != ("cut_amplitude",):
            raise ParameterError("statistic = 'chatter_probability' goes with objective "
                                 "'cut_amplitude' (the cut at rpm, depth_mm) alone")
        if len(objectives) > 1 and self.sampler != "nsga2":
            raise ParameterError(f"{len(objectives)} objectives are a Pareto search: "
                                 "sampler = 'nsga2'")
        check_int("samples", self.samples, 1, 100_000)
        check_int("trials", self.trials, 1, 100_000)
        check_int("seed", self.seed, 0, 2**31 - 1)
        check_range("quantile", self.quantile, 0.0, 1.0, lo_open=True, hi_open=True)
        check_range("rpm", self.rpm, 0.0, 1e5, lo_open=True, unit="rev/min")
        check_range("depth_mm", self.depth_mm, 0.0, 100.0, lo_open=True, unit="mm")
        check_range("max_depth_mm", self.max_depth_mm, 0.0, 100.0, lo_open=True, unit="mm")
        check_range("depth_step_mm", self.depth_step_mm, 0.0, self.max_depth_mm, lo_open=True,
                    unit="mm")
        check_range("duration_s", self.duration_s, 0.0, 100.0, lo_open=True, unit="s")
        for r in self.rpms:
            check_range("rpms", r, 0.0, 1e5, lo_open=True, unit="rev/min")
        if not self.variables:
            raise ParameterError("a design study needs at least one variable")
        for v in self.variables:
            if self.bar not in VARIABLES[v.name][0]:
                raise ParameterError(f"variable {v.name!r} applies to a "
                                     f"{VARIABLES[v.name][0][0]} bar, not bar = {self.bar!r}")

    @property
    def objectives(self) -> tuple[str, ...]:
        return (self.objective,) if isinstance(self.objective, str) else self.objective

    @property
    def directions(self) -> list[str]:
        return [OBJECTIVES[o][1] for o in self.objectives]


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
            d = replace(d, friction=replace(d.friction, kind="force", value=max(float(v), 0.0)))
        elif name == "friction_number":  # the published number, read as the preset reads it
            kind, value = (("paper-number", max(float(v), 0.0)) if system.preset == "paper"
                           else ("rolling", max(float(v), 0.0) * 1e-3))
            d = replace(d, friction=replace(d.friction, kind=kind, value=value))
        elif name == "restitution":
            d = replace(d, restitution=float(np.clip(v, 0.0, 1.0)))
        elif name == "damping_ratio":
            bar = replace(bar, damping_ratio=np.full(bar.n_modes, float(np.clip(v, 0.0, 0.99))))
        elif name == "ball_position_mm":
            half = d.gap_m / 2
            ini["ball_position_m"] = float(np.clip(v * 1e-3, -half, half))
        elif name == "ball_velocity_m_s":
            ini["ball_velocity_m_s"] = float(v)
    return replace(system, bar=bar, damper=d), Initial(**ini)
