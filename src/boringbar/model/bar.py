"""The bar: a stepped Euler-Bernoulli cantilever reduced to a few bending modes.

docs/model.md, section 1. The finite-element model uses Hermite-cubic beam elements
with consistent mass, clamped at z = 0 and free at z = L (the cutting end).
Nodes sit at every section boundary and at every point where a mode-shape
value is wanted (the ball at z_d, the absorber at z_a), so psi(z_d) and
psi(z_a) are nodal values, not interpolations.

A user with a tap test instead of drawings builds a :class:`ModalModel`
directly with :meth:`ModalModel.from_tap_test`.
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg

from boringbar._validate import ParameterError, check_choice, check_positive, check_range
from boringbar.model.linalg import one_blas_thread
from boringbar.model.materials import MATERIALS

#: Published geometry (docs/model.md, section 1), metres.
BAR_LENGTH = 0.200
BALL_POSITION = 0.12955
ABSORBER_POSITION = 0.096
STEEL_E = MATERIALS["steel"].youngs_modulus
STEEL_RHO = MATERIALS["steel"].density
DAMPING_RATIO = 0.01


@dataclass(frozen=True)
class Section:
    """One prismatic piece of the bar, from ``start_m`` to ``end_m`` (m, from the clamp).

    ``diameter_m`` is the outer (model) diameter in m; ``inner_diameter_m`` > 0
    makes it a tube.  ``moment_scale`` multiplies its second moment of area alone (a
    cavity's section bent across the ball's direction: its stiffness, with its mass).
    A section that is not round (flats, an off-centre bore) gives its own
    ``given_moments_m4``, its second moments of area (m^4) for bending in the bar's
    first and second planes, each at most the round section's; ``plane`` (0 or 1) is
    the plane its bar is bent in.  ``given_area_m2`` (m^2): its area, at most the round
    section's; None: the round section's.
    """

    start_m: float
    end_m: float
    diameter_m: float
    inner_diameter_m: float = 0.0
    moment_scale: float = 1.0
    given_moments_m4: tuple[float, float] | None = None
    given_area_m2: float | None = None
    plane: int = 0

    def __post_init__(self):
        check_range("section start_m", self.start_m, 0.0, math.inf)
        if not self.end_m > self.start_m:
            raise ValueError(
                f"section end_m = {self.end_m!r} m must be greater than its start_m = "
                f"{self.start_m!r} m"
            )
        check_positive("section diameter_m", self.diameter_m, "m")
        check_range("section inner_diameter_m", self.inner_diameter_m, 0.0, self.diameter_m,
                    hi_open=True)
        check_choice("section plane", self.plane, (0, 1))
        if self.given_moments_m4 is not None:
            if len(self.given_moments_m4) != 2:
                raise ParameterError(f"section given_moments_m4 = {self.given_moments_m4!r} "
                                     "must be two second moments (m^4), one a plane")
            for k, moment in enumerate(self.given_moments_m4):
                check_range(f"section given_moments_m4[{k}]", moment, 0.0, self.round_moment_m4,
                            lo_open=True, unit="m^4", why="at most the round section's")
        if self.given_area_m2 is not None:
            check_range("section given_area_m2", self.given_area_m2, 0.0, self.round_area_m2,
                        lo_open=True, unit="m^2", why="at most the round section's")

    @property
    def round_area_m2(self) -> float:
        """The round section's (or tube's) area (m^2)."""
        return math.pi / 4.0 * (self.diameter_m**2 - self.inner_diameter_m**2)

    @property
    def round_moment_m4(self) -> float:
        """The round section's (or tube's) second moment of area (m^4)."""
        return math.pi / 64.0 * (self.diameter_m**4 - self.inner_diameter_m**4)

    @property
    def area_m2(self) -> float:
        return self.round_area_m2 if self.given_area_m2 is None else self.given_area_m2

    @property
    def second_moment_m4(self) -> float:
        if self.given_moments_m4 is not None:
            return self.given_moments_m4[self.plane]
        return self.round_moment_m4 * self.moment_scale


def published_sections(cavity: bool = True) -> tuple[Section, ...]:
    """The published bar (docs/model.md, section 1): with the ball cavity, or solid."""
    d2 = 0.017 if cavity else 0.025
    return (
        Section(0.0, 0.122, 0.025),
        Section(0.122, 0.1371, d2),
        Section(0.1371, 0.170, 0.022),
        Section(0.170, 0.200, 0.019),
    )


def _read_only(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class ModalModel:
    """The bar reduced to ``n`` uncoupled bending modes (modal coordinates u_i).

    Each mode i obeys M_i u_i'' + C_i u_i' + K_i u_i = (generalised forces),
    with C_i = 2 zeta_i sqrt(K_i M_i).  Mode shapes enter only through their
    values at the tip (psi_tip), at the ball (psi_damper) and at the
    absorber (psi_absorber).  Any normalisation of a mode is allowed; the
    physical outputs (tip displacement W = psi_tip . u) do not depend on it.

    ``mass_kg``, ``stiffness_n_m``, ``damping_ratio``: M_i (kg), K_i (N/m), zeta_i per
    mode; ``psi_tip``, ``psi_damper``, ``psi_absorber``: the mode shapes at the tip, at
    the ball ``z_damper_m`` and at the absorber ``z_absorber_m`` (m from the clamp);
    ``source``: where the model came from ("fe", "tap-test", with a calibration
    note appended); ``info``: free-form provenance.

    ``psi_force``: the shape the cutting or harmonic force enters each mode by, where it
    differs from ``psi_tip``, the shape the chip thickness and the reported tip
    displacement W read (an oriented cut in two bending planes,
    :func:`boringbar.model.oriented.oriented_model`; docs/model.md, section 4.7); None:
    ``psi_tip`` (a force along the direction W is measured in).  In an oriented model a
    mode of a bar of two planes may have psi_tip = 0 (it bends across the chip), but the
    first may not.
    """

    mass_kg: np.ndarray  #: modal masses M_i (kg, in the units the mode is normalised)
    stiffness_n_m: np.ndarray  #: modal stiffnesses K_i (N/m, likewise)
    damping_ratio: np.ndarray  #: zeta_i
    psi_tip: np.ndarray  #: psi_i(L)
    psi_damper: np.ndarray  #: psi_i(z_d)
    psi_absorber: np.ndarray  #: psi_i(z_a)
    z_damper_m: float = BALL_POSITION
    z_absorber_m: float = ABSORBER_POSITION
    source: str = "fe"  #: "fe", "tap-test", or with a calibration note appended
    info: dict = field(default_factory=dict)
    psi_force: np.ndarray | None = None  #: the force's shape at the tip (None: psi_tip)

    def __post_init__(self):
        n = len(np.atleast_1d(self.mass_kg))
        if self.psi_force is None:
            object.__setattr__(self, "psi_force", self.psi_tip)
        for name in ("mass_kg", "stiffness_n_m", "damping_ratio", "psi_tip", "psi_damper",
                     "psi_absorber", "psi_force"):
            arr = np.atleast_1d(np.asarray(getattr(self, name), dtype=float)).copy()
            if arr.shape != (n,):
                raise ValueError(f"modal model: {name} has shape {arr.shape}, expected ({n},)")
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"modal model: {name} = {arr!r} must be finite")
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        for i in range(n):
            check_positive(f"modal mass of mode {i + 1}", self.mass_kg[i])
            check_positive(f"modal stiffness of mode {i + 1}", self.stiffness_n_m[i])
            check_range(f"damping ratio of mode {i + 1}", self.damping_ratio[i], 0.0, 1.0,
                        hi_open=True)
        # (a bar of two planes may have modes that bend across the chip, psi_tip = 0;
        # the first carries the tip's normalisation)
        if n < 1 or self.psi_tip[0] == 0.0 or (self.planes == 1 and np.any(self.psi_tip == 0.0)):
            raise ValueError("modal model: every mode needs a non-zero tip value psi_tip")

    # --- derived quantities -------------------------------------------------
    # (kept once computed, as every run reads them: the fields are read-only copies)
    @functools.cached_property
    def oriented(self) -> bool:
        """The force enters the modes by a shape of its own (psi_force != psi_tip)."""
        return not np.array_equal(self.psi_force, self.psi_tip)

    @property
    def planes(self) -> int:
        """The bending planes its modes lie in: 2 for an oriented model (model/oriented.py)."""
        return self.info.get("planes", 1)

    @property
    def n_modes(self) -> int:
        return len(self.mass_kg)

    @functools.cached_property
    def omegas_rad_s(self) -> np.ndarray:
        """Natural frequencies of the retained modes (rad/s)."""
        return _read_only(np.sqrt(self.stiffness_n_m / self.mass_kg))

    @functools.cached_property
    def natural_frequency_rad_s(self) -> float:
        """First natural frequency omega_n (rad/s)."""
        return float(self.omegas_rad_s[0])

    @property
    def natural_frequency_hz(self) -> float:
        return self.natural_frequency_rad_s / (2.0 * math.pi)

    @functools.cached_property
    def damping_n_s_m(self) -> np.ndarray:
        """Modal viscous coefficients C_i = 2 zeta_i sqrt(K_i M_i) (N s/m)."""
        return _read_only(2.0 * self.damping_ratio * np.sqrt(self.stiffness_n_m * self.mass_kg))

    @property
    def tip_stiffness_n_m(self) -> float:
        """Static-like stiffness of the first mode at the tip, K_1 / psi_1(L)^2 (N/m)."""
        return float(self.stiffness_n_m[0] / self.psi_tip[0] ** 2)

    @property
    def tip_mass_kg(self) -> float:
        """First-mode mass referred to the tip, M_1 / psi_1(L)^2 (kg)."""
        return float(self.mass_kg[0] / self.psi_tip[0] ** 2)

    # --- transformations ----------------------------------------------------
    def truncated(self, n_modes: int) -> ModalModel:
        """The first ``n_modes`` modes."""
        check_range("n_modes", n_modes, 1, self.n_modes)
        n = int(n_modes)
        return replace(self, mass_kg=self.mass_kg[:n], stiffness_n_m=self.stiffness_n_m[:n],
                       damping_ratio=self.damping_ratio[:n], psi_tip=self.psi_tip[:n],
                       psi_damper=self.psi_damper[:n], psi_absorber=self.psi_absorber[:n],
                       psi_force=self.psi_force[:n])

    def with_first_frequency(self, frequency_hz: float) -> ModalModel:
        """Keep masses and mode shapes, scale every K so that f1 = ``frequency_hz``.

        This is the published-frequency calibration of the ``paper`` preset
        (docs/model.md, section 2); it is a uniform change of E.
        """
        check_positive("calibration frequency_hz", frequency_hz)
        factor = (frequency_hz / self.natural_frequency_hz) ** 2
        info = dict(self.info, stiffness_scale=factor, calibrated_f1_hz=frequency_hz)
        return replace(self, stiffness_n_m=self.stiffness_n_m * factor,
                       source=f"{self.source}+calibrated-to-{frequency_hz:g}Hz", info=info)

    def normalised(self, scale) -> ModalModel:
        """The same model with mode i's shape multiplied by ``scale[i]``.

        M and K scale by scale^2; physical results are unchanged (a test).
        """
        s = np.broadcast_to(np.asarray(scale, dtype=float), (self.n_modes,))
        return replace(self, mass_kg=self.mass_kg * s**2, stiffness_n_m=self.stiffness_n_m * s**2,
                       psi_tip=self.psi_tip * s, psi_damper=self.psi_damper * s,
                       psi_absorber=self.psi_absorber * s, psi_force=self.psi_force * s)

    def to_dict(self) -> dict:
        return {
            "source": self.source,
            "n_modes": self.n_modes,
            "natural_frequencies_hz": (self.omegas_rad_s / (2 * math.pi)).tolist(),
            "modal_mass_kg": self.mass_kg.tolist(),
            "modal_stiffness_n_m": self.stiffness_n_m.tolist(),
            "damping_ratio": self.damping_ratio.tolist(),
            "psi_tip": self.psi_tip.tolist(),
            "psi_damper": self.psi_damper.tolist(),
            "psi_absorber": self.psi_absorber.tolist(),
            "z_damper_m": self.z_damper_m,
            "z_absorber_m": self.z_absorber_m,
            **({"psi_force": self.psi_force.tolist()} if self.oriented else {}),
            **{k: v for k, v in self.info.items()},
        }

    @classmethod
    def from_dict(cls, d: dict) -> ModalModel:
        """The model :meth:`to_dict` describes (its other keys become ``info``)."""
        known = {"source", "n_modes", "natural_frequencies_hz", "modal_mass_kg",
                 "modal_stiffness_n_m",
                 "damping_ratio", "psi_tip", "psi_damper", "psi_absorber", "z_damper_m",
                 "z_absorber_m", "psi_force"}
        return cls(mass_kg=d["modal_mass_kg"], stiffness_n_m=d["modal_stiffness_n_m"],
                   damping_ratio=d["damping_ratio"], psi_tip=d["psi_tip"],
                   psi_damper=d["psi_damper"], psi_absorber=d["psi_absorber"],
                   z_damper_m=d["z_damper_m"], z_absorber_m=d["z_absorber_m"],
                   source=d["source"], psi_force=d.get("psi_force"),
                   info={k: v for k, v in d.items() if k not in known})

    @classmethod
    def from_tap_test(cls, frequency_hz: float, damping_ratio: float = DAMPING_RATIO, *,
                      tip_stiffness_n_m: float | None = None, tip_mass_kg: float | None = None,
                      damper_ratio: float = 1.0, absorber_ratio: float = 1.0) -> ModalModel:
        """One mode from measured data, normalised to psi(L) = 1.

        Give ``tip_stiffness_n_m`` k_tip (N/m) or ``tip_mass_kg`` (kg, = k_tip/omega_n^2);
        ``damper_ratio`` = psi_d/psi_L and ``absorber_ratio`` = psi_a/psi_L.
        """
        check_positive("frequency_hz", frequency_hz)
        omega = 2 * math.pi * frequency_hz
        if (tip_stiffness_n_m is None) == (tip_mass_kg is None):
            raise ValueError("from_tap_test: give exactly one of tip_stiffness_n_m (N/m) or "
                             "tip_mass_kg (kg)")
        if tip_stiffness_n_m is not None:
            check_positive("tip_stiffness_n_m", tip_stiffness_n_m, "N/m")
            mass = tip_stiffness_n_m / omega**2
        else:
            check_positive("tip_mass_kg", tip_mass_kg, "kg")
            mass = float(tip_mass_kg)
        return cls(mass_kg=np.array([mass]), stiffness_n_m=np.array([mass * omega**2]),
                   damping_ratio=np.array([damping_ratio]), psi_tip=np.array([1.0]),
                   psi_damper=np.array([float(damper_ratio)]),
                   psi_absorber=np.array([float(absorber_ratio)]), source="tap-test")


#: The most finite elements a bar is meshed into: its eigenproblem is dense, and 1000
#: elements (about 2000 degrees of freedom) take seconds, where a few dozen converge the
#: modes that are kept
MAX_ELEMENTS = 1000


@dataclass(frozen=True)
class SteppedBar:
    """A stepped cantilever: clamped at z = 0, free at the end of the last section.

    ``sections``: contiguous :class:`Section` s from the clamp; ``youngs_modulus_pa``
    (Pa) and ``density_kg_m3`` (kg/m^3) of the material; ``damping_ratio``: modal
    damping of every mode; ``max_element_length_m`` (m): the finite-element mesh size
    (nodes also at every section boundary and at the points asked for).
    ``clamp_translational_stiffness_n_m`` (N/m) and
    ``clamp_rotational_stiffness_n_m_per_rad`` (N m/rad) support the bar's root on springs;
    ``math.inf`` (the default) is a rigid clamp, whose degree of freedom is removed.
    """

    sections: tuple[Section, ...] = published_sections(cavity=True)
    youngs_modulus_pa: float = STEEL_E
    density_kg_m3: float = STEEL_RHO
    damping_ratio: float = DAMPING_RATIO
    max_element_length_m: float = 0.005
    clamp_translational_stiffness_n_m: float = math.inf
    clamp_rotational_stiffness_n_m_per_rad: float = math.inf

    def __post_init__(self):
        object.__setattr__(self, "sections", tuple(self.sections))
        if not self.sections:
            raise ValueError("a SteppedBar needs at least one section")
        if abs(self.sections[0].start_m) > 1e-12:
            raise ValueError(f"the first section must start at the clamp, z = 0 "
                             f"(got {self.sections[0].start_m!r} m)")
        for a, b in itertools.pairwise(self.sections):
            if abs(a.end_m - b.start_m) > 1e-12:
                raise ValueError(f"sections must be contiguous: one ends at {a.end_m!r} m, the "
                                 f"next starts at {b.start_m!r} m")
        check_positive("youngs_modulus_pa", self.youngs_modulus_pa, "Pa")
        check_positive("density_kg_m3", self.density_kg_m3, "kg/m^3")
        check_range("damping_ratio", self.damping_ratio, 0.0, 1.0, hi_open=True)
        check_positive("max_element_length_m", self.max_element_length_m, "m")
        finest = self.length_m / MAX_ELEMENTS
        if self.max_element_length_m < finest:
            raise ParameterError(
                f"max_element_length_m = {self.max_element_length_m!r} m meshes the "
                f"{self.length_m:g} m bar into more than {MAX_ELEMENTS} elements (a dense "
                f"eigenproblem of twice as many degrees of freedom); give at least "
                f"{finest:.3g} m (the modes kept converge long before: 5 mm is the default)")
        for name, value, unit in (
                ("clamp_translational_stiffness_n_m", self.clamp_translational_stiffness_n_m,
                 "N/m"),
                ("clamp_rotational_stiffness_n_m_per_rad",
                 self.clamp_rotational_stiffness_n_m_per_rad, "N m/rad")):
            if value != math.inf:  # inf: rigid
                check_positive(name, value, unit)

    @property
    def plane_moments(self) -> bool:
        """Whether a section gives its own second moments a plane (not round)."""
        return any(s.given_moments_m4 is not None for s in self.sections)

    def in_plane(self, plane: int) -> SteppedBar:
        """This bar bent in its ``plane`` (0: the first, 1: the second): each section with
        given second moments takes that plane's."""
        return replace(self, sections=tuple(replace(s, plane=plane) for s in self.sections))

    @property
    def rigid_clamp(self) -> bool:
        return math.isinf(self.clamp_translational_stiffness_n_m) and math.isinf(
            self.clamp_rotational_stiffness_n_m_per_rad)

    def _kept_dofs(self, n_dof: int) -> np.ndarray:
        """The degrees of freedom left after the clamp: a rigid direction is removed."""
        keep = np.ones(n_dof, dtype=bool)
        keep[0] = not math.isinf(self.clamp_translational_stiffness_n_m)
        keep[1] = not math.isinf(self.clamp_rotational_stiffness_n_m_per_rad)
        return keep

    def _deflections(self, vec: np.ndarray) -> np.ndarray:
        """Deflection w at every node (rows) of the reduced eigenvectors ``vec``."""
        removed = int(math.isinf(self.clamp_translational_stiffness_n_m)) + int(
            math.isinf(self.clamp_rotational_stiffness_n_m_per_rad))
        full = np.zeros((vec.shape[0] + removed, vec.shape[1]))
        full[self._kept_dofs(full.shape[0])] = vec
        return full[0::2, :]

    @property
    def length_m(self) -> float:
        return self.sections[-1].end_m

    def mesh(self, points=()) -> np.ndarray:
        """Node positions: every section boundary and every requested point."""
        brk = {0.0, self.length_m} | {s.end_m for s in self.sections}
        for z in points:
            check_range("mode-shape point z", z, 0.0, self.length_m)
            brk.add(float(z))
        brk = np.array(sorted(brk))
        nodes = [brk[0]]
        for a, b in itertools.pairwise(brk):
            if b - a < 1e-12:
                continue
            n_el = max(1, math.ceil((b - a) / self.max_element_length_m - 1e-9))
            nodes.extend(np.linspace(a, b, n_el + 1)[1:])
        return np.array(nodes)

    def _section_at(self, z: float) -> Section:
        for s in self.sections:
            if s.start_m - 1e-12 <= z <= s.end_m + 1e-12:
                return s
        raise ValueError(f"z = {z!r} m lies outside the bar [0, {self.length_m}] m")

    def matrices(self, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Global stiffness and consistent mass matrices, the clamp's springs added
        and its rigid DOFs removed.

        DOFs per node: deflection w and slope theta.
        """
        n_dof = 2 * len(nodes)
        K = np.zeros((n_dof, n_dof))
        M = np.zeros((n_dof, n_dof))
        for e, (a, b) in enumerate(itertools.pairwise(nodes)):
            sec = self._section_at(0.5 * (a + b))
            ei = self.youngs_modulus_pa * sec.second_moment_m4
            ra = self.density_kg_m3 * sec.area_m2
            ke, me = _element_matrices(b - a, ei, ra)
            idx = slice(2 * e, 2 * e + 4)
            K[idx, idx] += ke
            M[idx, idx] += me
        if self.rigid_clamp:
            return K[2:, 2:], M[2:, 2:]
        keep = self._kept_dofs(n_dof)
        if keep[0]:
            K[0, 0] += self.clamp_translational_stiffness_n_m
        if keep[1]:
            K[1, 1] += self.clamp_rotational_stiffness_n_m_per_rad
        return K[np.ix_(keep, keep)], M[np.ix_(keep, keep)]

    @staticmethod
    @one_blas_thread
    def _eig(K: np.ndarray, M: np.ndarray, n: int):
        """The first ``n`` eigenpairs (omega^2 ascending, shapes), from the flexibility
        form M phi = omega^-2 K phi reduced through K's Cholesky factor: its largest
        eigenvalues are the lowest modes.  The stiffness form K phi = omega^2 M phi
        with LAPACK's subset driver loses digits as the mesh is refined (f1 of the
        published bar off by 1.4e-8 at 5 mm elements, 1e-4 at 0.5 mm) and when a stiff
        clamp spring sits beside the beam's own terms (7 % at 1e13 N/m); this form
        stays within 1e-9 of the full solver in both cases."""
        size = K.shape[0]
        mu, vec = scipy.linalg.eigh(M, K, subset_by_index=[size - n, size - 1])
        return 1.0 / mu[::-1], vec[:, ::-1]

    def static_tip_stiffness(self) -> float:
        """The tip's static stiffness (N/m): a unit tip force over the tip deflection of
        the full finite-element model (every mode, the clamp's springs included)."""
        nodes = self.mesh()
        K, _ = self.matrices(nodes)
        load = np.zeros(K.shape[0])
        load[-2] = 1.0
        return float(1.0 / np.linalg.solve(K, load)[-2])

    def modes(self, n_modes: int = 1, points=()) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """First ``n_modes`` (omega rad/s, node positions, deflection shapes (nodes, n))."""
        nodes = self.mesh(points)
        K, M = self.matrices(nodes)
        n = int(n_modes)
        check_range("n_modes", n, 1, K.shape[0])
        w2, vec = self._eig(K, M, n)
        return np.sqrt(w2), nodes, self._deflections(vec)

    def modal_model(self, n_modes: int = 1, z_damper_m: float = BALL_POSITION,
                    z_absorber_m: float = ABSORBER_POSITION) -> ModalModel:
        """Reduce to ``n_modes`` modes, normalised to psi_i(L) = 1, with the mode shapes
        at the ball ``z_damper_m`` and the absorber ``z_absorber_m`` (m from the clamp).

        Kept per bar and arguments (:func:`kept_modal_model`): a design search or the
        page builds system after system on one bar, and the finite-element solve was
        nearly all of ``make_system``'s time.  A bar is frozen and a modal model's arrays
        are read-only, so a kept model cannot change; each call gets its own copy of its
        ``info``."""
        kept = kept_modal_model(self, int(n_modes), float(z_damper_m), float(z_absorber_m))
        return replace(kept, info=dict(kept.info))  # its own info, the one mutable field

    def solve_modal_model(self, n_modes: int, z_damper_m: float,
                          z_absorber_m: float) -> ModalModel:
        """:meth:`modal_model`, solved."""
        z_damper, z_absorber = z_damper_m, z_absorber_m
        nodes = self.mesh((z_damper, z_absorber))
        K, M = self.matrices(nodes)
        n = int(n_modes)
        check_range("n_modes", n, 1, K.shape[0])
        _, vec = self._eig(K, M, n)
        vec = vec / vec[-2, :]  # psi_i(L) = 1: the tip deflection DOF
        masses = np.einsum("ij,ik,kj->j", vec, M, vec)
        stiff = np.einsum("ij,ik,kj->j", vec, K, vec)
        w = self._deflections(vec)

        def at(z):
            i = int(np.argmin(np.abs(nodes - z)))
            return w[i, :]

        return ModalModel(mass_kg=masses, stiffness_n_m=stiff,
                          damping_ratio=np.full(len(masses), self.damping_ratio),
                          psi_tip=np.ones(len(masses)), psi_damper=at(z_damper),
                          psi_absorber=at(z_absorber), z_damper_m=float(z_damper),
                          z_absorber_m=float(z_absorber), source="fe",
                          info={"n_elements": len(nodes) - 1,
                                "bar_length_m": self.length_m})


#: How many (bar, modes, positions) :func:`kept_modal_model` keeps.
MODAL_CACHE_SIZE = 256


@functools.lru_cache(maxsize=MODAL_CACHE_SIZE)
def kept_modal_model(bar: SteppedBar, n_modes: int, z_damper_m: float,
                     z_absorber_m: float) -> ModalModel:
    """``bar``'s modal model (:meth:`SteppedBar.solve_modal_model`), kept (shared: a
    caller that may change its ``info`` copies it first, as :meth:`SteppedBar.modal_model`
    does)."""
    return bar.solve_modal_model(n_modes, z_damper_m, z_absorber_m)


def _element_matrices(length: float, ei: float, rho_a: float):
    """Hermite-cubic Euler-Bernoulli element: stiffness and consistent mass."""
    l = length
    ke = ei / l**3 * np.array([
        [12.0, 6 * l, -12.0, 6 * l],
        [6 * l, 4 * l * l, -6 * l, 2 * l * l],
        [-12.0, -6 * l, 12.0, -6 * l],
        [6 * l, 2 * l * l, -6 * l, 4 * l * l],
    ])
    me = rho_a * l / 420.0 * np.array([
        [156.0, 22 * l, 54.0, -13 * l],
        [22 * l, 4 * l * l, 13 * l, -3 * l * l],
        [54.0, 13 * l, 156.0, -22 * l],
        [-13 * l, -3 * l * l, -22 * l, 4 * l * l],
    ])
    return ke, me


def published_bar(cavity: bool = True, n_modes: int = 1,
                  z_absorber_m: float = ABSORBER_POSITION,
                  max_element_length_m: float = 0.005) -> ModalModel:
    """The published boring bar's modal model: the ball-cavity bar (``cavity``) or the
    solid one, ``n_modes`` retained, the absorber's mode shape at ``z_absorber_m`` (m),
    meshed at ``max_element_length_m`` (m)."""
    bar = SteppedBar(sections=published_sections(cavity),
                     max_element_length_m=max_element_length_m)
    return bar.modal_model(n_modes=n_modes, z_damper_m=BALL_POSITION, z_absorber_m=z_absorber_m)
