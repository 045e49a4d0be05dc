"""Where the events of a shooting regime fall (docs/continuation.md, "Shooting").

Between events the augmented state z = [x, sin Omega t, cos Omega t, 1] moves by
expm(A dt) (:mod:`boringbar.orbits.shooting`).  The events are the walls (y = +-delta/2
moving outward), y' = 0 of a ball with friction, and a rolling ball's slip coming to zero
and the friction rolling needs reaching +-mu_s N.  :func:`next_event` brackets them on
the grid of 64 steps a period and locates them by Brent's method on the closed form of
the ball's relative motion (:class:`Relative`) or on expm(A s) z.  Between grid points it
also finds a wall reached beyond an extremum of y, and an event function, linear in z,
that turns back towards zero within a step and crosses it twice.  ``fl`` is a shooting
:class:`~boringbar.orbits.shooting.Flow`.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq

#: Event kinds recorded in a period's event log: the walls, y' = 0 (F_b changes sign) and a
#: rolling ball's slip coming to zero and the friction rolling needs reaching +-mu_s N.
KINDS = ("impact+", "impact-", "reversal", "slip-zero", "roll-limit+", "roll-limit-")


def spin_index(fl) -> int:
    """The index of a rolling ball's spin s = r omega in the state (its last entry)."""
    return 2 * fl.n + 2


def unit(N: int, i: int) -> np.ndarray:
    """The unit vector e_i of length N."""
    v = np.zeros(N)
    v[i] = 1.0
    return v


def _event_fn(fl, mode: tuple, keep: np.ndarray | None):
    """The event values g(z) of FREE in ``mode`` (sdir, fdir): y - half, y + half, y' (if
    sliding with friction); a rolling ball's slip y' - s (slipping) and, rolled, the
    friction rolling needs (``keep``, a row on z) less and plus mu_s N.  An event function
    that does not apply is 1."""
    j = 2 * fl.n
    sdir, fdir = mode

    def g(z):
        rev = z[j + 1] if (fl.fc > 0.0 and sdir != 0.0) else 1.0
        if not fl.roll:
            return np.array([z[j] - fl.half, z[j] + fl.half, rev])
        slip, k = (z[j + 1] - z[j + 2], 0.0) if fdir != 0.0 else (1.0, float(keep @ z))
        lo, hi = (1.0, 1.0) if fdir != 0.0 else (k - fl.mus_n, k + fl.mus_n)
        return np.array([z[j] - fl.half, z[j] + fl.half, rev, slip, lo, hi])
    return g


#: The event indices whose function crosses zero upwards (a wall, the roll limit +mu_s N)
#: and downwards; the others (y', the slip) count a crossing either way.
UPWARD, DOWNWARD = (0, 4), (1, 5)


@dataclass(frozen=True)
class Watched:
    """The events after the walls that apply in a mode (:func:`watched`), each function
    linear in z, f = G z - off (y'; a slipping ball's slip y' - s; the friction rolling
    needs less and plus mu_s N), with its rate G A z: event indices, G, G A and off."""

    idx: tuple
    G: np.ndarray
    GA: np.ndarray
    off: np.ndarray

    def at(self, z: np.ndarray) -> list:
        """[(function, rate)] at z, one pair an event (Python floats: a step's test)."""
        return list(zip((self.G @ z - self.off).tolist(), (self.GA @ z).tolist(), strict=True))


def watched(fl, mode: tuple, keep, A: np.ndarray) -> Watched | None:
    """The :class:`Watched` events of ``mode`` (regime matrix A, rolled keep row), None if
    there are none."""
    N, j = fl.N, 2 * fl.n
    sdir, fdir = mode
    rows = {}
    if fl.fc > 0.0 and sdir != 0.0:
        rows[2] = (unit(N + 3, j + 1), 0.0)
    if fl.roll and fdir != 0.0:
        rows[3] = (unit(N + 3, j + 1) - unit(N + 3, spin_index(fl)), 0.0)
    elif fl.roll:
        rows[4], rows[5] = (keep, fl.mus_n), (keep, -fl.mus_n)
    if not rows:
        return None
    G = np.array([r for r, _ in rows.values()])
    return Watched(tuple(rows), G, G @ A, np.array([o for _, o in rows.values()]))


def _quiet(fl, zk, zn, fk, fn) -> bool:
    """Whether a grid step from zk to zn meets no event (most do): y inside at the end,
    y' of one sign, and each watched event function (fk, fn: :meth:`Watched.at` at the
    ends, or None) of one sign at both ends and not turning back towards zero within the
    step (moving towards it at the start, away at the end: two crossings, :func:`_turned`)."""
    j, half = 2 * fl.n, fl.half
    vk, vn = zk[j + 1], zn[j + 1]
    if not (-half < zn[j] < half and (vk > 0.0) == (vn > 0.0) and (vk < 0.0) == (vn < 0.0)):
        return False
    if fk is None:
        return True
    for (f0, d0), (f1, d1) in zip(fk, fn, strict=True):
        if not f0 * f1 > 0.0 or (f0 * d0 < 0.0 and f1 * d1 > 0.0):
            return False
    return True


def _turned(rel, g, A, zk, step, i, row, ends, fresh):
    """The time in (0, step) of event i's crossing where its function crosses zero twice
    within the grid step (out and back) or, ``fresh`` (zero at the step's start, just after
    an event), leaves zero and comes back across it; None if not.  Between grid points 64
    a period apart the slip of a rolling ball can change sign and change back (a slip of
    1e-4 m/s against y' that rises through the spin and falls back), where the ends alone
    see nothing.  ends: (value, rate) of the function at the step's ends
    (:meth:`Watched.at`)."""
    (f0, d0), (f1, d1) = ends
    if not d0 * d1 < 0.0:
        return None
    sigma = math.copysign(1.0, d0 if fresh else f0)
    if fresh and sigma * f1 < 0.0:  # left zero, turned and came back across
        s_ext = _extremum(A, zk, row, step)
        z_ext = expm(A * s_ext) @ zk
        return s_ext + _root(rel, g, A, z_ext, i, step - s_ext)
    if fresh or not (sigma * f1 > 0.0 and sigma * d0 < 0.0):
        return None
    # the cubic through the ends' values and rates dips by less than half the nearer
    # end's distance from zero: no crossing (the step is 1/64 period, where the cubic's
    # error is far smaller), and the costly search is skipped
    p0, p1 = sigma * f0, sigma * f1
    if _cubic_min(p0, p1, sigma * d0 * step, sigma * d1 * step) > 0.5 * min(p0, p1):
        return None
    s_ext = _extremum(A, zk, row, step)
    if sigma * _g_at(s_ext, g, A, zk, i) > 0.0:
        return None
    return _root(rel, g, A, zk, i, s_ext)


def _cubic_min(p0: float, p1: float, m0: float, m1: float) -> float:
    """The least value on [0, 1] of the cubic Hermite interpolant with values p0, p1 and
    slopes m0, m1 (per unit of the interval) at its ends."""
    # H'(s) = a s^2 + b s + c
    a, b, c = 6.0 * (p0 - p1) + 3.0 * (m0 + m1), 6.0 * (p1 - p0) - 4.0 * m0 - 2.0 * m1, m0
    if a != 0.0:
        disc = b * b - 4.0 * a * c
        sq = math.sqrt(disc) if disc >= 0.0 else math.nan
        roots = ((-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a))
    else:
        roots = (-c / b,) if b != 0.0 else ()
    low = min(p0, p1)
    for x in roots:
        if 0.0 < x < 1.0:
            low = min(low, (2 * x**3 - 3 * x**2 + 1) * p0 + (x**3 - 2 * x**2 + x) * m0
                      + (-2 * x**3 + 3 * x**2) * p1 + (x**3 - x**2) * m1)
    return low


def _extremum(A, z, row, step) -> float:
    """The zero in (0, step) of the rate row . z' of a linear event function after z."""
    return brentq(lambda s: float(row @ (A @ (expm(A * s) @ z))), 0.0, step,
                  xtol=1e-18, rtol=1e-15, maxiter=200)


def next_event(fl, reg, mode, z, t, t_stop, h):
    """(time, kind) of the first event after t before t_stop, or (t_stop, None); reg: the
    mode's regime (A, expm(A h) the grid step's flow, its Relative, its keep row, its
    :func:`watched` events)."""
    if not fl.ball:
        return t_stop, None
    A, E, rel, keep, w = reg
    g = _event_fn(fl, mode, keep)
    zk, tk = z, t
    fk = w.at(zk) if w else None
    while tk < t_stop:
        step = min(h, t_stop - tk)
        zn = E @ zk if step == h else expm(A * step) @ zk
        fn = w.at(zn) if w else None
        if _quiet(fl, zk, zn, fk, fn):
            zk, tk, fk = zn, tk + step, fn
            continue
        gk, gn = g(zk), g(zn)
        hits = []
        for i in range(len(gn)):
            fresh = tk == t and abs(gk[i]) < 1e-14
            s = None
            if _crossed(i, gk[i], gn[i]) and not fresh:
                s = _root(rel, g, A, zk, i, step)
            elif i < 2:
                s = _through_wall(fl, rel, g, A, zk, zn, step, i)
            elif w and i in w.idx:
                k = w.idx.index(i)
                s = _turned(rel, g, A, zk, step, i, w.G[k], (fk[k], fn[k]), fresh)
            if s is not None:
                hits.append((s, KINDS[i]))
        if hits:
            s, kind = min(hits)
            return tk + s, kind
        zk, tk, fk = zn, tk + step, fn
    return t_stop, None


class Relative:
    """The ball's relative position y and velocity y' on one regime in closed form, for
    locating events.  In flight the bar's modes do not feel the ball: mode i obeys
    u'' + 2 zeta w u' + w^2 u = a_i sin(Omega t) + b_i (a_i, b_i: A's forcing and
    constant entries), so u_i(s) = Re(C_i e^{lambda_i s}) + Im(a_i G_i E e^{i Omega s})
    + b_i / w^2, lambda_i = -zeta w + i w_d, G_i = 1 / (w^2 - Omega^2 + 2 i zeta w Omega),
    E = cos + i sin of the forcing phase at s = 0 and C_i from u_i(0), u_i'(0).  Then
    y'' = -psi_d . u'' + F_b / m gives y'(s) = y'0 - psi_d . (u'(s) - u'0) + F_b s / m and
    y(s) = y0 + (y'0 + psi_d . u'0) s - psi_d . (u(s) - u0) + F_b s^2 / (2 m), with
    u(s) - u0 from e^{x} - 1 (exact at s = 0).  An evaluation is n + 1 complex
    exponentials, where expm(A s) z is a matrix exponential: Brent's method calling it
    was half of an orbit map's time.  A slipping rolling ball's spin is linear in time,
    s(s) = s0 + A's constant spin entry times s, which gives its slip y' - s.  A mode
    without oscillation (zeta >= 1), a rolled ball (``closed`` False: the bar carries part
    of it, so the modes feel it) and the roll limit's events raise LinAlgError, and the
    caller falls back on expm."""

    def __init__(self, fl, A: np.ndarray, closed: bool = True):
        n, N = fl.n, fl.N
        self.fl = fl
        # K / M and C / M as the core's equations of motion give them, A's diagonal
        w2, c = -np.diagonal(A[n:2 * n, :n]), -np.diagonal(A[n:2 * n, n:2 * n])
        alpha, beta2 = -0.5 * c, w2 - 0.25 * c * c
        self.ok = closed and bool(np.all(beta2 > 0.0))
        self.lam = alpha + 1j * np.sqrt(np.maximum(beta2, 0.0))
        om = fl.omega
        self.pd = fl.psi_d
        # a_i G_i, a_i the sin state's entry of A (per unit mass), and the constant's share
        self.q = A[n:2 * n, N] / (w2 - om * om + 1j * c * om)
        self.const = A[n:2 * n, N + 2] / w2
        # A's y'' row is -psi_d . (the bar's rows) + F_b / m on the constant state
        self.fb_m = A[2 * n + 1, N + 2] + fl.psi_d @ A[n:2 * n, N + 2]
        self.spin_rate = A[spin_index(fl), N + 2] if fl.roll else 0.0

    def event(self, z: np.ndarray, i: int):
        """s -> event function i (y - half, y + half, y', the slip; :func:`_event_fn`) after
        the state z (augmented); i = EXTREMUM: y' too (its zero is an extremum of y)."""
        if not self.ok or i > 3:
            raise np.linalg.LinAlgError("no closed form (a mode that does not oscillate, "
                                        "zeta >= 1, or a rolled ball)")
        fl, n, N, lam = self.fl, self.fl.n, self.fl.N, self.lam
        iom = 1j * fl.omega
        forced = self.q * (z[N + 1] + 1j * z[N])  # a G E: the modes' forced parts, complex
        pe = complex(self.pd @ forced)
        uh = z[:n] - forced.imag - self.const  # the modes' free parts at s = 0
        vh = z[n:2 * n] - (forced * iom).imag
        C = uh + 1j * (lam.real * uh - vh) / lam.imag
        cu, cv = self.pd * C, self.pd * C * lam
        y0, v0, fb_m = z[2 * n], z[2 * n + 1], self.fb_m
        if i in (2, 3, EXTREMUM):
            s0, sd = (z[2 * n + 2], self.spin_rate) if i == 3 else (0.0, 0.0)
            return lambda s: (v0 - float((cv @ (np.exp(lam * s) - 1.0)).real)
                              - (pe * iom * (cmath.exp(iom * s) - 1.0)).imag + fb_m * s
                              - (s0 + sd * s))
        y0 = y0 - (fl.half if i == 0 else -fl.half)
        v = v0 + float(self.pd @ z[n:2 * n])
        return lambda s: (y0 + v * s - float((cu @ (np.exp(lam * s) - 1.0)).real)
                          - (pe * (cmath.exp(iom * s) - 1.0)).imag + 0.5 * fb_m * s * s)


#: The extremum of y (y' = 0) as an "event" of :func:`_root`.
EXTREMUM = -1


def _root(rel: Relative, g, A, z, i: int, step: float) -> float:
    """The zero in (0, step) of event function i (or y' for i = EXTREMUM) after the state
    z, by Brent's method on the closed form (:class:`Relative`); on expm(A s) z where the
    closed form's rounding puts both ends on one side (an end within rounding of zero)."""
    try:
        return brentq(rel.event(z, i), 0.0, step, xtol=1e-18, rtol=1e-15, maxiter=200)
    except (ValueError, np.linalg.LinAlgError):
        args = (g, A, z, i) if i != EXTREMUM else (_velocity, A, z, 2 * rel.fl.n + 1)
        return brentq(_g_at, 0.0, step, args=args, xtol=1e-18, rtol=1e-15, maxiter=200)


def _through_wall(fl, rel: Relative, g, A, zk, zn, step, i):
    """The time in (0, step) at which the ball reaches wall i (0: +, 1: -) though it is
    inside at both ends of the grid step: y has an extremum in the step (y' turns from
    outward to inward) beyond the wall; None if not.  Without this a shallow incursion
    between grid points (an impact born at a grazing) is missed, and a grazing is
    located late (2.8e-5 relative at 172 N, gap 0.5 mm, docs/continuation.md)."""
    j = 2 * fl.n
    out = 1.0 if i == 0 else -1.0
    if not (out * zk[j + 1] > 0.0 > out * zn[j + 1] and out * g(zk)[i] < 0.0):
        return None
    s_ext = _root(rel, g, A, zk, EXTREMUM, step)
    try:
        beyond = out * rel.event(zk, i)(s_ext)
    except np.linalg.LinAlgError:
        beyond = out * _g_at(s_ext, g, A, zk, i)
    if beyond < 0.0:
        return None
    return _root(rel, g, A, zk, i, s_ext)


def _velocity(z):
    """The state itself, as an event function (index it with y' for the extremum)."""
    return z


def _g_at(s, g, A, z, i):
    """Event function i at time s after the state z (closed form)."""
    return g(expm(A * s) @ z)[i]


def _crossed(i, a, b) -> bool:
    """A sign change of event function i in its direction (:data:`UPWARD`,
    :data:`DOWNWARD`, else either)."""
    if i in UPWARD:
        return a < 0.0 <= b
    if i in DOWNWARD:
        return a > 0.0 >= b
    return a * b <= 0.0 and a != b
