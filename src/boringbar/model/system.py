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

from dataclasses import dataclass

from boringbar._validate import ParameterError, check_choice, check_range
from boringbar.model.bar import ABSORBER_POSITION, ModalModel, published_bar
from boringbar.model.dampers import (
    NO_FRICTION,
    PUBLISHED_FRICTION_NUMBER,
    Friction,
    ImpactDamper,
    TunedMassDamper,
    sims_tuning,
)

PRESETS = ("physical", "paper")
BAR_KINDS = ("solid", "ball", "tmd")
BALLS = ("carbide", "steel")
PUBLISHED_F1_HZ = {"ball": 461.0, "solid": 456.0}
PUBLISHED_TMD_MASS = 0.39
#: "published": the published absorber; "den-hartog": Den Hartog's optimum for
#: the FRF magnitude; "sims": Sims' equal-real-trough optimum for chatter
TMD_DESIGNS = ("published", "den-hartog", "sims")

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
    the preset that built it ("custom" otherwise) and ``readings`` the published
    readings it applies (:data:`READINGS`)."""

    bar: ModalModel
    damper: ImpactDamper | TunedMassDamper | None = None
    preset: str = "custom"
    readings: tuple[str, ...] = ()

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

    @property
    def reference_frequency(self) -> float:
        """omega_n (rad/s) of the host bar without the damper's mass: what
        Omega/omega_n refers to (docs/model.md, section 6)."""
        return self.bar.natural_frequency

    def to_dict(self) -> dict:
        return {
            "kind": self.kind,
            "preset": self.preset,
            "readings": list(self.readings),
            "bar": self.bar.to_dict(),
            "damper": None if self.damper is None else self.damper.to_dict(),
        }


def make_system(bar: str = "ball", preset: str = "physical", *, gap: float = 0.5e-3,
                friction: bool = True, ball: str = "carbide", restitution: float = 0.7,
                n_modes: int | None = None, friction_number: float | None = None,
                friction_force: float | None = None, friction_reaction: str | None = None,
                locked: bool = False, tmd_mass: float = PUBLISHED_TMD_MASS,
                z_absorber: float = ABSORBER_POSITION, tmd_design: str | None = None,
                modal: ModalModel | None = None, static_ratio: float = 1.0) -> System:
    """Build one of the three bars under a preset, with explicit overrides.

    ``bar``: "solid", "ball" (ball damper; ``locked`` fixes the ball) or
    "tmd"; ``preset``: "physical" or "paper" (:data:`READINGS`).  Ball: ``gap``
    (m), ``ball`` ("carbide", "steel"), ``restitution``; ``friction`` on/off;
    ``friction_reaction``: "reciprocal" (physical) or "printed" (the published
    sign of the bar's reaction); ``friction_number`` is the published
    rolling-resistance number (0.6 nominal, read as the preset reads it);
    ``friction_force`` (N) overrides the number when friction is on.
    ``n_modes``: retained bending modes (default 1 paper, 2 physical);
    ``tmd_mass`` (kg) at ``z_absorber`` (m from the clamp);
    ``tmd_design``: "den-hartog" (physical default), "published" (paper
    default) or "sims" (Sims' equal-real-trough tuning, for chatter).  ``modal`` replaces
    the FE model (e.g. :meth:`ModalModel.from_tap_test`).  ``static_ratio``:
    F_s / F_c of true stick-slip (exact integrator only; see :class:`Friction`).
    """
    check_choice("bar", bar, BAR_KINDS)
    check_choice("preset", preset, PRESETS)
    paper = preset == "paper"
    if n_modes is None:
        n_modes = 1 if paper else 2
    check_range("n_modes", n_modes, 1, 8)
    readings: list[str] = []
    cavity = bar == "ball"
    if modal is None:
        modal = published_bar(cavity=cavity, n_modes=int(n_modes), z_absorber=z_absorber)
        if paper:
            modal = modal.with_first_frequency(PUBLISHED_F1_HZ["ball" if cavity else "solid"])
            readings.append("calibrated-stiffness")
    elif n_modes < modal.n_modes:
        modal = modal.truncated(int(n_modes))

    if bar == "solid":
        return System(modal, None, preset, tuple(readings))
    if bar == "tmd":
        design = tmd_design or ("published" if paper else "den-hartog")
        check_choice("tmd_design", design, TMD_DESIGNS)
        if design == "published":
            tmd = TunedMassDamper.published(position=modal.z_absorber)
        elif design == "sims":
            tmd = sims_tuning(tmd_mass, modal)
        else:
            tmd = TunedMassDamper.den_hartog(tmd_mass, modal)
        return System(modal, tmd, preset, tuple(readings))

    check_choice("ball", ball, BALLS)
    reaction = friction_reaction or ("printed" if paper else "reciprocal")
    check_choice("friction_reaction", reaction, ("reciprocal", "printed"))
    if not friction:
        fr = NO_FRICTION
    elif friction_force is not None:
        fr = Friction("force", friction_force, reaction, static_ratio)
    else:
        number = PUBLISHED_FRICTION_NUMBER if friction_number is None else friction_number
        check_range("friction_number", number, 0.0, 100.0)
        if paper:
            fr = Friction("paper-number", number, reaction, static_ratio)
            readings.append("paper-friction-force")
        else:
            fr = Friction("rolling", number * 1e-3, reaction, static_ratio)
    if fr.kind != "none" and reaction == "printed":
        readings.append("printed-bar-reaction")
    damper = ImpactDamper.ball(ball, gap=gap, restitution=restitution, friction=fr,
                               locked=locked)
    return System(modal, damper, preset, tuple(readings))
