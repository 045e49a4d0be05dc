"""A slow, obviously-correct reference of the published scheme (docs/model.md, sections 1-3, 5).

Written from docs/model.md, not from the kernel: the right-hand side is a plain
function f(t, x), the RK4 step is written out with k1..k4, and the wall rule
and impact law of docs/model.md, section 2 are applied after every step.  It reads
the same packed parameter vector ``p`` as the kernel (slots named in
:mod:`boringbar.simulate.layout`), so both run the same configuration; of the
derived slots it uses none (the effective impact mass is recomputed here).

State x = [u_1..u_n, u_1'..u_n', aux, aux'] with aux the ball's relative
displacement y = u_d - psi_d . u (ball, locked ball) or the absorber's
absolute displacement x_a (TMD).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from boringbar.simulate import layout as L


@dataclass(frozen=True)
class Model:
    """The parameters of ``p``, unpacked and named as in docs/model.md."""

    case: int
    n: int
    F0: float
    Omega: float
    M: np.ndarray
    K: np.ndarray
    C: np.ndarray
    psi_L: np.ndarray
    psi_d: np.ndarray
    psi_a: np.ndarray
    m: float  # ball mass
    half_gap: float  # delta / 2
    e: float
    F_c: float
    sr: float  # +1: the bar feels -psi_d F_b (reciprocal); -1: +psi_d F_b (printed)
    m_a: float
    k_a: float
    c_a: float

    @classmethod
    def from_packed(cls, p: np.ndarray) -> Model:
        n = int(p[L.N_MODES])
        block = lambda start: np.array(p[start:start + n], dtype=float)  # noqa: E731
        return cls(case=int(p[L.CASE]), n=n, F0=p[L.F0], Omega=p[L.OMEGA], M=block(L.M_),
                   K=block(L.K_), C=block(L.C_), psi_L=block(L.PSI_L), psi_d=block(L.PSI_D),
                   psi_a=block(L.PSI_A), m=p[L.BALL_MASS], half_gap=p[L.HALF_GAP],
                   e=p[L.RESTITUTION], F_c=p[L.FRICTION], sr=p[L.REACTION],
                   m_a=p[L.TMD_MASS], k_a=p[L.TMD_K], c_a=p[L.TMD_C])

    def force(self, t: float) -> float:
        """The cutting force at the tip, f(t) = F0 sin(Omega t)."""
        return self.F0 * np.sin(self.Omega * t)


def rhs(model: Model, t: float, x: np.ndarray) -> np.ndarray:
    """dx/dt of the modal equations (docs/model.md, sections 1-3)."""
    n = model.n
    u, v = x[:n], x[n:2 * n]
    aux, aux_d = x[2 * n], x[2 * n + 1]
    # generalised forces on the modes from the bar itself and the cutting force
    Q = model.psi_L * model.force(t) - model.C * v - model.K * u
    dx = np.zeros_like(x)
    dx[:n] = v
    if model.case == L.SOLID:
        dx[n:2 * n] = Q / model.M
    elif model.case == L.BALL:
        F_b = -model.F_c * np.sign(aux_d)  # np.sign(0) = 0
        # the bar feels -psi_d F_b (reciprocal, sr = +1) or +psi_d F_b (printed, sr = -1)
        u_dd = (Q - model.sr * model.psi_d * F_b) / model.M
        dx[n:2 * n] = u_dd
        dx[2 * n] = aux_d
        dx[2 * n + 1] = F_b / model.m - model.psi_d @ u_dd  # y'' = F_b/m - psi_d . u''
    elif model.case == L.TMD:
        stroke = aux - model.psi_a @ u
        stroke_d = aux_d - model.psi_a @ v
        spring = model.k_a * stroke + model.c_a * stroke_d
        dx[n:2 * n] = (Q + model.psi_a * spring) / model.M
        dx[2 * n] = aux_d
        dx[2 * n + 1] = -spring / model.m_a
    elif model.case == L.LOCKED:
        # the ball moves with the bar, u_d = psi_d . u + y with y fixed: the constraint
        # force on it is m psi_d . u'', and the bar feels its reaction, so
        # (diag M + m psi_d psi_d^T) u'' = Q
        A = np.diag(model.M) + model.m * np.outer(model.psi_d, model.psi_d)
        dx[n:2 * n] = np.linalg.solve(A, Q)
    else:
        raise ValueError(f"unknown case {model.case}")
    return dx


def rk4_step(model: Model, t: float, x: np.ndarray, h: float) -> np.ndarray:
    """One classical RK4 step of the smooth equations."""
    k1 = rhs(model, t, x)
    k2 = rhs(model, t + h / 2, x + h / 2 * k1)
    k3 = rhs(model, t + h / 2, x + h / 2 * k2)
    k4 = rhs(model, t + h, x + h * k3)
    return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def impact(model: Model, x: np.ndarray) -> np.ndarray:
    """Apply the impact law to a state with the ball on a wall, moving outward.

    An impulse J on the ball and -J psi_d,i on mode i, with the restitution law
    y'+ = -e y'- on the relative velocity:  J = -(1 + e) m_eff y'-,
    u_i'+ = u_i'- + (1 + e) m_eff psi_d,i y'- / M_i,
    m_eff = 1 / (1/m + sum_i psi_d,i^2 / M_i).
    """
    n = model.n
    x = x.copy()
    y_d = x[2 * n + 1]
    m_eff = 1.0 / (1.0 / model.m + np.sum(model.psi_d**2 / model.M))
    J = -(1.0 + model.e) * m_eff * y_d
    x[n:2 * n] += -J * model.psi_d / model.M
    x[2 * n + 1] = -model.e * y_d
    return x


def walls(model: Model, x: np.ndarray) -> tuple[np.ndarray, tuple | None]:
    """The wall rule of docs/model.md, section 2 at the end of a step.

    Returns the new state and (wall, y'-) if the impact law was applied.
    """
    n = model.n
    y, y_d = x[2 * n], x[2 * n + 1]
    if abs(y) < model.half_gap:
        return x, None
    wall = 1.0 if y > 0 else -1.0
    x = x.copy()
    x[2 * n] = wall * model.half_gap  # back on the wall
    if y * y_d > 0:  # moving outward
        return impact(model, x), (wall, y_d)
    return x, None


def run(p: np.ndarray, x0: np.ndarray, t0: float, dt: float, n_steps: int):
    """Integrate ``n_steps`` steps from ``x0`` at ``t0``.

    Returns (t, X, impacts): the times t_k = t0 + k dt and states X[k] for
    k = 0..n_steps, and the list of every impact law applied as
    (time at the end of the step, wall +1/-1, y'- before).
    """
    model = Model.from_packed(p)
    n = model.n
    x = np.array(x0, dtype=float)
    if model.case == L.LOCKED:
        x[2 * n + 1] = 0.0  # the locked ball has no relative velocity
    t = t0 + dt * np.arange(n_steps + 1)
    X = np.empty((n_steps + 1, x.size))
    X[0] = x
    impacts = []
    for k in range(n_steps):
        x = rk4_step(model, t[k], x, dt)
        if model.case == L.BALL:
            x, hit = walls(model, x)
            if hit is not None:
                impacts.append((t[k + 1], hit[0], hit[1]))
        X[k + 1] = x
    return t, X, impacts


def tip(p: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Tip displacement W = psi_L . u for states X (rows)."""
    n = int(p[L.N_MODES])
    return X[..., :n] @ p[L.PSI_L:L.PSI_L + n]


# --- regenerative cutting (docs/model.md, section 4) -------------------------------------------
@dataclass(frozen=True)
class CutModel(Model):
    """A :class:`Model` whose tip force is given: the cutting force of one RK4 stage."""

    tip_force: float = 0.0

    def force(self, t: float) -> float:
        return self.tip_force


def delayed_tip(W: list, Wd: list, s: float, dt: float, w_before: float, cubic: bool) -> float:
    """W at time ``s`` (s after the cut began) from the full history of step-end values
    W[g], W'[g] at times g dt; before the cut the surface is ``w_before`` (W' = 0).

    Between two stored nodes: cubic Hermite from W and W' at both ends, or linear.
    """
    q = s / dt
    a = int(np.floor(q))
    fr = q - a

    def node(g):
        return (W[g], Wd[g]) if g >= 0 else (w_before, 0.0)

    wa, wda = node(a)
    wb, wdb = node(a + 1)
    if not cubic:
        return (1.0 - fr) * wa + fr * wb
    h00 = 2 * fr**3 - 3 * fr**2 + 1
    h10 = fr**3 - 2 * fr**2 + fr
    h01 = -2 * fr**3 + 3 * fr**2
    h11 = fr**3 - fr**2
    return h00 * wa + h10 * dt * wda + h01 * wb + h11 * dt * wdb


MASK64 = 2**64 - 1


def mix64(z: int) -> int:
    """splitmix64's output function on a 64-bit word (Steele, Lea and Flood 2014)."""
    z = (z + 0x9E3779B97F4A7C15) & MASK64
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK64
    return z ^ (z >> 31)


def normal_at(seed: int, j: int) -> float:
    """The j-th standard normal deviate of stream ``seed`` (docs/model.md, section 4.4):
    Box-Muller of u1 = (top 53 bits of mix(mix(seed) ^ mix(2j)) + 1) 2^-53 in (0, 1]
    and u2 = (top 53 bits of mix(mix(seed) ^ mix(2j + 1))) 2^-53 in [0, 1)."""
    key = mix64(seed)
    a = mix64(key ^ mix64((2 * j) & MASK64))
    b = mix64(key ^ mix64((2 * j + 1) & MASK64))
    u1 = ((a >> 11) + 1) * 2.0**-53
    u2 = (b >> 11) * 2.0**-53
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


def noise_gain(p: np.ndarray, dt: float, step: int) -> float:
    """The force's factor max(0, 1 + eps_j) in step ``step`` of a cut: eps_j of the
    interval j = step // n, n = round(NOISE_INTERVAL / dt) steps (at least 1)."""
    std = p[L.NOISE_STD]
    if std == 0.0:
        return 1.0
    n = max(1, round(p[L.NOISE_INTERVAL] / dt))
    return max(0.0, 1.0 + std * normal_at(int(p[L.NOISE_SEED]), step // n))


def cutting_force(p: np.ndarray, h: float) -> float:
    """The cutting law at chip thickness h >= 0: KR_B h (linear, CUT_MC = 0) or
    KR_B h^(1 - m_c) (Kienzle's, KR_B = K b (1 mm)^m_c)."""
    mc = p[L.CUT_MC]
    return p[L.KR_B] * h if mc == 0.0 else p[L.KR_B] * h ** (1.0 - mc)


def regenerative_run(p: np.ndarray, x0: np.ndarray, dt: float, n_steps: int):
    """Integrate a regenerative cut for ``n_steps`` RK4 steps from ``x0`` at t = 0.

    At every stage the cutting force is f = F(h) (1 + eps) with
    h = max(0, min_{k=1..N} [k h_m + W(t - k tau)] - W(t)), the delayed W read
    from the full stored history (:func:`delayed_tip`), W(t) = psi_L . u of the
    stage state, F the cutting law (:func:`cutting_force`) and 1 + eps the step's
    noise factor (:func:`noise_gain`).  Returns (t, X, force, first_zero, zero_steps):
    times and states at every step end, the force at each step's last stage (what the
    kernel records), the first stage time with h = 0 (None if never) and the number
    of steps with h = 0 at some stage.
    """
    model = CutModel.from_packed(p)
    n = model.n
    feed, tau = p[L.FEED], p[L.TAU]
    revs, cubic, w_before = int(p[L.N_REV]), p[L.INTERP] > 0.0, p[L.HIST_W0]
    x = np.array(x0, dtype=float)
    if model.case == L.LOCKED:
        x[2 * n + 1] = 0.0
    W = [float(model.psi_L @ x[:n])]
    Wd = [float(model.psi_L @ x[n:2 * n])]
    X = np.empty((n_steps + 1, x.size))
    X[0] = x
    force = np.empty(n_steps)
    first_zero, zero_steps = None, 0

    def chip(ts: float, xs: np.ndarray) -> float:
        surface = min(k * feed + delayed_tip(W, Wd, ts - k * tau, dt, w_before, cubic)
                      for k in range(1, revs + 1))
        return max(0.0, surface - float(model.psi_L @ xs[:n]))

    for step in range(n_steps):
        t = step * dt
        gain = noise_gain(p, dt, step)
        ks, zero = [], False
        xs = x
        for c, a in ((0.0, 0.0), (0.5, 0.5), (0.5, 0.5), (1.0, 1.0)):
            if ks:
                xs = x + a * dt * ks[-1]
            h = chip(t + c * dt, xs)
            if h == 0.0:
                zero = True
                if first_zero is None:
                    first_zero = t + c * dt
            f = cutting_force(p, h) * gain
            ks.append(rhs(replace(model, tip_force=f), t + c * dt, xs))
        x = x + dt / 6 * (ks[0] + 2 * ks[1] + 2 * ks[2] + ks[3])
        if model.case == L.BALL:
            x, _ = walls(model, x)
        force[step] = f
        zero_steps += zero
        X[step + 1] = x
        W.append(float(model.psi_L @ x[:n]))
        Wd.append(float(model.psi_L @ x[n:2 * n]))
    return dt * np.arange(n_steps + 1), X, force, first_zero, zero_steps
