"""Linear frequency responses of the bar, and tuned-mass-damper tuning.

docs/model.md, sections 1 and 3.  The bar is the n-mode modal model

    M_i u_i'' + C_i u_i' + K_i u_i = psi_L,i f,        W = psi_L . u,

optionally carrying a tuned mass damper at z_a (section 3),

    M u'' + C u' + K u = psi_L f + psi_a [k_a (x_a - psi_a . u) + c_a (x_a' - psi_a . u')]
    m_a x_a'' = -k_a (x_a - psi_a . u) - c_a (x_a' - psi_a . u'),

and/or a rigid added mass m at z_d (a locked ball: m psi_d psi_d^T joins the
modal mass matrix and couples the modes).  Everything is linear, so the tip
receptance G(i omega) = W / F (m/N) follows from one small dense solve per
frequency.

Tuning (mode 1 of the bar, absorber mass ratio mu = m_a psi_a^2 / M):

- Den Hartog (equal peaks of |G|): :func:`boringbar.model.dampers.den_hartog_parameters`.
- Sims (equal real troughs, N. D. Sims, J. Sound Vib. 301 (2007) 592-607):
  :func:`boringbar.model.dampers.sims_parameters`, the closed form for an undamped single-mode host;
  it maximises the limiting depth of cut, which is inversely proportional
  to the most negative real part of G.
- :func:`minimax_real_tuning`: the same objective minimised numerically on
  the actual (damped, multi-mode) model, the check on Sims' closed form.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.optimize

from boringbar._validate import ParameterError, check_nonnegative
from boringbar.model.bar import ModalModel
from boringbar.model.dampers import TunedMassDamper, sims_tuning

#: Default search band for the real-part trough, in units of omega_1.
TROUGH_BAND = (0.4, 2.2)
TROUGH_POINTS = 3601


# --- frequency responses ------------------------------------------------------
def tip_frf(
    bar: ModalModel, omega_rad_s, *, tmd: TunedMassDamper | None = None,
    added_mass_kg: float = 0.0
) -> np.ndarray:
    """Tip receptance G(i omega) = W / F (m/N) for a harmonic force F at the tip.

    ``bar`` is a :class:`~boringbar.model.bar.ModalModel`; ``omega_rad_s`` (rad/s) is
    array-like and the result has its shape (complex).  The dynamic
    stiffness solved at each frequency is, with kc = k_a + i omega c_a,

        [ diag(K - omega^2 M + i omega C) - omega^2 m psi_d psi_d^T + kc psi_a psi_a^T,  -kc psi_a ]
        [ -kc psi_a^T,                                                  kc - omega^2 m_a ]

    (the absorber row only if ``tmd`` is given), acting on (u, x_a) with the
    load (psi_L F, 0); then W = psi_L . u.  ``added_mass_kg`` (kg) is a mass
    rigidly attached at z_d (``bar.psi_damper``).  The TMD acts at
    ``bar.psi_absorber``, so ``tmd.position_m`` must equal ``bar.z_absorber_m``.
    """
    w = np.asarray(omega_rad_s, dtype=float)
    check_nonnegative("added_mass_kg", added_mass_kg, "kg")
    z = dynamic_stiffness(bar, w.ravel(), tmd, float(added_mass_kg))
    rhs = np.zeros(z.shape[:2] + (1,), dtype=complex)
    rhs[:, : bar.n_modes, 0] = bar.psi_force  # (psi_tip but in an oriented cut)
    u = np.linalg.solve(z, rhs)[:, : bar.n_modes, 0]
    return (u @ bar.psi_tip).reshape(w.shape)


def dynamic_stiffness(bar, w: np.ndarray, tmd, added_mass: float) -> np.ndarray:
    """Batched dynamic stiffness matrices, shape (len(w), n [+1], n [+1])."""
    n = bar.n_modes
    size = n + (tmd is not None)
    z = np.zeros((len(w), size, size), dtype=complex)
    diag = bar.stiffness_n_m - np.outer(w**2, bar.mass_kg) + 1j * np.outer(w, bar.damping_n_s_m)
    z[:, np.arange(n), np.arange(n)] = diag
    psi_d = bar.psi_damper
    z[:, :n, :n] -= (w**2 * added_mass)[:, None, None] * np.outer(psi_d, psi_d)
    if tmd is not None:
        _check_position(bar, tmd)
        kc = tmd.stiffness_n_m + 1j * w * tmd.damping_n_s_m
        psi_a = bar.psi_absorber
        z[:, :n, :n] += kc[:, None, None] * np.outer(psi_a, psi_a)
        z[:, :n, n] = -kc[:, None] * psi_a
        z[:, n, :n] = -kc[:, None] * psi_a
        z[:, n, n] = kc - w**2 * tmd.mass_kg
    return z


def _check_position(bar, tmd) -> None:
    if abs(tmd.position_m - bar.z_absorber_m) > 1e-9:
        raise ParameterError(
            f"absorber position = {tmd.position_m!r} m differs from the modal model's "
            f"z_absorber = {bar.z_absorber_m!r} m; rebuild the bar with z_absorber there"
        )


def static_tip_compliance(bar) -> float:
    """Static tip compliance of the retained modes, sum_i psi_L,i psi_F,i / K_i (m/N;
    psi_F = psi_L but in an oriented cut)."""
    return float(np.sum(bar.psi_tip * bar.psi_force / bar.stiffness_n_m))


# --- the most negative real part ------------------------------------------------
def min_real_part(
    bar: ModalModel, tmd: TunedMassDamper | None = None, omega_rad_s=None, *,
    added_mass_kg: float = 0.0
) -> tuple[float, float]:
    """(min Re G (m/N), omega at the minimum (rad/s)) of the tip receptance of ``bar``
    (a ModalModel) with the absorber ``tmd`` (or none) and a rigid ``added_mass_kg`` (kg)
    at the ball's position.

    Searched on ``omega_rad_s`` (rad/s; default: omega_1 times ``TROUGH_BAND``,
    ``TROUGH_POINTS`` points); every local minimum of the grid is then
    refined by a bounded scalar minimisation between its neighbours, so the
    value is accurate to the solver tolerance, not to the grid spacing.
    The limiting depth of cut of a regenerative cut is inversely
    proportional to -min Re G (docs/model.md, section 3).
    """
    if omega_rad_s is None:
        omega_rad_s = bar.natural_frequency_rad_s * np.linspace(*TROUGH_BAND, TROUGH_POINTS)
    w = np.asarray(omega_rad_s, dtype=float)
    if w.ndim != 1 or len(w) < 3:
        raise ParameterError(f"omega_rad_s must be a 1-D grid of at least 3 points (got shape "
                             f"{w.shape})")
    re = tip_frf(bar, w, tmd=tmd, added_mass_kg=added_mass_kg).real
    best = (float(re.min()), float(w[np.argmin(re)]))
    for i in _local_minima(re):
        lo, hi = w[max(i - 1, 0)], w[min(i + 1, len(w) - 1)]
        res = scipy.optimize.minimize_scalar(
            lambda x: tip_frf(bar, x, tmd=tmd, added_mass_kg=added_mass_kg).real,
            bounds=(lo, hi),
            method="bounded",
            options={"xatol": 1e-9 * hi},
        )
        if res.fun < best[0]:
            best = (float(res.fun), float(res.x))
    return best


def _local_minima(values: np.ndarray) -> np.ndarray:
    """Indices i with values[i] <= both neighbours (interior points only)."""
    v = np.asarray(values)
    return np.flatnonzero((v[1:-1] <= v[:-2]) & (v[1:-1] <= v[2:])) + 1


def minimax_real_tuning(
    mass: float, bar, *, start: TunedMassDamper | None = None, omega=None, xatol: float = 1e-7
) -> TunedMassDamper:
    """Absorber (k_a, c_a) minimising the most negative real part of the tip FRF.

    Nelder-Mead over (ln k_a, ln c_a) from ``start`` (default: Sims'
    closed form), objective -min Re G scaled by the tip stiffness
    (dimensionless), evaluated by :func:`min_real_part` on ``omega``.  This
    is the direct numerical check of the closed form; unlike it, it sees the
    host's damping and every retained mode.
    """
    x0 = sims_tuning(mass, bar) if start is None else start
    scale = bar.tip_stiffness_n_m

    def objective(p):
        tmd = TunedMassDamper(mass_kg=mass, stiffness_n_m=math.exp(p[0]),
                              damping_n_s_m=math.exp(p[1]), position_m=bar.z_absorber_m)
        return -min_real_part(bar, tmd, omega)[0] * scale

    res = scipy.optimize.minimize(
        objective,
        [math.log(x0.stiffness_n_m), math.log(x0.damping_n_s_m)],
        method="Nelder-Mead",
        options={"xatol": xatol, "fatol": 1e-12, "maxiter": 2000},
    )
    return TunedMassDamper(
        mass_kg=mass,
        stiffness_n_m=math.exp(res.x[0]),
        damping_n_s_m=math.exp(res.x[1]),
        position_m=bar.z_absorber_m,
        design="minimax-real",
    )
