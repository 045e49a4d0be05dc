"""A design study's description: its variables, uncertain parameters and options, each
checked, and the Monte Carlo samples every candidate shares (docs/design.md)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.special

from boringbar._validate import ParameterError, check_choice, check_int, check_range
from boringbar.analysis.lobes import DEPTH_FLOOR, DEPTH_TOLERANCE, LobesOptions
from boringbar.analysis.speeds import check_speeds
from boringbar.model.dampers import MAX_GAP, MU_MAX, ImpactDamper
from boringbar.model.forcing import MAX_DEPTH
from boringbar.model.materials import MATERIALS
from boringbar.model.perturb import perturbed
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
CRITERIA = ("growth", "zero", "bounded")
#: variable -> (bars it applies to, unit, lowest allowed, highest allowed), SI
VARIABLES = {
    "gap_m": (("ball",), "m", 0.0, MAX_GAP),
    "ball_material": (("ball",), "", None, None),
    "ball_diameter_m": (("ball",), "m", 1e-3, 0.1),
    "cavity_position_m": (("ball",), "m", 0.0, math.inf),
    "restitution": (("ball",), "", 0.0, 1.0),
    "tmd_mass_kg": (("tmd",), "kg", 0.0, 100.0),
    "tmd_frequency_ratio": (("tmd",), "", 0.1, 10.0),
    "tmd_damping_ratio": (("tmd",), "", 0.0, 2.0),
}
UNCERTAIN = ("friction_force_n", "friction_number", "restitution", "ball_position_m",
             "ball_velocity_m_s", "damping_ratio", "mu_static", "mu_kinetic")
#: a rolling ball's floor friction coefficients (docs/model.md, section 2.7)
FLOOR_FRICTION = ("mu_static", "mu_kinetic")
DISTRIBUTIONS = ("uniform", "normal")
#: an uncertain parameter as a person reads it: (words, unit, factor from SI)
UNCERTAIN_READ = {"friction_force_n": ("friction force", "N", 1.0),
                  "friction_number": ("friction number", "", 1.0),
                  "restitution": ("restitution", "", 1.0),
                  "ball_position_m": ("ball position", "mm", 1e3),
                  "ball_velocity_m_s": ("ball velocity", "m/s", 1.0),
                  "damping_ratio": ("damping ratio", "", 1.0),
                  "mu_static": ("static floor friction", "", 1.0),
                  "mu_kinetic": ("kinetic floor friction", "", 1.0)}
#: The unit a person reads a quantity of an SI unit in (figures, summary lines, the
#: report): lengths in mm, as the design files give them; factor from SI.
READ_AS = {"m": ("mm", 1e3)}


def reading(name: str) -> tuple[str, str, float]:
    """A design variable as a person reads it: (words, unit, factor from SI), e.g.
    "gap_m" -> ("gap", "mm", 1e3), "tmd_mass_kg" -> ("tmd mass", "kg", 1.0),
    "ball_material" -> ("ball material", "", 1.0)."""
    unit = VARIABLES[name][1] if name in VARIABLES else ""
    words = (name.removesuffix(f"_{unit}") if unit else name).replace("_", " ")
    shown, factor = READ_AS.get(unit, (unit, 1.0))
    return words, shown, factor


#: how a person reads an objective's value: objective -> (unit, factor from SI); a
#: probability of chatter is read as it is
OBJECTIVE_READ = {"rms_band": ("mm", 1e3), "cut_amplitude": ("mm", 1e3),
                  "min_depth": ("mm", 1e3), "frf_peak": ("um/N", 1e6),
                  "min_real": ("um/N", 1e6)}


#: each objective's SI unit, as the trial table's column names end: m, or m/N written m_n
OBJECTIVE_SI = {"rms_band": "m", "cut_amplitude": "m", "min_depth": "m", "frf_peak": "m_n",
                "min_real": "m_n"}


def objective_reading(objective: str, statistic: str) -> tuple[str, float]:
    """(unit, factor from SI) of the ``statistic`` of ``objective`` as a person reads
    it (:data:`OBJECTIVE_READ`)."""
    if statistic == "chatter_probability":
        return "", 1.0
    return OBJECTIVE_READ[objective]


def shown(name: str, value) -> str:
    """'gap = 0.381 mm', 'ball material = tungsten': a variable's value as a person
    reads it (:func:`reading`)."""
    words, unit, factor = reading(name)
    if isinstance(value, str):
        return f"{words} = {value}"
    return f"{words} = {value * factor:.4g}" + (f" {unit}" if unit else "")


#: The options' lengths (m): name -> (lowest, highest, lowest excluded).  min_depth's
#: lobe search checks max_depth_m against its depth grid besides (LobesOptions).
LENGTHS = {"depth_m": (0.0, MAX_DEPTH, True), "max_depth_m": (DEPTH_FLOOR, MAX_DEPTH, False)}


def check_length(label: str, name: str, value, scale: float = 1.0, unit: str = "m") -> float:
    """The option length ``name`` (:data:`LENGTHS`) within its range; ``label``, ``value``
    and ``unit`` as the user gave it, ``scale`` times its SI value (a file's mm: 1e3)."""
    lo, hi, lo_open = LENGTHS[name]
    return check_range(label, value, lo * scale, hi * scale, lo_open=lo_open, unit=unit)


def check_bounds(label: str, name: str, low, high, scale: float = 1.0,
                 unit: str | None = None) -> None:
    """The range ``low``-``high`` of the variable ``name`` within its allowed one
    (:data:`VARIABLES`); ``label``, the bounds and ``unit`` (default: the variable's) as
    the user gave them, ``scale`` times SI (a file's mm: 1e3)."""
    _, si_unit, lo, hi = VARIABLES[name]
    unit = si_unit if unit is None else unit
    check_range(f"{label} low", low, lo * scale, hi * scale, unit=unit)
    check_range(f"{label} high", high, low, hi * scale, lo_open=True, unit=unit)


def check_distribution(label: str, distribution: str, a, b) -> None:
    """``distribution`` one of :data:`DISTRIBUTIONS`, with finite ``a`` and ``b`` >= a
    (uniform) or a standard deviation ``b`` >= 0 (normal), in any one unit."""
    check_choice(f"{label} distribution", distribution, DISTRIBUTIONS)
    check_range(f"{label} a", a, -math.inf, math.inf, lo_open=True, hi_open=True)
    if distribution == "uniform":
        check_range(f"{label} b", b, a, math.inf, hi_open=True)
    else:
        check_range(f"{label} standard deviation", b, 0.0, math.inf, hi_open=True)


@dataclass(frozen=True)
class Variable:
    """A design variable: ``name`` (one of :data:`VARIABLES`), its range
    ``low``-``high`` (SI, units as in the name: ``Variable("gap_m", 0.1e-3, 0.5e-3)``),
    or ``choices`` (ball_material)."""

    name: str
    low: float | None = None
    high: float | None = None
    choices: tuple = ()

    def __post_init__(self):
        check_choice("design variable", self.name, tuple(VARIABLES))
        if self.name == "ball_material":
            if not self.choices:
                raise ParameterError("ball_material needs choices, e.g. ['carbide', 'steel']")
            for c in self.choices:
                check_choice("ball_material choice", c, tuple(MATERIALS))
            return
        check_bounds(self.name, self.name, self.low, self.high)


@dataclass(frozen=True)
class Uncertain:
    """An uncertain parameter ``name`` (one of :data:`UNCERTAIN`, SI) and its
    ``distribution``: ``uniform`` on [a, b], or ``normal`` with mean a and standard
    deviation b (0: fixed at a)."""

    name: str
    distribution: str
    a: float
    b: float

    def __post_init__(self):
        check_choice("uncertain parameter", self.name, UNCERTAIN)
        check_distribution(self.name, self.distribution, self.a, self.b)

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
    mean. cut_amplitude: the steady amplitude of a cut at ``rpm`` and ``depth_m``
    (m). min_depth: the minimum chatter-free depth over ``rpms``, each speed's limit
    found by the lobes' search up to ``max_depth_m`` (m) to ``depth_tolerance`` of
    itself (:meth:`lobes_options`), by ``criterion`` as the lobes judge a cut: "growth"
    (the converged verdict; the default, "zero" under the paper preset: the force
    reaches zero) or "bounded"; under "growth" cut_amplitude is half the settled tip
    peak-to-peak of a knocked cut (0 where the knock dies out). Fixed runs last
    ``duration_s`` with ``integrator`` (a cut takes rk4); ``preset``. Every quantity is
    SI (design files take mm: docs/design.md)."""

    bar: str
    variables: tuple[Variable, ...]
    objective: str | tuple[str, ...] = "rms_band"
    band: str = "worst"
    ratios: tuple[float, ...] = (0.95, 1.0, 1.05)
    forces_n: tuple[float, ...] = (10.0,)
    rpm: float = 1200.0
    depth_m: float = 0.05e-3
    rpms: tuple[float, ...] = (900.0, 1200.0, 1500.0)
    max_depth_m: float = 1e-3
    depth_tolerance: float = DEPTH_TOLERANCE
    criterion: str | None = None
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
        if self.criterion is None:  # the lobes' default (lobes.criterion_for)
            object.__setattr__(self, "criterion", "zero" if self.preset == "paper"
                               else "growth")
        check_choice("criterion", self.criterion, CRITERIA)
        if self.statistic == "chatter_probability" and objectives != ("cut_amplitude",):
            raise ParameterError("statistic = 'chatter_probability' goes with objective "
                                 "'cut_amplitude' (the cut at rpm, depth_m) alone")
        if len(objectives) > 1 and self.sampler != "nsga2":
            raise ParameterError(f"{len(objectives)} objectives are a Pareto search: "
                                 "sampler = 'nsga2'")
        check_int("samples", self.samples, 1, 100_000)
        check_int("trials", self.trials, 1, 100_000)
        check_int("seed", self.seed, 0, 2**31 - 1)
        check_range("quantile", self.quantile, 0.0, 1.0, lo_open=True, hi_open=True)
        check_range("rpm", self.rpm, 0.0, 1e5, lo_open=True, unit="rev/min")
        check_length("depth_m", "depth_m", self.depth_m)
        check_length("max_depth_m", "max_depth_m", self.max_depth_m)
        check_range("duration_s", self.duration_s, 0.0, 100.0, lo_open=True, unit="s")
        check_speeds("rpms", self.rpms)
        self.lobes_options()  # the search's grid: depth_tolerance, and depths up to max_depth_m
        if not self.variables:
            raise ParameterError("a design study needs at least one variable")
        for v in self.variables:
            if self.bar not in VARIABLES[v.name][0]:
                raise ParameterError(f"variable {v.name!r} applies to a "
                                     f"{VARIABLES[v.name][0][0]} bar, not bar = {self.bar!r}")

    def lobes_options(self) -> LobesOptions:
        """min_depth's lobe search: at each of ``rpms``, bisection on the lobes' geometric
        depth grid (each depth ``depth_tolerance`` above the one below, from
        :data:`~boringbar.analysis.lobes.DEPTH_FLOOR`) up to ``max_depth_m``, seeded at the
        analytic limit, by ``criterion``, with the published cut."""
        return LobesOptions(tuple(float(r) for r in self.rpms), "search", self.criterion,
                            None, self.max_depth_m, analytic=False,
                            depth_tolerance=self.depth_tolerance)

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


def nominal_sample(options: DesignOptions) -> np.ndarray:
    """The uncertain parameters at their centre: a uniform one's midpoint, a normal one's
    mean (the nominal sample the figures of the best design are drawn at)."""
    return np.array([(p.a + p.b) / 2 if p.distribution == "uniform" else p.a
                     for p in options.uncertain], dtype=float)


def nominal_words(options: DesignOptions) -> str:
    """The nominal sample in words, as a person reads it: "friction force = 0.25 N,
    restitution = 0.7"; "nominal values" without uncertain parameters."""
    words = []
    for p, v in zip(options.uncertain, nominal_sample(options), strict=True):
        name, unit, factor = UNCERTAIN_READ[p.name]
        words.append(f"{name} = {v * factor:.3g}" + (f" {unit}" if unit else ""))
    return ", ".join(words) or "nominal values"


def sampled_system(system: System, names: tuple, row) -> tuple[System, Initial]:
    """``system`` and the initial state with one sample of the uncertain parameters."""
    ini, floor = {}, {}
    for name, v in zip(names, row, strict=True):
        if name in ("friction_force_n", "restitution", "damping_ratio"):
            system = perturbed(system, **{name: float(v)})
        elif name == "friction_number":  # the published number, read as the preset reads it
            kind, value = (("paper-number", max(float(v), 0.0)) if system.preset == "paper"
                           else ("rolling", max(float(v), 0.0) * 1e-3))
            d = system.damper
            system = replace(system, damper=replace(d, friction=replace(d.friction, kind=kind,
                                                                        value=value)))
        elif name == "ball_position_m":
            half = system.damper.gap_m / 2
            ini["ball_position_m"] = float(np.clip(v, -half, half))
        elif name == "ball_velocity_m_s":
            ini["ball_velocity_m_s"] = float(v)
        elif name in FLOOR_FRICTION:
            floor[name] = float(v)
    if floor:
        system = floor_friction(system, floor)
    return system, Initial(**ini)


def floor_friction(system: System, drawn: dict) -> System:
    """``system`` with a rolling ball's floor friction coefficients as ``drawn`` (name ->
    value), each clipped to [0, MU_MAX]; a kinetic one drawn above the static one slips
    at the static one (the ball is held by at least what it slips with)."""
    d = system.damper
    if not isinstance(d, ImpactDamper) or d.motion != "roll":
        raise ParameterError(f"uncertain {next(iter(drawn))} is a rolling ball's floor "
                             "friction, and this bar has no rolling ball (a system file's "
                             "ball.motion = 'roll')")
    mus = float(np.clip(drawn.get("mu_static", d.mu_static), 0.0, MU_MAX))
    muk = float(np.clip(drawn.get("mu_kinetic", d.mu_kinetic), 0.0, mus))
    return replace(system, damper=replace(d, mu_static=mus, mu_kinetic=muk))
