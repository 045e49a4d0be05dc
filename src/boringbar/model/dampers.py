"""The dampers: a free ball with clearance (docs/model.md, section 2) and a tuned
mass damper (section 3), with Den Hartog's design.

All quantities SI.  A bar with no damper is ``damper=None``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from boringbar._validate import (
    ParameterError,
    check_choice,
    check_nonnegative,
    check_positive,
    check_range,
)
from boringbar.model.bar import ModalModel
from boringbar.model.contact import (
    CONTACT_LAWS,
    check_contact_stiffness,
    check_hertz_restitution,
    effective_modulus_pa,
    hertz_stiffness_n_m1_5,
)
from boringbar.model.materials import MATERIALS

GRAVITY = 9.81
BALL_DIAMETER = 0.015
#: The largest total clearance delta (m) the cavity allows: the published bar
#: (25 mm diameter) holds the 15 mm ball in a cross-drilled cavity whose length
#: beyond the ball is not part of the model (the FE sections only reduce the
#: diameter there), so the bound is the one stated for the published cavity in
#: issue #7: at most 2 mm of clearance.  Gaps used in the published study: 0.1
#: and 0.5 mm.
MAX_GAP = 2e-3
#: The largest friction force (N) a ball may be given (``Friction("force", ...)``):
#: far above any rolling or Coulomb force of a 26 g ball, small enough that the
#: kernel's arithmetic stays finite.
MAX_FRICTION_FORCE = 1e6
#: Ball densities (kg/m^3) by material name (model/materials.py).
BALL_DENSITY = {name: m.density for name, m in MATERIALS.items()}
#: The published carbide ball's mass (26 g, as published; 14.7 g/cm^3 gives 25.98 g).
PUBLISHED_CARBIDE_MASS = 0.026
#: The published rolling-resistance number, "0.6" (mm).
PUBLISHED_FRICTION_NUMBER = 0.6
#: The published absorber (docs/model.md, section 3).
PUBLISHED_TMD = {"mass_kg": 0.39, "stiffness_n_m": 1.05e6, "damping_n_s_m": 505.0}
FRICTION_KINDS = ("none", "rolling", "coulomb", "force", "paper-number")
#: How the ball moves along its cavity: sliding (the published model) or rolling, its
#: spin a state (docs/model.md, section 2.7).
BALL_MOTIONS = ("slide", "roll")
#: A rolling ball's floor friction coefficients, static and kinetic: typical of carbide
#: on steel wetted by coolant (dry, 0.3-0.5; nobody measures them well in a bar, and a
#: design search takes their spread).
MU_STATIC, MU_KINETIC = 0.2, 0.15
#: The largest friction coefficient a rolling ball may be given.
MU_MAX = 10.0
REACTIONS = ("reciprocal", "printed")


@dataclass(frozen=True)
class Friction:
    """Friction between ball and cavity floor, F_b = -F_c sgn(y').

    ``kind`` says how ``value`` gives the magnitude F_c for a ball of mass m,
    radius r_m:

    - ``rolling``: rolling-resistance length nu (m), F_c = nu m g / r_m
      (published nu = 0.6 mm gives F_c = 0.08 m g, 0.0204 N for 26 g);
    - ``coulomb``: coefficient mu_c, F_c = mu_c m g;
    - ``force``: F_c itself (N);
    - ``paper-number``: **friction force as computed in the paper**: the
      published number (0.6, meant in mm) used with r_m in metres,
      F_c = value m g / r_m (20.4 N for 0.6 and 26 g).  Kept so the published
      results can be rerun; not physics.
    - ``none``: F_c = 0.

    ``reaction`` is how the bar feels it: ``reciprocal`` (-psi_d F_b, action
    equals reaction) or ``printed``, the **bar reaction as printed**
    (+psi_d F_b: the bar is pushed the same way as the ball; breaks momentum
    and energy balance, which the results then report).

    ``static_ratio`` = F_s / F_c >= 1, the static limit of true stick-slip
    (docs/model.md, section 5): the ball sticks while the force needed to carry it
    with the bar is at most F_s.  Only the exact integrator models it; the
    published RK4 scheme has the sgn() law, whose chatter is stick-slip with
    F_s = F_c, and refuses any other ratio.
    """

    kind: str = "rolling"
    value: float = PUBLISHED_FRICTION_NUMBER * 1e-3
    reaction: str = "reciprocal"
    static_ratio: float = 1.0

    def __post_init__(self):
        check_choice("friction kind", self.kind, FRICTION_KINDS)
        check_choice("friction reaction", self.reaction, REACTIONS)
        if self.kind == "force":
            check_range("friction value (force)", self.value, 0.0, MAX_FRICTION_FORCE, unit="N")
        else:
            check_nonnegative(f"friction value ({self.kind})", self.value)
        check_range("friction static_ratio (F_s / F_c)", self.static_ratio, 1.0, math.inf,
                    hi_open=True)

    def force(self, mass_kg: float, radius_m: float) -> float:
        """F_c (N) for a ball of ``mass_kg`` (kg) and ``radius_m`` (m)."""
        mass, radius = mass_kg, radius_m
        if self.kind == "none":
            return 0.0
        if self.kind == "rolling":
            return self.value * mass * GRAVITY / radius
        if self.kind == "coulomb":
            return self.value * mass * GRAVITY
        if self.kind == "force":
            return self.value
        return self.value * mass * GRAVITY / radius  # paper-number: value taken as metres

    def to_dict(self) -> dict:
        return {"kind": self.kind, "value": self.value, "reaction": self.reaction,
                "static_ratio": self.static_ratio}


    @classmethod
    def from_dict(cls, d: dict) -> Friction:
        """The friction :meth:`to_dict` describes."""
        return cls(d["kind"], d["value"], d["reaction"], d["static_ratio"])


NO_FRICTION = Friction("none", 0.0)


@dataclass(frozen=True)
class ImpactDamper:
    """A free ball in a cavity at z_d with total clearance ``gap_m`` (delta, m).

    The ball (``mass_kg`` kg, ``radius_m`` m, ``material`` a name for the record)
    travels delta/2 each way from the cavity centre; ``restitution`` is the
    coefficient of restitution of its impacts (0-1); ``friction`` (a
    :class:`Friction`) acts while it rolls or slides along the cavity.  ``locked``
    turns it into a rigid added mass at z_d (for comparison).
    :meth:`ball` builds one from a material and a diameter.

    ``motion``: ``"slide"`` (the published model) or ``"roll"``: the ball's spin is a
    state; it rolls while the floor's friction that keeps it rolling is at most
    ``mu_static`` m g and slips with ``mu_kinetic`` m g beyond (docs/model.md, section
    2.7); ``friction`` then acts as rolling resistance, as for a sliding ball.

    ``contact``: how the ball meets the plugs that close its cavity
    (docs/model.md, section 2.6): ``"impact"``, the published instantaneous law with
    restitution e (the default), or ``"hertz"``, a compliant contact of Hertz's law with
    Hunt and Crossley's damping tuned so that each impact restores e.  Its stiffness K
    (N/m^1.5) is ``contact_stiffness_n_m1_5``, or if None Hertz's for this ball on a flat
    plug of ``plug_material`` (model/materials.py).
    """

    mass_kg: float = PUBLISHED_CARBIDE_MASS
    gap_m: float = 0.5e-3
    restitution: float = 0.7
    friction: Friction = Friction()
    radius_m: float = BALL_DIAMETER / 2
    locked: bool = False
    material: str = "carbide"
    contact: str = "impact"
    contact_stiffness_n_m1_5: float | None = None
    plug_material: str = "steel"
    motion: str = "slide"
    mu_static: float = MU_STATIC
    mu_kinetic: float = MU_KINETIC

    def __post_init__(self):
        check_positive("ball mass_kg", self.mass_kg, "kg")
        self._check_motion()
        check_choice("ball contact", self.contact, CONTACT_LAWS)
        check_choice("plug_material", self.plug_material, tuple(MATERIALS))
        if self.contact_stiffness_n_m1_5 is not None:
            check_contact_stiffness(self.contact_stiffness_n_m1_5)
        if self.contact == "hertz":
            check_hertz_restitution(self.restitution)
            if self.contact_stiffness_n_m1_5 is None and self.material not in MATERIALS:
                raise ParameterError(f"ball material = {self.material!r} has no elastic "
                                     "constants: a Hertz contact needs a "
                                     "contact_stiffness_n_m1_5")
        check_range("gap_m", self.gap_m, 0.0, MAX_GAP, lo_open=True, unit="m")
        check_range("restitution", self.restitution, 0.0, 1.0)
        check_positive("ball radius_m", self.radius_m, "m")
        if not isinstance(self.friction, Friction):
            raise ParameterError(f"friction = {self.friction!r} must be a Friction")

    @classmethod
    def ball(cls, material: str = "carbide", *, gap_m: float = 0.5e-3,
             restitution: float = 0.7, friction: Friction = Friction(),
             diameter_m: float = BALL_DIAMETER, mass_kg: float | None = None,
             locked: bool = False, contact: str = "impact",
             contact_stiffness_n_m1_5: float | None = None,
             plug_material: str = "steel", motion: str = "slide",
             mu_static: float = MU_STATIC, mu_kinetic: float = MU_KINETIC) -> ImpactDamper:
        """A ball of ``material`` (carbide: 26 g as published; steel: from density) and
        ``diameter_m`` (m); ``mass_kg`` (kg) overrides the material's mass; ``contact``,
        ``contact_stiffness_n_m1_5`` (N/m^1.5), ``plug_material``, ``motion``,
        ``mu_static`` and ``mu_kinetic`` as the class says."""
        check_choice("ball material", material, tuple(BALL_DENSITY) + ("custom",))
        check_positive("ball diameter_m", diameter_m, "m")
        diameter, mass = diameter_m, mass_kg
        if mass is None:
            if material == "custom":
                raise ParameterError("ball material = 'custom' needs a mass_kg")
            if material == "carbide" and diameter == BALL_DIAMETER:
                mass = PUBLISHED_CARBIDE_MASS
            else:
                mass = BALL_DENSITY[material] * math.pi / 6 * diameter**3
        return cls(mass_kg=mass, gap_m=gap_m, restitution=restitution, friction=friction,
                   radius_m=diameter / 2, locked=locked, material=material, contact=contact,
                   contact_stiffness_n_m1_5=contact_stiffness_n_m1_5,
                   plug_material=plug_material, motion=motion, mu_static=mu_static,
                   mu_kinetic=mu_kinetic)

    @property
    def friction_force_n(self) -> float:
        """F_c (N)."""
        return self.friction.force(self.mass_kg, self.radius_m)

    def _check_motion(self) -> None:
        check_choice("ball motion", self.motion, BALL_MOTIONS)
        check_range("mu_static", self.mu_static, 0.0, MU_MAX)
        check_range("mu_kinetic", self.mu_kinetic, 0.0, MU_MAX)
        if self.mu_static < self.mu_kinetic:
            raise ParameterError(f"mu_static = {self.mu_static!r} is below mu_kinetic = "
                                 f"{self.mu_kinetic!r}: a ball that slips with mu_kinetic "
                                 "is held by at least as much")
        if self.motion == "roll" and self.friction.reaction != "reciprocal":
            raise ParameterError("a rolling ball takes the reciprocal friction reaction, not "
                                 f"{self.friction.reaction!r} (the paper preset's printed "
                                 "sign): give friction_reaction = 'reciprocal' "
                                 "(--friction-reaction reciprocal)")
        if self.motion == "roll" and self.friction.static_ratio != 1:
            raise ParameterError("friction static_ratio is a sliding ball's stick-slip; a "
                                 "rolling one has mu_static and mu_kinetic")

    @property
    def hertz_stiffness_n_m1_5(self) -> float:
        """K (N/m^1.5) of the Hertz contact: the given one, else the ball's (its
        material, radius) on a flat plug of ``plug_material``."""
        if self.contact_stiffness_n_m1_5 is not None:
            return self.contact_stiffness_n_m1_5
        b, p = MATERIALS[self.material], MATERIALS[self.plug_material]
        return hertz_stiffness_n_m1_5(self.radius_m, effective_modulus_pa(
            b.youngs_modulus, b.poisson_ratio, p.youngs_modulus, p.poisson_ratio))

    @property
    def static_friction_force_n(self) -> float:
        """F_s = static_ratio F_c (N): the most friction can hold the ball with."""
        return self.friction_force_n * self.friction.static_ratio

    def to_dict(self) -> dict:
        d = {"type": "ball", "material": self.material, "mass_kg": self.mass_kg,
             "gap_m": self.gap_m, "restitution": self.restitution, "radius_m": self.radius_m,
             "locked": self.locked, "friction": self.friction.to_dict(),
             "friction_force_n": self.friction_force_n}
        if self.contact != "impact":  # (the impact law's description as it always was)
            d.update(contact=self.contact, contact_stiffness_n_m1_5=self.hertz_stiffness_n_m1_5,
                     plug_material=self.plug_material)
        if self.motion != "slide":  # (likewise the sliding ball's)
            d.update(motion=self.motion, mu_static=self.mu_static, mu_kinetic=self.mu_kinetic)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> ImpactDamper:
        """The ball :meth:`to_dict` describes."""
        return cls(mass_kg=d["mass_kg"], gap_m=d["gap_m"], restitution=d["restitution"],
                   friction=Friction.from_dict(d["friction"]), radius_m=d["radius_m"],
                   locked=d["locked"], material=d["material"],
                   contact=d.get("contact", "impact"),
                   contact_stiffness_n_m1_5=d.get("contact_stiffness_n_m1_5"),
                   plug_material=d.get("plug_material", "steel"),
                   motion=d.get("motion", "slide"), mu_static=d.get("mu_static", MU_STATIC),
                   mu_kinetic=d.get("mu_kinetic", MU_KINETIC))


@dataclass(frozen=True)
class TunedMassDamper:
    """An absorber of ``mass_kg`` (kg) on spring ``stiffness_n_m`` (N/m) and dashpot
    ``damping_n_s_m`` (N s/m) at ``position_m`` z_a (m from the clamp); ``design`` names
    where the values came from ("given", "published", "den-hartog", "sims")."""

    mass_kg: float
    stiffness_n_m: float
    damping_n_s_m: float
    position_m: float = 0.096
    design: str = "given"

    def __post_init__(self):
        check_positive("absorber mass_kg", self.mass_kg, "kg")
        check_positive("absorber stiffness_n_m", self.stiffness_n_m, "N/m")
        check_nonnegative("absorber damping_n_s_m", self.damping_n_s_m, "N s/m")
        check_range("absorber position_m", self.position_m, 0.0, math.inf, lo_open=True,
                    hi_open=True, unit="m")

    @classmethod
    def published(cls, position_m: float = 0.096) -> TunedMassDamper:
        """The published design (m_a = 0.39 kg, k_a = 1.05 MN/m, c_a = 505 N s/m) at
        ``position_m`` (m from the clamp)."""
        return cls(**PUBLISHED_TMD, position_m=position_m, design="published")

    @classmethod
    def den_hartog(cls, mass_kg: float, bar: ModalModel,
                   position_m: float | None = None) -> TunedMassDamper:
        """Den Hartog's optimum of ``mass_kg`` (kg) for the first mode of ``bar`` (a
        ModalModel), at ``position_m`` (m; default: ``bar.z_absorber_m``).

        mu_a = m_a psi_a^2 / M, f_opt = 1/(1 + mu_a),
        zeta_opt = sqrt(3 mu_a / (8 (1 + mu_a)^3)), k_a = m_a (f_opt omega_n)^2,
        c_a = 2 zeta_opt m_a omega_n.  ``bar.psi_absorber`` must be psi(z_a).
        """
        check_positive("absorber mass_kg", mass_kg, "kg")
        p = den_hartog_parameters(mass_kg, bar)
        return cls(mass_kg=mass_kg, stiffness_n_m=p["stiffness_n_m"],
                   damping_n_s_m=p["damping_n_s_m"],
                   position_m=bar.z_absorber_m if position_m is None else position_m,
                   design="den-hartog")

    def to_dict(self) -> dict:
        return {"type": "tmd", "mass_kg": self.mass_kg, "stiffness_n_m": self.stiffness_n_m,
                "damping_n_s_m": self.damping_n_s_m, "position_m": self.position_m,
                "design": self.design}

    @classmethod
    def from_dict(cls, d: dict) -> TunedMassDamper:
        """The absorber :meth:`to_dict` describes."""
        return cls(d["mass_kg"], d["stiffness_n_m"], d["damping_n_s_m"],
                   d["position_m"], d["design"])


def roll_words(mu_static: float, mu_kinetic: float) -> str:
    """'mu_s 0.2, mu_k 0.15': a rolling ball's friction coefficients, as a run's summary
    and its figure's title name them."""
    return f"mu_s {mu_static:g}, mu_k {mu_kinetic:g}"


def spin_gain(mass_kg: float) -> float:
    """r^2 / I = 5 / (2 m) of a solid ball of ``mass_kg`` (1/kg, I = 2/5 m r^2): a friction
    F at its rim turns its spin r omega at -F r^2 / I (docs/model.md, 2.7)."""
    return 2.5 / mass_kg


def den_hartog_parameters(mass_kg: float, bar: ModalModel) -> dict:
    """Den Hartog's formulas (docs/model.md, section 3) for an absorber of ``mass_kg``
    (kg) on mode 1 of ``bar`` (a ModalModel): mass ratio, frequency and damping ratios,
    stiffness (N/m) and damping (N s/m)."""
    mass = mass_kg
    mu = mass * bar.psi_absorber[0] ** 2 / bar.mass_kg[0]
    wn = bar.natural_frequency_rad_s
    f_opt = 1.0 / (1.0 + mu)
    zeta = math.sqrt(3.0 * mu / (8.0 * (1.0 + mu) ** 3))
    return {"mass_ratio": mu, "frequency_ratio": f_opt, "damping_ratio": zeta,
            "stiffness_n_m": mass * (f_opt * wn) ** 2, "damping_n_s_m": 2.0 * zeta * mass * wn}


def absorber_mass_ratio(mass: float, bar) -> float:
    """mu = m_a psi_a,1^2 / M_1 (mode 1; independent of the mode's normalisation)."""
    check_positive("absorber mass", mass, "kg")
    return float(mass * bar.psi_absorber[0] ** 2 / bar.mass_kg[0])


# --- Sims' equal-real-trough tuning ---------------------------------------------
def sims_parameters(mass: float, bar) -> dict:
    """Sims' equal-real-trough optimum for an absorber on mode 1 of ``bar``.

    With mu = m_a psi_a^2 / M and s = sqrt(4 + 3 mu), for an undamped
    single-mode host the tuning that minimises max(-Re G) is

        zeta_a = sqrt((8 + 9 mu - 4 s) / (16 (1 + mu)))     [= c_a / (2 m_a omega_a)]
        f      = omega_a / omega_n
               = sqrt(12 + 12 s + 9 s^2 + 9 sqrt(mu (3 s + 2)(s + 2))) / (sqrt(72) (1 + mu))

    k_a = m_a (f omega_n)^2, c_a = 2 zeta_a m_a f omega_n.  zeta_a is Sims'
    formula; f is the exact root of the same minimax problem (the larger
    root of 36 Y^2 - (12 + 12 s + 9 s^2) Y + 4 (5 + 3 mu + 2 s) = 0 with
    Y = (f (1 + mu))^2), identified to 50 digits against a high-precision
    numerical minimax.  As mu -> 0, zeta_a -> sqrt(3 mu / 8) like Den
    Hartog's, but f -> 1 + sqrt(mu / 8): Sims tunes the absorber above the
    host, Den Hartog (f = 1/(1 + mu)) below it.  The host's own damping and
    the other modes are ignored (``minimax_real_tuning`` includes them).
    """
    mu = absorber_mass_ratio(mass, bar)
    s = math.sqrt(4.0 + 3.0 * mu)
    zeta = math.sqrt((8.0 + 9.0 * mu - 4.0 * s) / (16.0 * (1.0 + mu)))
    y = (12.0 + 12.0 * s + 9.0 * s * s + 9.0 * math.sqrt(mu * (3 * s + 2) * (s + 2))) / 72.0
    f = math.sqrt(y) / (1.0 + mu)
    wa = f * bar.natural_frequency_rad_s
    return {
        "mass_ratio": mu,
        "frequency_ratio": f,
        "damping_ratio": zeta,
        "stiffness_n_m": mass * wa**2,
        "damping_n_s_m": 2.0 * zeta * mass * wa,
    }


def sims_tuning(mass_kg: float, bar: ModalModel) -> TunedMassDamper:
    """A :class:`TunedMassDamper` of ``mass_kg`` (kg) at ``bar.z_absorber_m``, Sims-tuned
    (the ModalModel ``bar``'s mode 1)."""
    p = sims_parameters(mass_kg, bar)
    return TunedMassDamper(
        mass_kg=mass_kg,
        stiffness_n_m=p["stiffness_n_m"],
        damping_n_s_m=p["damping_n_s_m"],
        position_m=bar.z_absorber_m,
        design="sims",
    )
