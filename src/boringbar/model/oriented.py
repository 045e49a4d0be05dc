"""Two bending planes and an oriented cut (docs/model.md, section 4.7).

The bar bends in two principal planes of its section.  In the section at the tip the
directions are measured from the radial direction r (the published model's one
direction: the chip thickness's, and the force's, in a cut along the feed) toward the
tangential t (the cutting speed's direction).  A mode of principal plane p moves the
tip along d_p = (cos phi_p, sin phi_p), phi_2 = phi_1 + 90 degrees.

The cut: the chip thickness changes with the tip's radial motion by cos kappa (kappa the
lead angle, between the cutting edge's normal and the radial direction in the plane of
the bar's axis; 0 is the published cut), and the force is
F = b h (Kr cos kappa r + Kt t): the edge-normal force Kr b h has the radial part
cos kappa (its axial part acts along the stiff bar), the tangential force is Kt b h.
With rho = Kt / Kr the kernel keeps its scalar law f = Kr b h, and each mode j of plane
p enters it by

    psi_tip,j   = psi_L,j cos kappa cos phi_p              (W: what the chip reads)
    psi_force,j = psi_L,j (cos kappa cos phi_p + rho sin phi_p)
    psi_damper,j = psi_d,j cos(phi_p - alpha)              (the ball along the cavity)

alpha the cavity's axis (``hole_angle_deg``; the absorber too moves along it).  Where
rho = 0 and kappa = 0 and one plane is radial this is the published bar.  The
oriented frequency response W / (Kr b h) = sum_j psi_tip,j psi_force,j / (K_j - w^2
M_j + i w C_j) is then Tlusty's oriented transfer function, and the classical lobes
follow from it unchanged (reference/stability.py).

The second plane's modes are the first's with the bending stiffness EI scaled by
``stiffness_ratio`` (the same masses and shapes, frequencies times its square root):
exact for a section whose two second moments keep one ratio along the bar (a round bar:
1; flats or a bore across the section: the ratio of their I).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from boringbar._validate import ParameterError, check_range
from boringbar.model.bar import ModalModel

#: Projections smaller than this (a cosine of 90 degrees in floating point) are zero.
ZERO_PROJECTION = 1e-12
#: Each CutGeometry field's range, (low, high, low open, high open, unit, why): the one
#: the class, the command line's options and the system file's keys check.
GEOMETRY_RANGES = {
    "force_ratio": (0.0, 100.0, False, False, "", "Kt / Kr"),
    "lead_angle_deg": (0.0, 90.0, False, True, "degrees",
                       "at 90 the tip's radial motion no longer changes the chip, and the "
                       "model has no regenerative chatter"),
    "hole_angle_deg": (-90.0, 90.0, False, False, "degrees",
                       "the cavity's axis through the section"),
    "principal_angle_deg": (-90.0, 90.0, False, False, "degrees", ""),
    "stiffness_ratio": (0.0, 1e3, True, False, "", "EI_2 / EI_1"),
}


def check_geometry(field: str, value, name: str | None = None) -> float:
    """``value`` of CutGeometry's ``field`` in its range (:data:`GEOMETRY_RANGES`), or a
    ParameterError naming ``name`` (default: the field)."""
    lo, hi, lo_open, hi_open, unit, why = GEOMETRY_RANGES[field]
    return check_range(name or field, value, lo, hi, lo_open=lo_open, hi_open=hi_open,
                       unit=unit, why=why)


@dataclass(frozen=True)
class CutGeometry:
    """An oriented cut on a bar of two bending planes (module docstring; angles in
    degrees).  ``force_ratio``: Kt / Kr >= 0, the tangential over the edge-normal
    cutting coefficient (about 2-4 in practice: Kt is the main force); ``lead_angle_deg``
    kappa in [0, 90): 0 the published radial cut; ``hole_angle_deg`` in [-90, 90]: the
    cavity's axis, along which the ball moves; ``principal_angle_deg`` in [-90, 90]:
    the bar's first principal bending plane; ``stiffness_ratio`` > 0: EI of the second
    plane over the first's."""

    force_ratio: float = 0.0
    lead_angle_deg: float = 0.0
    hole_angle_deg: float = 0.0
    principal_angle_deg: float = 0.0
    stiffness_ratio: float = 1.0

    def __post_init__(self):
        for field in GEOMETRY_RANGES:
            check_geometry(field, getattr(self, field))

    def to_dict(self) -> dict:
        return {"force_ratio": self.force_ratio, "lead_angle_deg": self.lead_angle_deg,
                "hole_angle_deg": self.hole_angle_deg,
                "principal_angle_deg": self.principal_angle_deg,
                "stiffness_ratio": self.stiffness_ratio}


#: The bars each of the section's keys describes: a ball bar's planes are its cavity's
#: section bent each way (along and across the cavity), so the principal plane and the
#: stiffness ratio describe a bar without one; the cavity's axis concerns a bar with
#: something moving in it (the ball, or the absorber of a TMD).
APPLIES_TO = {"hole_angle_deg": ("ball", "tmd"), "principal_angle_deg": ("solid", "tmd"),
              "stiffness_ratio": ("solid", "tmd")}

#: The section's keys in words (geometry_words).
_WORDS = {"force_ratio": "Kt/Kr {:g}", "lead_angle_deg": "lead angle {:g} deg",
          "hole_angle_deg": "cavity at {:g} deg",
          "principal_angle_deg": "principal plane at {:g} deg", "stiffness_ratio": "EI ratio {:g}"}


def geometry_words(geometry: dict, bar: str) -> str:
    """'Kt/Kr 2.5, lead angle 30 deg, cavity at 20 deg': an oriented cut's geometry
    (:meth:`CutGeometry.to_dict`) as ``bar`` uses it, for titles and summaries (the
    stiffness ratio where it is not 1)."""
    used = [fmt.format(geometry[k]) for k, fmt in _WORDS.items()
            if k in geometry and bar in APPLIES_TO.get(k, (bar,))
            and not (k == "stiffness_ratio" and geometry[k] == 1.0)]
    return ", ".join(used)


def unused_keys(geometry: CutGeometry, bar: str) -> list[str]:
    """The keys of ``geometry`` set away from their defaults that ``bar`` does not use
    (:data:`APPLIES_TO`)."""
    default = CutGeometry()
    return [k for k, bars in APPLIES_TO.items()
            if bar not in bars and getattr(geometry, k) != getattr(default, k)]


def for_bar(geometry: CutGeometry, bar: str, base: CutGeometry) -> CutGeometry:
    """``geometry`` with the keys ``bar`` does not use as ``base`` (the system file's
    orientation) has them: the one cut of a comparison of bars, as each bar takes it."""
    return replace(geometry, **{k: getattr(base, k) for k in unused_keys(geometry, bar)})


def _clean(values: np.ndarray) -> np.ndarray:
    scale = max(float(np.max(np.abs(values))), 1e-300)
    return np.where(np.abs(values) < ZERO_PROJECTION * scale, 0.0, values)


def oriented_model(plane: ModalModel, geometry: CutGeometry,
                   across: ModalModel | None = None, cavity: bool = True) -> ModalModel:
    """The bar of ``plane``'s modes in both principal planes under the oriented cut
    ``geometry`` (module docstring): 2 n modes, those of the plane nearer the radial
    direction first (its first mode carries the tip's normalisation).

    ``across``: the second plane's own modal model, for a bar whose sections make its
    planes differ: with ``cavity``, the FE bar bent across the ball's direction, its
    planes along and across the cavity (phi_1 = ``hole_angle_deg``;
    ``principal_angle_deg`` and ``stiffness_ratio`` describe a bar without a cavity);
    without, a bar whose sections give their second moments a plane, at
    ``principal_angle_deg``.  None: ``plane``'s modes with EI times
    ``stiffness_ratio``, at ``principal_angle_deg``."""
    g = geometry
    if across is not None and across.n_modes != plane.n_modes:
        raise ParameterError(f"the planes' modal models have {plane.n_modes} and "
                             f"{across.n_modes} modes; give each the same count")
    if 2 * plane.n_modes > 8:
        raise ParameterError(f"two bending planes of {plane.n_modes} modes each are "
                             f"{2 * plane.n_modes} modes; the core takes at most 8 (give "
                             "n_modes <= 4)")
    kappa, alpha = math.radians(g.lead_angle_deg), math.radians(g.hole_angle_deg)
    first = g.hole_angle_deg if across is not None and cavity else g.principal_angle_deg
    phis = [math.radians(first), math.radians(first) + math.pi / 2]
    models = [plane, across if across is not None else
              replace(plane, stiffness_n_m=plane.stiffness_n_m * g.stiffness_ratio)]
    order = sorted(range(2), key=lambda p: -abs(math.cos(phis[p])))
    parts = []
    # each mode in its own plane, for the modes' table (``plane``'s at built_deg)
    raw = {"plane_deg": [], "psi_tip": [], "psi_ball": [], "psi_absorber": [],
           "built_deg": math.degrees(phis[0])}
    for p in order:
        phi, m = phis[p], models[p]
        shapes = ([math.degrees(phi)] * m.n_modes, m.psi_tip, m.psi_damper, m.psi_absorber)
        for key, values in zip(list(raw)[:4], shapes, strict=True):
            raw[key] += [float(v) for v in values]
        parts.append((m.mass_kg, m.stiffness_n_m, m.damping_ratio,
                      m.psi_tip * math.cos(kappa) * math.cos(phi),
                      m.psi_tip * (math.cos(kappa) * math.cos(phi)
                                   + g.force_ratio * math.sin(phi)),
                      m.psi_damper * math.cos(phi - alpha),
                      m.psi_absorber * math.cos(phi - alpha)))
    columns = (np.concatenate(c) for c in zip(*parts, strict=True))
    mass, stiff, zeta, tip, force, damper, absorber = columns
    info = dict(plane.info, planes=2, cut_geometry=g.to_dict(), plane_modes=raw)
    return ModalModel(mass, stiff, zeta, _clean(tip), _clean(damper), _clean(absorber),
                      plane.z_damper_m, plane.z_absorber_m, f"{plane.source}+two-planes",
                      info, _clean(force))
