"""A bar with its damper, and the two presets (docs/model.md, section 2).

``physical`` (the default) is the model as physics demands.  ``paper``
switches on exactly the published readings that docs/model.md names, so the
published study can be rerun as it was done:

- **friction force as computed in the paper**: the rolling-resistance
  number 0.6 (mm) used with r_m in metres, F_c = 0.6 m g / 0.0075 = 20.4 N;
- **bar reaction as printed**: the bar feels +psi_d F_b instead of -psi_d F_b;
- **stiffness calibrated to the published frequencies**: K scaled so that
  f1 = 461 Hz (ball-cavity bar) and 456 Hz (solid bar);
- the published absorber (m_a = 0.39 kg, k_a = 1.05 MN/m, c_a = 505 N s/m),
  placed at z_a = 96 mm, and one retained mode.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np

from boringbar._validate import (
    ParameterError,
    check_bool,
    check_choice,
    check_int,
    check_range,
)
from boringbar.model.bar import ModalModel
from boringbar.model.dampers import (
    NO_FRICTION,
    Friction,
    ImpactDamper,
    TunedMassDamper,
    sims_tuning,
)
from boringbar.model.materials import MATERIALS
from boringbar.model.oriented import APPLIES_TO, CutGeometry, oriented_model, unused_keys
from boringbar.model.system_file import SystemSpec, parse_system, published_system

PRESETS = ("physical", "paper")
BAR_KINDS = ("solid", "ball", "tmd")
BALLS = tuple(MATERIALS)
#: "given" (alias "published"): the absorber the system file gives (the published
#: absorber in the shipped file); "den-hartog": Den Hartog's optimum for the FRF
#: magnitude; "sims": Sims' equal-real-trough optimum for chatter
TMD_DESIGNS = ("given", "published", "den-hartog", "sims")
#: How the published rolling-resistance number is read (make_system's friction_reading):
#: "paper", as the paper computed it (nu in metres: 20.4 N for the 26 g ball), or
#: "rolling", as a rolling-resistance length in mm (0.0204 N)
FRICTION_READINGS = ("paper", "rolling")

#: The published readings, by name, with the reason each exists.
READINGS = {
    "paper-friction-force": "friction force as computed in the paper: the number 0.6 (mm) "
    "used with r_m in metres, F_c = 0.6 m g / 0.0075 (20.4 N for 26 g)",
    "printed-bar-reaction": "bar reaction as printed: +psi_d F_b on the bar instead of "
    "-psi_d F_b (breaks action and reaction; the energy balance reports the work it injects)",
    "calibrated-stiffness": "stiffness calibrated to the published frequencies: K scaled so "
    "f1 = 461 Hz (ball-cavity bar) / 456 Hz (solid bar), masses and mode shape kept",
}


@dataclass(frozen=True, eq=False)
class System:
    """A bar (modal model of the host bar) and its damper (or none); ``preset`` names
    the preset that built it ("custom" otherwise), ``readings`` the published
    readings it applies (:data:`READINGS`) and ``spec`` the system file it was
    built from.  :meth:`to_dict` is what results carry; :meth:`from_dict` of it
    rebuilds the same system, bit for bit."""

    bar: ModalModel
    damper: ImpactDamper | TunedMassDamper | None = None
    preset: str = "custom"
    readings: tuple[str, ...] = ()
    #: the system file it was built from (None: built by hand)
    spec: SystemSpec | None = None

    def __post_init__(self):
        if self.damper is not None and not isinstance(self.damper,
                                                      (ImpactDamper, TunedMassDamper)):
            raise ParameterError(f"damper = {self.damper!r} must be an ImpactDamper, a "
                                 "TunedMassDamper or None")

    @property
    def kind(self) -> str:
        """"solid", "ball", "locked" (ball fixed to the bar) or "tmd"."""
        if self.damper is None:
            return "solid"
        if isinstance(self.damper, TunedMassDamper):
            return "tmd"
        return "locked" if self.damper.locked else "ball"

    def linear_host(self) -> System:
        """The linear bar a small vibration sees (the onset of chatter): for a free ball
        off its walls, the bar carrying it where friction holds it (a vibration so small
        that the bar's acceleration at the cavity is below what the friction can give
        the ball moves the ball with the bar: the locked ball), the bare cavity bar where
        there is no friction (the ball does not act); else the system itself."""
        if self.kind != "ball":
            return self
        if self.damper.motion == "roll" and self.damper.mu_static > 0:
            # rolling without slip, the floor carries 2/7 of the ball with the bar
            return System(self.bar, replace(self.damper, locked=True, motion="slide",
                                            mass_kg=self.damper.mass_kg * 2 / 7),
                          self.preset, self.readings)
        if self.damper.friction_force_n > 0:
            return System(self.bar, replace(self.damper, locked=True), self.preset,
                          self.readings)
        return System(self.bar, None, self.preset, self.readings)

    @property
    def reference_frequency_rad_s(self) -> float:
        """omega_n (rad/s) of the host bar without the damper's mass: what
        Omega/omega_n refers to (docs/model.md, section 6)."""
        return self.bar.natural_frequency_rad_s

    def to_dict(self) -> dict:
        return {
            "kind": self.kind,
            "preset": self.preset,
            "readings": list(self.readings),
            "bar": self.bar.to_dict(),
            "damper": None if self.damper is None else self.damper.to_dict(),
            "system_file": None if self.spec is None else self.spec.to_dict(),
        }

    @classmethod
    def from_dict(cls, d: dict) -> System:
        """The system a result's ``system`` attribute (:meth:`to_dict`) describes."""
        damper = d.get("damper")
        if damper is not None:
            damper = (TunedMassDamper.from_dict(damper) if damper["type"] == "tmd"
                      else ImpactDamper.from_dict(damper))
        spec = d.get("system_file")
        return cls(ModalModel.from_dict(d["bar"]), damper, d.get("preset", "custom"),
                   tuple(d.get("readings", ())),
                   None if spec is None else parse_system(spec, "<result>"))


@functools.cache
def published_system_spec() -> SystemSpec:
    """The published bar's system file, read once (the presets' default)."""
    return published_system()


def make_system(bar: str = "ball", preset: str = "physical", *, gap_m: float | None = None,
                friction: bool = True, ball: str | None = None,
                restitution: float | None = None, n_modes: int | None = None,
                friction_number: float | None = None, friction_force_n: float | None = None,
                friction_reaction: str | None = None, friction_reading: str | None = None,
                locked: bool = False,
                tmd_mass_kg: float | None = None, z_absorber_m: float | None = None,
                tmd_design: str | None = None, modal: ModalModel | None = None,
                static_ratio: float | None = None, spec: SystemSpec | None = None,
                contact: str | None = None,
                contact_stiffness_n_m1_5: float | None = None, planes: int | None = None,
                cut_geometry: CutGeometry | None = None, motion: str | None = None,
                mu_static: float | None = None, mu_kinetic: float | None = None) -> System:
    """Build one of the three bars of a system file under a preset, with explicit
    overrides.

    ``spec``: the system file (:func:`~boringbar.model.system_file.load_system`;
    default: the published bar, shipped with the package).  ``bar``: "solid" (the
    file's bar without its cavity), "ball" (with the cavity and its ball;
    ``locked`` fixes the ball) or "tmd" (without the cavity, with the file's
    absorber); ``preset``: "physical" or "paper" (:data:`READINGS`).  Every
    other argument left None takes the file's value.  Ball: ``gap_m`` (m), ``ball``
    (a material of :data:`BALLS`; its mass then follows from its density and the
    file's diameter), ``restitution``; ``friction`` on/off;
    ``friction_reaction``: "reciprocal" (physical) or "printed" (the published
    sign of the bar's reaction); ``friction_number`` is the published
    rolling-resistance number (0.6 nominal, read as the preset reads it);
    ``friction_reading``: how the published number is read, "paper" (as the paper
    computed it: nu in metres, 20.4 N for the 26 g ball; the paper preset's
    default) or "rolling" (nu in mm, 0.0204 N; the physical preset's default);
    ``friction_force_n`` (N) overrides the file's friction when friction is on.
    ``n_modes``: retained bending modes (default: the file's, else 1 paper, 2
    physical); ``tmd_mass_kg`` (kg) at ``z_absorber_m`` (m from the clamp);
    ``tmd_design``: the file's tuning (physical default), "given" (paper
    default where the file gives the absorber's stiffness and damping;
    "published" is the same) or "den-hartog", "sims" (Sims' equal-real-trough
    tuning, for chatter).  ``modal`` replaces the FE model (e.g.
    :meth:`ModalModel.from_tap_test`).  ``static_ratio``: F_s / F_c of true
    stick-slip (exact integrator only; see :class:`Friction`).  ``contact``: the
    ball's contact law, "impact" or "hertz", and ``contact_stiffness_n_m1_5`` (N/m^1.5)
    a Hertz contact's K (default: the file's, else Hertz's from the materials; see
    :class:`ImpactDamper`).  ``planes``: 2 for the bar's modes in both bending planes
    under the oriented cut ``cut_geometry`` (a :class:`CutGeometry`, docs/model.md,
    section 4.7; a key the bar does not use is refused, unless it is the file's:
    oriented.APPLIES_TO); ``n_modes`` then counts the modes of each plane.
    Default: the file's ``[orientation]``, else one plane.  ``motion``: the ball
    "slide"s (the published model) or "roll"s, with the floor friction coefficients
    ``mu_static`` >= ``mu_kinetic`` (docs/model.md, section 2.7); default the file's.
    Another bar's argument (``gap_m`` for the solid bar) is refused: it would do nothing.
    """
    _check_kind(bar, preset)
    _check_bar_args(bar, locals())
    spec = published_system_spec() if spec is None else spec
    paper = preset == "paper"
    built, readings = _modal(spec, bar, paper, n_modes, z_absorber_m, modal)
    modal = _planes(spec, bar, built, planes, cut_geometry, modal is None, z_absorber_m)
    if bar == "solid":
        return System(modal, None, preset, tuple(readings), spec)
    if bar == "tmd":
        tmd = _tmd(spec, modal, paper, tmd_mass_kg, tmd_design)
        return System(modal, tmd, preset, tuple(readings), spec)
    if spec.ball is None:
        raise ParameterError(f"bar = 'ball' needs a [cavity] and a [ball] in the system file "
                             f"{spec.source}")
    reading = friction_reading or ("paper" if paper else "rolling")
    check_choice("friction_reading", reading, FRICTION_READINGS)
    reaction = (friction_reaction or spec.ball.friction_reaction
                or ("printed" if paper else "reciprocal"))
    fr = _friction(spec, reading == "paper", friction, friction_number, friction_force_n,
                   reaction, static_ratio, readings)
    b = spec.ball
    gap = b.gap_m if gap_m is None else gap_m
    check_range("gap_m", gap, 0.0, spec.max_gap(), lo_open=True,
                unit="m", why="at most the cavity's depth less the ball")
    material = b.material if ball is None else check_choice("ball", ball, BALLS)
    damper = ImpactDamper.ball(
        material, gap_m=gap, restitution=b.restitution if restitution is None else restitution,
        friction=fr, diameter_m=b.diameter_m,
        mass_kg=b.mass_kg if material == b.material else None, locked=locked,
        contact=contact or b.contact, plug_material=b.plug_material,
        motion=motion or b.motion,
        mu_static=b.mu_static if mu_static is None else mu_static,
        mu_kinetic=b.mu_kinetic if mu_kinetic is None else mu_kinetic,
        contact_stiffness_n_m1_5=(b.contact_stiffness_n_m1_5 if contact_stiffness_n_m1_5 is None
                                  else contact_stiffness_n_m1_5))
    _check_unused(damper, mu_static=mu_static, mu_kinetic=mu_kinetic,
                  contact_stiffness_n_m1_5=contact_stiffness_n_m1_5)
    return System(modal, damper, preset, tuple(readings), spec)


def _check_kind(bar, preset) -> None:
    if isinstance(bar, SystemSpec):
        raise TypeError(f"bar = the system file {bar.name!r}: make_system's first argument "
                        "is the bar's kind ('solid', 'ball' or 'tmd'); give the file as "
                        "spec=, e.g. make_system('ball', spec=spec)")
    check_choice("bar", bar, BAR_KINDS)
    check_choice("preset", preset, PRESETS)


#: make_system's arguments of one bar's damper alone (None: not given).
BALL_ARGS = ("gap_m", "ball", "restitution", "friction_number", "friction_force_n",
             "friction_reaction", "friction_reading", "static_ratio", "contact",
             "contact_stiffness_n_m1_5", "motion", "mu_static", "mu_kinetic")
TMD_ARGS = ("tmd_mass_kg", "tmd_design")


def _check_bar_args(bar: str, args: dict) -> None:
    """Refuse an argument of another bar's damper (a gap given to the solid bar): it
    would change nothing.  ``friction`` and ``locked`` must be bools."""
    check_bool("friction", args["friction"])
    if check_bool("locked", args["locked"]) and bar != "ball":
        raise ParameterError(f"locked = True applies to the ball bar, not bar = {bar!r}")
    for name in (BALL_ARGS if bar != "ball" else ()) + (TMD_ARGS if bar != "tmd" else ()):
        if args[name] is not None:
            owner = "ball" if name in BALL_ARGS else "tmd"
            raise ParameterError(f"{name} = {args[name]!r} applies to the {owner} bar, not "
                                 f"bar = {bar!r}")


def _check_unused(damper: ImpactDamper, **given) -> None:
    """Refuse a rolling ball's floor friction given to a sliding ball, and a Hertz
    contact's stiffness given to the impact law: each would change nothing.  (A system
    file may still describe them: they are the hardware's, and taken once the motion or
    the contact law selects them.)"""
    for name, value in given.items():
        if value is None:
            continue
        if name.startswith("mu_") and damper.motion != "roll":
            raise ParameterError(f"{name} = {value!r} is a rolling ball's floor friction, and "
                                 "this ball slides: give motion = 'roll' (--ball-motion "
                                 f"roll), or leave {name} out")
        if name == "contact_stiffness_n_m1_5" and damper.contact != "hertz":
            raise ParameterError(f"contact_stiffness_n_m1_5 = {value!r} is a Hertz contact's "
                                 "stiffness, and this ball meets its plugs by the impact law: "
                                 "give contact = 'hertz' (--contact hertz), or leave it out")


def _planes(spec: SystemSpec, bar: str, modal: ModalModel, planes, geometry, own: bool,
            z_absorber) -> ModalModel:
    """``modal`` in both bending planes under the oriented cut, where asked.  Its second
    plane is a finite-element bar of its own where ``modal`` is the file's (``own``, built
    with the absorber at ``z_absorber``) and the planes differ by more than a stiffness
    ratio: the ball bar's across its cavity, or a bar's whose sections give their second
    moments a plane."""
    planes = spec.planes if planes is None else check_int("planes", planes, 1, 2)
    if geometry is not None and not isinstance(geometry, CutGeometry):
        raise TypeError(f"cut_geometry = {geometry!r} must be a CutGeometry "
                        "(bb.CutGeometry(force_ratio=..., lead_angle_deg=..., ...))")
    _check_geometry_keys(spec, bar, geometry)
    if planes == 1:
        if geometry is not None:
            raise ParameterError("cut_geometry applies to a bar of two bending planes: give "
                                 "planes = 2")
        return modal
    geometry = spec.orientation if geometry is None else geometry
    cavity = bar == "ball" and spec.cavity is not None
    across = (_across(spec, modal, z_absorber, cavity)
              if own and (cavity or spec.bar.plane_moments) else None)
    if across is not None and not cavity and geometry.stiffness_ratio != 1.0:
        raise ParameterError(f"cut_geometry's stiffness_ratio = {geometry.stiffness_ratio:g}: "
                             f"the sections of {spec.name!r} give each plane's second moments "
                             "(second_moments_mm4); leave stiffness_ratio out")
    return oriented_model(modal, geometry, None if across is None else across(), cavity)


def _check_geometry_keys(spec: SystemSpec, bar: str, geometry) -> None:
    """Refuse a key of ``geometry`` that ``bar`` does not use (oriented.APPLIES_TO), where
    it is given and not as the system file describes the hardware (the file's keys
    describe every bar it builds, each taking its own)."""
    if geometry is None:
        return
    for key in unused_keys(geometry, bar):
        value = getattr(geometry, key)
        if value != getattr(spec.orientation, key):
            users = " and ".join(APPLIES_TO[key])
            why = (" (the ball bar's planes are its cavity's section bent along and across "
                   "the cavity)" if bar == "ball" else " (nothing moves in a solid bar)")
            raise ParameterError(f"cut_geometry's {key} = {value:g} applies to the {users} "
                                 f"bars, not to bar = {bar!r}{why}; leave it out")


def _across(spec: SystemSpec, plane: ModalModel, z_absorber, cavity: bool):
    """The bar's modes bent in its second plane (a ``cavity`` bar's across the ball's
    direction), as ``plane`` was built (its modes, damping, and the paper preset's
    stiffness calibration): a callable, so that a bar of one plane does not compute
    them."""
    def build() -> ModalModel:
        other = spec.modal(cavity, plane.n_modes, z_absorber, across=True)
        other = replace(other, damping_ratio=plane.damping_ratio)
        scale = plane.info.get("stiffness_scale", 1.0)
        return replace(other, stiffness_n_m=other.stiffness_n_m * scale)
    return build


def _modal(spec: SystemSpec, bar: str, paper: bool, n_modes, z_absorber, modal):
    """The host bar's modal model and the readings it applies."""
    if n_modes is None:
        n_modes = spec.n_modes or (1 if paper else 2)
    check_range("n_modes", n_modes, 1, 8)
    readings: list[str] = []
    cavity = bar == "ball"
    if modal is None:
        modal = spec.modal(cavity, int(n_modes), z_absorber)
        calibration = spec.calibration.get("ball" if cavity else "solid")
        if paper and calibration is not None:
            modal = modal.with_first_frequency(calibration)
            readings.append("calibrated-stiffness")
    elif n_modes < modal.n_modes:
        modal = modal.truncated(int(n_modes))
    return modal, readings


def _tmd(spec: SystemSpec, modal: ModalModel, paper: bool, mass, design) -> TunedMassDamper:
    t = spec.tmd
    if t is None and mass is None:
        raise ParameterError(f"bar = 'tmd' needs a [tmd] in the system file {spec.source} "
                             "(or a tmd_mass_kg)")
    given = t is not None and t.stiffness_n_m is not None
    default = "den-hartog" if t is None else ("given" if paper and given else t.tuning)
    design = check_choice("tmd_design", design or default, TMD_DESIGNS)
    mass = t.mass_kg if mass is None else mass
    if design in ("given", "published"):
        if not given:
            raise ParameterError(f"tmd_design = {design!r} needs the absorber's stiffness_n_m "
                                 f"and damping_n_s_m in the system file {spec.source}")
        return TunedMassDamper(t.mass_kg, t.stiffness_n_m, t.damping_n_s_m, modal.z_absorber_m,
                               t.label)
    if design == "sims":
        return sims_tuning(mass, modal)
    return TunedMassDamper.den_hartog(mass, modal)


def _friction(spec: SystemSpec, paper_number: bool, on: bool, number, force, reaction,
              static_ratio, readings: list) -> Friction:
    """The ball's friction: the file's, or the overrides; appends the readings.
    ``paper_number``: the published number read as the paper computed it."""
    b = spec.ball
    check_choice("friction_reaction", reaction, ("reciprocal", "printed"))
    ratio = b.static_ratio if static_ratio is None else static_ratio
    if not on or (b.friction_kind == "none" and number is None and force is None):
        return NO_FRICTION
    if force is not None:
        fr = Friction("force", force, reaction, ratio)
    elif number is not None or b.friction_kind == "published-number":
        number = b.friction_value if number is None else number
        check_range("friction_number", number, 0.0, 100.0)
        if paper_number:
            fr = Friction("paper-number", number, reaction, ratio)
            readings.append("paper-friction-force")
        else:
            fr = Friction("rolling", number * 1e-3, reaction, ratio)
    else:
        value = b.friction_value * (1e-3 if b.friction_kind == "rolling" else 1.0)
        fr = Friction(b.friction_kind, value, reaction, ratio)
    if reaction == "printed":
        readings.append("printed-bar-reaction")
    return fr


def variants(spec: SystemSpec | None = None, preset: str = "physical") -> dict[str, System]:
    """The bars one system file describes, side by side, under ``preset``: "solid" (the
    bar without its cavity) always, "ball" (with its cavity and ball) if the file has a
    ball, "tmd" (with its absorber) if it has one; ``spec`` the file
    (:func:`~boringbar.model.system_file.load_system`; default the published bar).
    The mapping is what the analyses take: ``bb.sweep(bb.variants(spec))`` labels
    its cases solid, ball and tmd."""
    spec = spec or published_system_spec()
    kinds = ["solid"] + (["ball"] if spec.ball else []) + (["tmd"] if spec.tmd else [])
    return {kind: make_system(kind, preset, spec=spec) for kind in kinds}


def describe_modes(system: System) -> dict:
    """The modal model of ``system``'s host bar, as ``boringbar modes`` prints it:
    ``modes`` (per mode: frequency_hz, modal_mass_kg and modal_stiffness_n_m
    referred to the tip, damping_ratio, psi_tip, psi_ball, psi_absorber, each
    psi divided by psi_tip; None where the file has no ball or no absorber) and
    ``tip_static_stiffness_n_m``: from the full
    finite-element model (every mode, the clamp's springs, the paper preset's
    calibration) when the bar comes from a system file, else the retained
    modes' sum.  A bar of two planes gives each mode in its own plane (``plane_deg``, from
    the radial direction; its shapes before the cut and the ball project them) and
    ``built_plane_deg``, the plane the finite-element bar was built in, whose static
    stiffness it is."""
    m = system.bar
    raw = m.info.get("plane_modes")  # two planes: each mode in its own plane
    tip, ball, absorber = ((m.psi_tip, m.psi_damper, m.psi_absorber) if raw is None else
                           (np.asarray(raw[k]) for k in ("psi_tip", "psi_ball", "psi_absorber")))
    scale = tip**2
    modes = [{"frequency_hz": float(m.omegas_rad_s[i] / (2 * math.pi)),
              "modal_mass_kg": float(m.mass_kg[i] / scale[i]),
              "modal_stiffness_n_m": float(m.stiffness_n_m[i] / scale[i]),
              "damping_ratio": float(m.damping_ratio[i]),
              "psi_tip": 1.0, "psi_ball": float(ball[i] / tip[i]),
              "psi_absorber": float(absorber[i] / tip[i]),
              **({} if raw is None else {"plane_deg": raw["plane_deg"][i]})}
             for i in range(m.n_modes)]
    spec = system.spec
    for name, missing in (("psi_ball", spec is not None and spec.cavity is None),
                          ("psi_absorber", spec is not None and spec.tmd is None)):
        if missing and m.source.startswith("fe"):  # no such point on this bar
            for mode in modes:
                mode[name] = None
    built = (np.ones(m.n_modes, bool) if raw is None  # the modes of the FE bar's plane
             else np.isclose(raw["plane_deg"], raw["built_deg"]))
    if system.spec is not None and m.source.startswith("fe"):
        fe = system.spec.stepped_bar(system.kind in ("ball", "locked"))
        static = fe.static_tip_stiffness() * m.info.get("stiffness_scale", 1.0)
        static_from = "finite-element model"
    else:
        static = 1.0 / float(np.sum(scale[built] / m.stiffness_n_m[built]))
        static_from = "retained modes"
    if raw is not None:
        static_from += f", in the plane at {raw['built_deg']:g} deg"
    return {"modes": modes, "tip_static_stiffness_n_m": static,
            "tip_static_stiffness_from": static_from, "source": m.source,
            "z_ball_m": m.z_damper_m, "z_absorber_m": m.z_absorber_m,
            **({} if raw is None else {"built_plane_deg": raw["built_deg"]})}
