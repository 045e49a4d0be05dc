"""Analytic stability lobes of regenerative turning/boring (docs/model.md, section 4).

The cutting force at the tip is f = Kr b h with h = h_m + W(t - tau) - W(t)
(single-pass regeneration, tau = 60 / rpm).  Linearised about the steady cut,
a perturbation W = G f obeys W = G Kr b (W(t - tau) - W(t)), so at a chatter
frequency omega the characteristic equation is (Tobias/Tlusty; Altintas,
*Manufacturing Automation*, ch. 3)

    1 + Kr b (1 - exp(-i omega tau)) G(i omega) = 0,

G the tip receptance of :func:`boringbar.reference.linear.tip_frf`.  Writing
G = R + i I and theta = omega tau, its imaginary part gives
(1 - cos theta) I + sin theta R = 0, i.e. cot(theta / 2) = -I / R, and then its
real part gives 1 + 2 Kr b R = 0:

    b_lim(omega) = -1 / (2 Kr Re G(i omega))            (only where Re G < 0)
    omega tau    = eps + 2 pi j,   j = 0, 1, 2, ...
    eps          = 3 pi + 2 psi  (mod 2 pi),   psi = arg G = atan2(Im G, Re G).

A tip receptance is a driving-point FRF, so Im G <= 0 and, where Re G < 0,
psi lies in [-pi, -pi/2) and eps in [pi, 2 pi).  Lobe j is the curve
(rpm, b) = (60 omega / (eps + 2 pi j), b_lim(omega)) as omega runs over the
region where Re G < 0; the speed-independent minimum of all lobes is
-1 / (2 Kr min Re G).

A :class:`~boringbar.model.system.System` brings its own damper: a tuned mass
damper enters G, a locked ball is a rigid mass at z_d, and a free ball (which
in its clearance does not touch a wall under small vibration) is carried by its
friction as a locked ball, and without friction leaves the bare host bar
(System.linear_host).
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np
import scipy.linalg

from boringbar._validate import ParameterError, check_nonnegative, check_positive, check_range
from boringbar.model.bar import ModalModel
from boringbar.model.cutting import KR_ALUMINIUM
from boringbar.model.dampers import TunedMassDamper
from boringbar.model.forcing import check_lobe_speed
from boringbar.reference.linear import dynamic_stiffness, min_real_part, tip_frf

#: Default frequency grid spans these multiples of the lowest / highest
#: undamped natural frequency of the coupled system.
GRID_SPAN = (0.5, 2.0)
#: Bisection steps refining each lobe crossing (bracket shrinks 2^-60).
BISECTION_STEPS = 60
#: A crossing is bisected only if its better bracket end is within this fraction of
#: the best crossing's worse end (:func:`_contenders`).
CONTENDER_MARGIN = 0.1
#: grid steps times speeds looked at in one block by the crossing search (memory), and
#: the steps of its first round (each round doubles them)
CROSSING_BLOCK = 2_000_000
CROSSING_FIRST = 512
TWO_PI = 2.0 * math.pi


# --- the phase relation ------------------------------------------------------------
def regeneration_phase(g) -> np.ndarray:
    """eps = 3 pi + 2 arg G (mod 2 pi), the phase of lobe j = 0 (rad).

    With theta = omega tau = eps + 2 pi j the characteristic equation
    1 + Kr b (1 - exp(-i theta)) G = 0 holds for b = -1 / (2 Kr Re G)
    (module docstring).  Meaningful where Re G < 0; there eps is in [pi, 2 pi).
    """
    g = np.asarray(g, dtype=complex)
    return np.mod(3.0 * math.pi + 2.0 * np.angle(g), TWO_PI)


# --- inputs ------------------------------------------------------------------------
def linear_host(system_or_bar, tmd=None, added_mass: float = 0.0):
    """(ModalModel, TunedMassDamper | None, added mass kg) of a System or a bar: what the
    tip FRF of a small vibration sees (System.linear_host: a TMD enters it, a locked
    ball is a rigid mass at z_d, a free ball in its clearance is carried by its friction
    as a locked one, and without friction does not act)."""
    if isinstance(system_or_bar, ModalModel):
        if tmd is not None and not isinstance(tmd, TunedMassDamper):
            raise ParameterError(f"tmd = {tmd!r} must be a TunedMassDamper or None")
        return system_or_bar, tmd, check_nonnegative("added_mass", added_mass, "kg")
    bar = getattr(system_or_bar, "bar", None)
    if not isinstance(bar, ModalModel):
        raise ParameterError(f"system_or_bar = {system_or_bar!r} must be a System or a ModalModel")
    if tmd is not None or added_mass != 0.0:
        raise ParameterError(
            "tmd and added_mass are taken from the System; give them only with a ModalModel "
            f"(got tmd = {tmd!r}, added_mass = {added_mass!r})"
        )
    host = system_or_bar.linear_host()  # a free ball: carried by friction, or not acting
    if host.kind == "tmd":
        return bar, host.damper, 0.0
    if host.kind == "locked":
        return bar, None, float(host.damper.mass_kg)
    return bar, None, 0.0


def system_receptance(system, w) -> np.ndarray:
    """The tip receptance (m/N) of ``system`` (or a bar) at ``w`` (rad/s), its damper
    taken as :func:`linear_host` says."""
    bar, tmd, added_mass = linear_host(system)
    return tip_frf(bar, w, tmd=tmd, added_mass_kg=added_mass)


def natural_frequencies(
    bar: ModalModel, tmd: TunedMassDamper | None = None, added_mass: float = 0.0
) -> np.ndarray:
    """Undamped natural frequencies (rad/s) of the coupled linear system.

    The mass and stiffness matrices are read off the dynamic stiffness of
    :mod:`boringbar.reference.linear` (Z(0) = K, Re Z(1) = K - M), so this
    stays the one place that assembles them.
    """
    z = dynamic_stiffness(bar, np.array([0.0, 1.0]), tmd, float(added_mass)).real
    k, m = z[0], z[0] - z[1]
    return np.sqrt(scipy.linalg.eigh(k, m, eigvals_only=True))


def _frequency_grid(bar, tmd, added_mass, n_freq, freq_range) -> np.ndarray:
    """Geometric grid (rad/s): constant relative resolution at every mode."""
    n = int(check_range("n_freq", n_freq, 100, 10_000_000))
    if freq_range is None:
        wn = natural_frequencies(bar, tmd, added_mass)
        lo, hi = GRID_SPAN[0] * wn.min(), GRID_SPAN[1] * wn.max()
    else:
        try:
            f_lo, f_hi = (float(f) for f in freq_range)
        except (TypeError, ValueError):
            raise ParameterError(f"freq_range = {freq_range!r} must be (low, high) in Hz") from None
        check_positive("freq_range low", f_lo, "Hz")
        check_range("freq_range high", f_hi, f_lo, math.inf, lo_open=True, hi_open=True, unit="Hz")
        lo, hi = TWO_PI * f_lo, TWO_PI * f_hi
    return np.geomspace(lo, hi, n)


def _lobe_numbers(lobes) -> np.ndarray:
    try:
        j = np.array(list(lobes), dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"lobes = {lobes!r} must be an iterable of integers >= 0") from None
    if j.ndim != 1 or len(j) == 0 or np.any(j < 0) or np.any(j != np.round(j)):
        raise ParameterError(f"lobes = {lobes!r} must be a non-empty list of integers >= 0")
    return j.astype(int)


# --- lobes -------------------------------------------------------------------------
def analytic_lobes(
    system_or_bar,
    kr: float = KR_ALUMINIUM,
    *,
    tmd: TunedMassDamper | None = None,
    added_mass: float = 0.0,
    lobes: Iterable[int] = range(0, 40),
    n_freq: int = 20000,
    freq_range: tuple[float, float] | None = None,
) -> dict:
    """Stability lobes of regenerative turning, one curve per lobe number j.

    ``system_or_bar``: a :class:`~boringbar.model.system.System` or a
    :class:`~boringbar.model.bar.ModalModel` (then ``tmd``, ``added_mass`` (kg) as
    in :func:`~boringbar.reference.linear.tip_frf`).  ``kr`` (Pa) is the
    radial cutting-force coefficient.  The chatter frequency runs over a
    geometric grid of ``n_freq`` points, ``freq_range`` (Hz) or by default
    0.5 x the lowest to 2 x the highest undamped natural frequency of the
    coupled system (every retained mode and the absorber).

    Returns a dict: ``lobe`` (j, shape (n_lobes,)); ``rpm``, ``b_lim`` (m)
    and ``frequency_hz``, each (n_lobes, n_freq), NaN where Re G >= 0 (no
    chatter there; NaN also breaks plotted lines between separate regions);
    ``phase`` (eps, rad, (n_freq,)); ``kr``.  rpm = 60 omega / (eps + 2 pi j),
    b_lim = -1 / (2 Kr Re G) (module docstring).
    """
    kr = check_positive("kr", kr, "Pa")
    bar, tmd, added_mass = linear_host(system_or_bar, tmd, added_mass)
    w = _frequency_grid(bar, tmd, added_mass, n_freq, freq_range)
    return lobes_of_receptance(w, tip_frf(bar, w, tmd=tmd, added_mass_kg=added_mass), kr, lobes)


def lobes_of_receptance(w, g, kr: float = KR_ALUMINIUM,
                        lobes: Iterable[int] = range(0, 40)) -> dict:
    """The lobes of :func:`analytic_lobes` from a tip receptance ``g`` (m/N) sampled
    at ``w`` (rad/s, increasing): a model's, or a measured FRF as it is, without a
    modal fit (the classical frequency-domain method)."""
    kr = check_positive("kr", kr, "Pa")
    j = _lobe_numbers(lobes)
    w, g = np.asarray(w, dtype=float), np.asarray(g, dtype=complex)
    chatter = g.real < 0.0
    eps = regeneration_phase(g)
    b = np.where(chatter, -0.5 / (kr * np.where(chatter, g.real, -1.0)), np.nan)
    rpm = 60.0 * w / (eps[None, :] + TWO_PI * j[:, None])
    shape = (len(j), len(w))
    return {
        "lobe": j,
        "rpm": np.where(chatter, rpm, np.nan),
        "b_lim": np.broadcast_to(b, shape).copy(),
        "frequency_hz": np.broadcast_to(np.where(chatter, w / TWO_PI, np.nan), shape).copy(),
        "phase": eps,
        "kr": kr,
    }


def limit_at_speeds(
    system_or_bar,
    rpm,
    kr: float = KR_ALUMINIUM,
    *,
    tmd: TunedMassDamper | None = None,
    added_mass: float = 0.0,
    lobes: Iterable[int] | None = None,
    n_freq: int = 20000,
    freq_range: tuple[float, float] | None = None,
    with_frequency: bool = False,
):
    """The analytic limiting depth of cut b_lim (m) at each spindle speed ``rpm``.

    At tau = 60 / rpm every lobe that passes through this speed is a root
    omega of omega tau - eps(omega) = 2 pi j on the region Re G < 0; the
    limit is the smallest b_lim = -1 / (2 Kr Re G) over all those roots.
    Finding the roots in omega, rather than interpolating each lobe curve
    in rpm, takes the left and right branches of every lobe (and lobes that
    fold back in rpm) as they come: each sign change on the frequency grid
    is one crossing, refined by bisection to machine precision, so the
    value is exact up to crossings closer together than one grid step.

    ``lobes`` restricts j (default: every j >= 0 that the grid reaches);
    other keywords as :func:`analytic_lobes`.  Returns an array shaped like
    ``rpm`` (inf where no lobe reaches the speed), or with
    ``with_frequency`` the pair (b_lim (m), chatter frequency (Hz)).
    """
    kr = check_positive("kr", kr, "Pa")
    bar, tmd, added_mass = linear_host(system_or_bar, tmd, added_mass)
    speeds = np.asarray(rpm, dtype=float)
    flat = speeds.ravel()
    for s in flat:
        check_lobe_speed("rpm", s)
    allowed = None if lobes is None else _lobe_numbers(lobes)
    w = _frequency_grid(bar, tmd, added_mass, n_freq, freq_range)
    g = tip_frf(bar, w, tmd=tmd, added_mass_kg=added_mass)
    eps = regeneration_phase(g)
    # every speed's crossings bisected together: one FRF solve per step for all
    owner, at, j = _contenders(g, *_crossings(w, g, eps, 60.0 / flat, allowed, prune=True))
    lo, hi = w[at], w[at + 1]
    b_out = np.full(flat.shape, np.inf)
    f_out = np.full(flat.shape, np.nan)
    if owner.size:
        root = _bisect(bar, tmd, added_mass, lo, hi, j, 60.0 / flat[owner])
        re = tip_frf(bar, root, tmd=tmd, added_mass_kg=added_mass).real
        b = np.where(re < 0.0, -0.5 / (kr * np.minimum(re, -1e-300)), np.inf)
        # each speed's smallest limit, the first of equals as argmin takes it
        order = np.lexsort((np.arange(b.size), b, owner))
        first = order[np.r_[True, owner[order][1:] != owner[order][:-1]]]
        b_out[owner[first]], f_out[owner[first]] = b[first], root[first] / TWO_PI
    b_out, f_out = b_out.reshape(speeds.shape), f_out.reshape(speeds.shape)
    return (b_out, f_out) if with_frequency else b_out


def _crossings(w, g, eps, tau, allowed, prune: bool = False):
    """Every crossing at every delay ``tau`` (s): the index of its speed in ``tau``,
    of its grid step [w[i], w[i + 1]] and its lobe number j, by speed, step and j.

    h(omega) = (omega tau - eps) / 2 pi is continuous inside a region where
    Re G < 0; each integer j >= 0 it passes between two grid points is one
    lobe crossing.  The steps inside such regions are looked at from the most
    negative Re G up, in rounds; with ``prune``, a speed leaves once the steps left
    cannot hold a contender (:func:`_contenders`): their better end is above
    (1 - CONTENDER_MARGIN) times its best worse end so far, so they could neither
    be kept nor lower that end.
    """
    step = np.flatnonzero((g.real[:-1] < 0.0) & (g.real[1:] < 0.0))
    better = np.minimum(g.real[step], g.real[step + 1])
    order = np.argsort(better, kind="stable")
    step, better = step[order], better[order]
    best = np.full(tau.shape, np.inf)
    speeds, found, start, size = np.arange(tau.size), [], 0, CROSSING_FIRST
    while speeds.size and start < step.size:
        rows = max(1, CROSSING_BLOCK // max(size, 1))
        part = step[start:start + size]
        for k in range(0, speeds.size, rows):
            f = _crossed(w, eps, part, tau, speeds[k:k + rows], allowed)
            np.minimum.at(best, f[0], np.maximum(g.real[f[1]], g.real[f[1] + 1]))
            found.append(f)
        start, size = start + size, 2 * size
        if prune and start < step.size:
            speeds = speeds[~(better[start - 1] > (1.0 - CONTENDER_MARGIN) * best[speeds])]
    if not found:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int), np.zeros(0)
    speed, at, j = (np.concatenate([f[i] for f in found]) for i in range(3))
    order = np.lexsort((j, at, speed))
    return speed[order], at[order], j[order]


def _crossed(w, eps, step, tau, speeds, allowed):
    """The crossings in the grid steps ``step`` at the delays ``tau[speeds]``:
    (index of the speed, index of the step, lobe number j)."""
    h_lo = (w[step] * tau[speeds, None] - eps[step]) / TWO_PI
    h_hi = (w[step + 1] * tau[speeds, None] - eps[step + 1]) / TWO_PI
    bottom = np.floor(np.minimum(h_lo, h_hi))
    count = (np.floor(np.maximum(h_lo, h_hi)) - bottom).astype(int)
    row, col = np.nonzero(count)
    n = count[row, col]
    # the integers crossed in step i are bottom_i + 1 .. top_i
    offset = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)
    speed, at = np.repeat(speeds[row], n), np.repeat(step[col], n)
    j = np.repeat(bottom[row, col], n) + 1 + offset
    keep = j >= 0
    if allowed is not None:
        keep &= np.isin(j, allowed)
    return speed[keep], at[keep], j[keep]


def _contenders(g, speed, at, j):
    """The crossings that can hold their speed's smallest limit: Re G at the root
    lies between its values at the bracket's ends (the bracket is one step of a fine
    grid, where Re G bends by far less than the margin), so a crossing whose better
    end is CONTENDER_MARGIN short of the best worse end of its speed cannot win (a
    speed's only crossing is kept)."""
    better = np.minimum(g.real[at], g.real[at + 1])
    worse = np.maximum(g.real[at], g.real[at + 1])
    starts = np.flatnonzero(np.r_[True, speed[1:] != speed[:-1]]) if speed.size else \
        np.zeros(0, dtype=int)
    count = np.diff(np.r_[starts, speed.size])
    best = np.repeat(np.minimum.reduceat(worse, starts), count) if speed.size else worse
    keep = np.repeat(count < 2, count) | (better <= (1.0 - CONTENDER_MARGIN) * best)
    return speed[keep], at[keep], j[keep]


def _bisect(bar, tmd, added_mass, lo, hi, j, tau):
    """Vectorised bisection of omega tau - eps(omega) - 2 pi j on [lo, hi]."""
    lo, hi = lo.copy(), hi.copy()

    def f(x):
        return (
            x * tau
            - regeneration_phase(tip_frf(bar, x, tmd=tmd, added_mass_kg=added_mass))
            - TWO_PI * j
        )

    f_lo = f(lo)
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        if np.all((mid == lo) | (mid == hi)):
            break  # adjacent doubles everywhere: the rest would change nothing
        f_mid = f(mid)
        same = np.sign(f_mid) == np.sign(f_lo)
        lo, f_lo = np.where(same, mid, lo), np.where(same, f_mid, f_lo)
        hi = np.where(same, hi, mid)
    return 0.5 * (lo + hi)


def sampled_limits(w, g, rpm, kr: float = KR_ALUMINIUM) -> dict:
    """The analytic limit of a tip receptance known only at samples ``w`` (rad/s),
    ``g`` (m/N), as measured: ``min_limit`` -1 / (2 Kr min Re G) over the samples
    and its ``frequency_hz``; ``limit`` (m) at each speed of ``rpm``, from every
    lobe crossing of :func:`limit_at_speeds` between two samples, the frequency and
    Re G interpolated linearly between them (inf where no lobe reaches a speed)."""
    kr = check_positive("kr", kr, "Pa")
    w, g = np.asarray(w, dtype=float), np.asarray(g, dtype=complex)
    eps = regeneration_phase(g)
    i = int(np.argmin(g.real))
    low = -0.5 / (kr * g.real[i]) if g.real[i] < 0.0 else math.inf
    speeds = np.atleast_1d(np.asarray(rpm, dtype=float))
    for speed in speeds.ravel():
        check_lobe_speed("rpm", speed)
    tau, limits = 60.0 / speeds.ravel(), np.full(speeds.size, np.inf)
    speed, a, j = _crossings(w, g, eps, tau, None)
    h_lo = (w[a] * tau[speed] - eps[a]) / TWO_PI - j
    h_hi = (w[a + 1] * tau[speed] - eps[a + 1]) / TWO_PI - j
    t = h_lo / (h_lo - h_hi)
    re = (1 - t) * g.real[a] + t * g.real[a + 1]
    b = np.where(re < 0.0, -0.5 / (kr * np.minimum(re, -1e-300)), np.inf)
    np.minimum.at(limits, speed, b)
    return {"min_limit": low, "frequency_hz": w[i] / TWO_PI, "rpm": speeds,
            "limit": limits.reshape(speeds.shape)}


def min_limit(
    system_or_bar,
    kr: float = KR_ALUMINIUM,
    *,
    tmd: TunedMassDamper | None = None,
    added_mass: float = 0.0,
    n_freq: int = 20000,
    freq_range: tuple[float, float] | None = None,
) -> float:
    """The absolute (speed-independent) limiting depth -1 / (2 Kr min Re G) (m).

    The bottom of every lobe touches it.  min Re G is searched on the grid
    of :func:`analytic_lobes` and refined by
    :func:`~boringbar.reference.linear.min_real_part`.  For one mode with tip
    stiffness k = K / psi_L^2 and damping ratio zeta it is
    2 k zeta (1 + zeta) / Kr, reached at omega = omega_n sqrt(1 + 2 zeta).
    """
    kr = check_positive("kr", kr, "Pa")
    bar, tmd, added_mass = linear_host(system_or_bar, tmd, added_mass)
    w = _frequency_grid(bar, tmd, added_mass, n_freq, freq_range)
    re, _ = min_real_part(bar, tmd, w, added_mass_kg=added_mass)
    return math.inf if re >= 0.0 else -0.5 / (kr * re)
