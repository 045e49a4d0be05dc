"""Periodic orbits of the regenerative cut: chatter orbits (docs/continuation.md).

The autonomous cut is the linear host of a system (the bar, a tuned mass damper, a
locked ball: :meth:`~boringbar.model.system.System.linear_host`) under the cutting force
(docs/model.md, section 4):

    M u'' + C u' + K u = p F(b, h),      W = c . u,
    h(t) = max(0, min_{k=1..N} [k h_m + W(t - k tau)] - W(t)),

p and c the mode shapes at the tip.  A periodic orbit of period T is its own history:
W(t - k tau) = W(t - k tau mod T).  It is discretised as the RK4 integrator keeps a cut:
m steps of dt = T / m, the state x = (u, u') at each node, and the delayed W at each
stage from the cubic Hermite through the neighbouring nodes' W and W', here the nodes
of the orbit itself.  The unknowns are the m node states, T and the continued parameter
(the depth b, or the delay tau, which sets the speed); the equations are the m RK4 steps,
closed around the period, and the phase condition W'(0) = 0 (the orbit starts at the
tip's largest excursion).  Because every node sees its delays at the
same fraction of a step, the discretised orbit of a linear bar in the cut is an exact
discrete harmonic, and its frequency and depth meet the frequency-domain
characteristic equation to O(dt^4).

Floquet multipliers come from the discretised map: a perturbation of the history (the
nodes over the longest delay in use) carried one period by the linearised steps.  The
map is applied by the compiled core (a forward recursion over the nodes) and its
largest eigenvalues found by ARPACK.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from boringbar.model.cutting import CuttingLaw, cutting_law
from boringbar.model.forcing import Regenerative
from boringbar.model.system import System
from boringbar.simulate import pack
from boringbar.simulate.kernels import cut_history_map, regime_matrix

#: RK4 stages' times within a step; stages 2 and 3 share the middle one.
STAGE_TIMES = np.array([0.0, 0.5, 1.0])
#: RK4's stages: where each is taken (a fraction of the step along the previous stage),
#: its weight, and which of the three stage times its delayed W is read at.
RK4_COEF, RK4_WEIGHTS, RK4_DELAY = (0.0, 0.5, 0.5, 1.0), (1.0, 2.0, 2.0, 1.0), (0, 1, 1, 2)
#: Steps per period of the discretised orbit (the Hopf point meets the characteristic
#: equation to about 1e-9 at this count; docs/continuation.md shows the order).
STEPS = 200
#: Multipliers computed at each orbit (the largest in modulus), and ARPACK's tolerance.
MULTIPLIERS, EIG_TOL = 4, 1e-10
#: Unknowns up to which the Newton matrix is factorised densely.
DENSE_LU = 1700
#: Relative step of the finite differences in T and b.
FD_STEP = 1e-7


class CutOrbitError(ValueError):
    """Newton's method found no orbit from this start."""


@dataclass(frozen=True)
class CutModel:
    """The cut's equations in first-order form x' = A x + g F(b, h), W = c . x."""

    a: np.ndarray  #: (s, s) state matrix of the linear host
    g: np.ndarray  #: (s,) the force's column: (0, M^-1 p)
    c: np.ndarray  #: (s,) tip displacement W = c . x
    cv: np.ndarray  #: (s,) tip velocity W' = cv . x
    feed: float  #: h_m (m)
    revolutions: int  #: N
    law: CuttingLaw

    @property
    def size(self) -> int:
        return len(self.g)

    def force(self, b: float, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """F(b, h) and dF/dh (N, N/m) where h > 0; both 0 out of the cut."""
        inside = h > 0.0
        f = np.asarray(self.law.force_n(b, h), dtype=float)
        if self.law.linear_law:
            return f, np.where(inside, self.law.kr_pa * b, 0.0)
        return f, np.where(inside, (1.0 - self.law.exponent) * f / np.where(inside, h, 1.0), 0.0)


def cut_model(system: System, forcing: Regenerative) -> CutModel:
    """The autonomous cut of ``system``'s linear host under ``forcing``'s law, feed and
    revolutions (its depth and speed are the orbit's: :class:`Orbit`).  The state matrix
    and the force's column are the core's (``regime_matrix``: the equations RK4 steps
    with; a locked ball's carrying term, an absorber), taken on x = (u, x_a, u', x_a')."""
    host = system.linear_host()
    n, absorber = host.bar.n_modes, host.kind == "tmd"
    # the core's state is [u, u', aux, aux', sin, cos, 1]; F0 = 1 puts the force's column
    # (0, M^-1 psi_F) where the harmonic force would be
    A = regime_matrix(pack(host, 0.0, 1.0, 1e-6), 0.0)  # (the step is not read)
    aux = [2 * n] if absorber else []
    kept = [*range(n), *aux, *range(n, 2 * n), *[i + 1 for i in aux]]
    d = len(kept) // 2
    p = np.zeros(d)
    p[:n] = host.bar.psi_tip
    zero = np.zeros(d)
    return CutModel(a=A[np.ix_(kept, kept)], g=A[kept, len(A) - 3],
                    c=np.concatenate([p, zero]), cv=np.concatenate([zero, p]),
                    feed=forcing.feed_m, revolutions=forcing.revolutions,
                    law=cutting_law(forcing.kr_pa, forcing.workpiece))


def static_state(model: CutModel, b: float) -> np.ndarray:
    """The steady cut's state: the deflection under F(b, h_m)."""
    f = model.law.force_n(b, model.feed)
    return -np.linalg.solve(model.a, model.g * f)


# --- the delayed displacement ---------------------------------------------------------
def hermite(theta: np.ndarray) -> np.ndarray:
    """The cubic Hermite weights (h00, h10, h01, h11) at ``theta`` in [0, 1], stacked last."""
    t2, t3 = theta * theta, theta * theta * theta
    return np.stack([2 * t3 - 3 * t2 + 1, t3 - 2 * t2 + theta, 3 * t2 - 2 * t3, t3 - t2], axis=-1)


@dataclass(frozen=True)
class Delays:
    """Where every stage's delayed W falls: node ``j`` (and j + 1) and the weights of
    (W_j, W'_j, W_j+1, W'_j+1), each (m, 3, N); ``base`` the unwrapped node index."""

    j: np.ndarray
    weights: np.ndarray
    base: np.ndarray


def delays(model: CutModel, o: Orbit) -> Delays:
    m, period = o.steps, o.period
    i = np.arange(m)[:, None, None]
    k = np.arange(1, model.revolutions + 1)[None, None, :]
    pos = i + STAGE_TIMES[None, :, None] - k * o.tau * m / period
    base = np.floor(pos).astype(np.int64)
    w = hermite(pos - base)
    w[..., 1] *= period / m
    w[..., 3] *= period / m
    return Delays(j=np.mod(base, m), weights=w, base=base)


def delayed_w(model: CutModel, x: np.ndarray, dl: Delays) -> np.ndarray:
    """W(t_i + c dt - k tau) of the periodic orbit ``x`` (m, s): (m, 3, N)."""
    return interpolated(model, x, dl.j, dl.weights)


def interpolated(model: CutModel, x: np.ndarray, j: np.ndarray, weights: np.ndarray):
    """W between nodes j and j + 1 (periodic) of the orbit ``x`` (m, s), from the Hermite
    ``weights`` of (W_j, W'_j, W_j+1, W'_j+1), the derivatives' already times the step."""
    w, v = x @ model.c, x @ model.cv
    j1 = np.mod(j + 1, len(x))
    parts = np.stack([w[j], v[j], w[j1], v[j1]], axis=-1)
    return np.sum(weights * parts, axis=-1)


# --- one RK4 step, with its derivatives ----------------------------------------------
def _field(model: CutModel, b: float, x: np.ndarray, wd: np.ndarray):
    """x' (m, s), d x'/d x (m, s, s) and d x'/d wd (m, s, N) at stage states ``x`` and
    delayed W ``wd`` (m, N)."""
    k = np.arange(1, model.revolutions + 1)
    surface = k * model.feed + wd
    active = np.argmin(surface, axis=1)
    rows = np.arange(len(x))
    h = np.maximum(surface[rows, active] - x @ model.c, 0.0)
    f, df = model.force(b, h)
    dx = x @ model.a.T + np.outer(f, model.g)
    jx = np.broadcast_to(model.a, (len(x),) + model.a.shape) - (
        df[:, None, None] * model.g[None, :, None] * model.c[None, None, :])
    jw = np.zeros((len(x), model.size, model.revolutions))
    jw[rows, :, active] = df[:, None] * model.g[None, :]
    return dx, jx, jw


def step(model: CutModel, b: float, x: np.ndarray, wd: np.ndarray, dt: float,
         tangent: bool = False):
    """RK4 from every node ``x`` (m, s) with the stages' delayed W ``wd`` (m, 3, N):
    the next states, and with ``tangent`` their derivatives (m, s, s + 3 N) by the
    nodes' states then the stages' delayed W (stage time 0, 1/2, 1, each k)."""
    m, s = x.shape
    n = model.revolutions
    seeds = np.zeros((m, s, s + 3 * n))
    seeds[:, :, :s] = np.eye(s)
    out, dout = x.copy(), seeds.copy()
    k, dk = np.zeros_like(x), np.zeros_like(seeds)
    for coef, weight, at in zip(RK4_COEF, RK4_WEIGHTS, RK4_DELAY, strict=True):
        k, jx, jw = _field(model, b, x + coef * dt * k, wd[:, at])
        out += weight * dt / 6.0 * k
        if tangent:
            dk = np.einsum("mij,mjd->mid", jx, seeds + coef * dt * dk)
            dk[:, :, s + at * n:s + (at + 1) * n] += jw
            dout += weight * dt / 6.0 * dk
    return (out, dout) if tangent else out


# --- the periodic boundary-value problem ---------------------------------------------
#: What an orbit may be continued in: the depth of cut b (m), or the delay tau (s, one
#: revolution), which sets the spindle speed 60 / tau rpm.
FREE = ("depth", "tau")


@dataclass(frozen=True)
class Orbit:
    """A discretised periodic orbit: node states ``x`` (m, s), period ``period`` (s) of the
    cut at depth ``depth`` (m) and delay ``tau`` (s, one revolution); its unknowns are the
    nodes, the period and the ``free`` one of :data:`FREE`, the other held."""

    x: np.ndarray
    period: float
    depth: float
    tau: float
    free: str = "depth"

    @property
    def steps(self) -> int:
        return len(self.x)

    @property
    def rpm(self) -> float:
        return 60.0 / self.tau

    @property
    def parameter(self) -> float:
        """The free parameter's value."""
        return self.depth if self.free == "depth" else self.tau

    def unknowns(self) -> np.ndarray:
        return np.concatenate([self.x.ravel(), [self.period, self.parameter]])

    def at(self, y: np.ndarray) -> Orbit:
        """The orbit of unknowns ``y``: this one's shape, held and free parameters."""
        values = {"depth": self.depth, "tau": self.tau, self.free: float(y[-1])}
        return Orbit(y[:-2].reshape(self.x.shape), float(y[-2]), values["depth"],
                     values["tau"], self.free)


def residual(model: CutModel, o: Orbit) -> np.ndarray:
    """The m RK4 steps closed around the period, then the phase condition W'(0) = 0."""
    dl = delays(model, o)
    nxt = step(model, o.depth, o.x, delayed_w(model, o.x, dl), o.period / o.steps)
    return np.concatenate([(np.roll(o.x, -1, axis=0) - nxt).ravel(), [o.x[0] @ model.cv]])


def jacobian(model: CutModel, o: Orbit) -> sp.csc_matrix:
    """d residual / d (x, T, p), p the free parameter, sparse: the nodes' columns exactly
    (forward mode through the RK4 stages and the Hermite weights), T's and p's by central
    differences."""
    m, s = o.x.shape
    dl = delays(model, o)
    _, d = step(model, o.depth, o.x, delayed_w(model, o.x, dl), o.period / m, tangent=True)
    rows, cols, vals = _node_blocks(model, d, dl, m, s)
    size = m * s
    nodes = sp.csc_matrix((vals, (rows, cols)), shape=(size + 1, size))
    extra = np.stack([_central(model, o, -2), _central(model, o, -1)], axis=1)
    return sp.hstack([nodes, sp.csc_matrix(extra)], format="csc")


def _node_blocks(model: CutModel, d: np.ndarray, dl: Delays, m: int, s: int):
    """COO entries of d residual / d nodes: +I at the next node, -dPhi/dx at the node, and
    -dPhi/dwd times the Hermite weights at the two nodes each delay falls between."""
    n = model.revolutions
    r = np.arange(m)[:, None] * s + np.arange(s)[None, :]
    parts = [(r.ravel(), (np.roll(r, -1, axis=0)).ravel(), np.ones(m * s))]
    rr = np.repeat(r[:, :, None], s, axis=2)
    cc = np.repeat(r[:, None, :], s, axis=1)
    parts.append((rr.ravel(), cc.ravel(), -d[:, :, :s].ravel()))
    # the delayed W depends on the nodes through (c, cv) . x at nodes j and j + 1
    for stage in range(3):
        for k in range(n):
            col = d[:, :, s + stage * n + k]  # (m, s)
            w = dl.weights[:, stage, k]  # (m, 4)
            for node, (wa, wb) in ((dl.j[:, stage, k], (0, 1)),
                                   (np.mod(dl.j[:, stage, k] + 1, m), (2, 3))):
                lin = w[:, wa, None] * model.c[None, :] + w[:, wb, None] * model.cv[None, :]
                block = -col[:, :, None] * lin[:, None, :]  # (m, s, s)
                cn = node[:, None] * s + np.arange(s)[None, :]
                parts.append((rr.ravel(), np.repeat(cn[:, None, :], s, axis=1).ravel(),
                              block.ravel()))
    phase = (np.full(s, m * s), np.arange(s), model.cv)
    parts.append(phase)
    return tuple(np.concatenate([p[q] for p in parts]) for q in range(3))


def _central(model: CutModel, o: Orbit, which: int) -> np.ndarray:
    y = o.unknowns()
    h = FD_STEP * abs(y[which])
    up, down = y.copy(), y.copy()
    up[which] += h
    down[which] -= h
    return (residual(model, o.at(up)) - residual(model, o.at(down))) / (2 * h)


# --- measures of an orbit ------------------------------------------------------------
def w_at(model: CutModel, o: Orbit, t: np.ndarray) -> np.ndarray:
    """W at times ``t`` (s, any), from the nodes' cubic Hermite, periodic in T."""
    m = o.steps
    dt = o.period / m
    pos = np.asarray(t, dtype=float) / dt
    base = np.floor(pos)
    wts = hermite(pos - base)
    wts[..., 1::2] *= dt
    return interpolated(model, o.x, np.mod(base.astype(np.int64), m), wts)


def chip(model: CutModel, o: Orbit, t: np.ndarray) -> np.ndarray:
    """The chip thickness before the max(0, .): min_k [k h_m + W(t - k tau)] - W(t)."""
    t = np.asarray(t, dtype=float)
    k = np.arange(1, model.revolutions + 1)
    surface = k * model.feed + w_at(model, o, t[..., None] - k * o.tau)
    return surface.min(axis=-1) - w_at(model, o, t)


def _refined_min(fn, period: float, m: int, sub: int = 16) -> tuple[float, float]:
    """(t, value) of the smallest value of the periodic ``fn``: sampled ``sub`` times a
    step, then golden-section search in the samples' neighbourhood to 1e-13 of T."""
    t = np.arange(m * sub) * period / (m * sub)
    vals = fn(t)
    i = int(np.argmin(vals))
    lo, hi = t[i] - period / (m * sub), t[i] + period / (m * sub)
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    while hi - lo > 1e-13 * period:
        a, b = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
        fa, fb = fn(np.array([a, b]))
        if fa <= fb:
            hi = b
        else:
            lo = a
    tm = 0.5 * (lo + hi)
    return tm, float(fn(np.array([tm]))[0])


def node_forces(model: CutModel, o: Orbit) -> np.ndarray:
    """F (N) at the nodes."""
    t = np.arange(o.steps) * o.period / o.steps
    return np.asarray(model.law.force_n(o.depth, np.maximum(chip(model, o, t), 0.0)), dtype=float)


def min_chip(model: CutModel, o: Orbit) -> float:
    """The orbit's thinnest chip before the max(0, .) (m): negative where the tool
    leaves the cut."""
    return _refined_min(lambda t: chip(model, o, t), o.period, o.steps)[1]


def amplitude(model: CutModel, o: Orbit) -> float:
    """Half the peak-to-peak tip displacement (m), from the continuous interpolant."""
    hi = -_refined_min(lambda t: -w_at(model, o, t), o.period, o.steps)[1]
    lo = _refined_min(lambda t: w_at(model, o, t), o.period, o.steps)[1]
    return 0.5 * (hi - lo)


# --- Newton ---------------------------------------------------------------------------
def newton(model: CutModel, o: Orbit, extra, tol: float = 1e-10,
           max_iter: int = 12) -> tuple[Orbit, int, object]:
    """Solve residual = 0 with one more equation ``extra(y) -> (value, gradient row)``
    (a fixed amplitude, or the arclength): the orbit, the iterations it took and the
    last factorised matrix.  A chord method: the matrix is factorised again only when a
    step does not at least halve the last one; the step is relative to ``o``'s scale."""
    y = o.unknowns()
    scale = _scale(model, o)
    lu, last = None, math.inf
    for it in range(1, max_iter + 1):
        cur = o.at(y)
        e, row = extra(y)
        full = np.concatenate([residual(model, cur), [e]])
        if lu is None:
            lu = _factor(model, cur, row)
        dy = lu.solve(-full)
        size = np.max(np.abs(dy) / scale)
        if not np.isfinite(size):
            raise CutOrbitError("the orbit's Jacobian is singular")
        y = y + dy
        if size < tol:
            return o.at(y), it, lu
        if size > 0.5 * last:
            lu = None
        last = size
    raise CutOrbitError(f"Newton did not converge in {max_iter} iterations "
                        f"(last relative step {last:.2e})")


@dataclass(frozen=True)
class DenseLU:
    """A dense LU factorisation with SuperLU's ``shape`` and ``solve``."""

    factors: tuple

    @property
    def shape(self) -> tuple[int, int]:
        return self.factors[0].shape

    def solve(self, b: np.ndarray) -> np.ndarray:
        return scipy.linalg.lu_solve(self.factors, b, check_finite=False)


def _factor(model: CutModel, o: Orbit, row: np.ndarray):
    """The bordered Jacobian factorised: densely up to DENSE_LU unknowns (the delays'
    couplings fill a sparse LU in as much as a dense one, and LAPACK is faster there),
    sparsely beyond."""
    jac = sp.vstack([jacobian(model, o), sp.csr_matrix(row[None, :])], format="csc")
    if jac.shape[0] <= DENSE_LU:
        with warnings.catch_warnings():
            warnings.simplefilter("error", scipy.linalg.LinAlgWarning)
            try:
                return DenseLU(scipy.linalg.lu_factor(jac.toarray(), check_finite=False))
            except scipy.linalg.LinAlgWarning as err:
                raise CutOrbitError(f"the orbit's Jacobian is singular ({err})") from None
    try:
        return spla.splu(jac)
    except RuntimeError as err:  # "Factor is exactly singular"
        raise CutOrbitError(f"the orbit's Jacobian is singular ({err})") from None


def _scale(model: CutModel, o: Orbit) -> np.ndarray:
    """A size for every unknown: the node states by their own spread, T and p by value."""
    spread = np.max(np.abs(o.x - o.x.mean(axis=0)), axis=0) + 1e-3 * np.max(np.abs(o.x), axis=0)
    spread = np.where(spread > 0, spread, 1.0)
    return np.concatenate([np.tile(spread, o.steps), [o.period, o.parameter]])


# --- Floquet multipliers --------------------------------------------------------------
def multipliers(model: CutModel, o: Orbit, count: int = MULTIPLIERS) -> np.ndarray:
    """The ``count`` largest Floquet multipliers of the discretised orbit, by modulus.

    A delay equation's multipliers over one short period crowd near the unit circle
    (every characteristic root with a small negative real part), which ARPACK separates
    slowly; over the q periods that renew the whole history they spread to their q-th
    powers.  So the eigenvectors of the q-period map's largest eigenvalues (the
    one-period map applied q times) are found, and the multipliers are the eigenvalues of
    the one-period map on the subspace they span (Rayleigh-Ritz).  The subspace is
    invariant under the one-period map, and a pair mu, conj(mu) whose q-th powers
    coincide (a real mu^q) is resolved there, where one eigenvector's own Rayleigh
    quotient would mix the two."""
    hm = HistoryMap.of(model, o)
    size = hm.size
    q = max(1, -(-hm.depth // len(o.x)))
    opq = spla.LinearOperator((size, size), matvec=lambda v: hm.apply(v, q), dtype=np.float64)
    k = min(count, size - 2)
    nu, vec = spla.eigs(opq, k=k, which="LM", tol=EIG_TOL, ncv=min(max(2 * k + 1, 30),
                        size - 1), v0=np.ones(size))
    basis, _ = np.linalg.qr(vec)
    image = np.column_stack([hm.apply(v.real, 1) + 1j * hm.apply(v.imag, 1)
                             for v in basis.T])
    mu = np.linalg.eigvals(basis.conj().T @ image)
    return mu[np.argsort(-np.abs(mu))]


@dataclass(frozen=True)
class HistoryMap:
    """The orbit's linearised discretised map on its history, in the core
    (``core.cut_history_map``).

    The history is node 0's state and, for the ``depth`` older nodes, only their W and
    W' (all that a delay reads of them): the map's nonzero spectrum is the full one's.
    Each step carries its node's perturbation by the step's derivative ``d`` and adds, for
    each delayed W the step reads (``cols``), the Hermite interpolation between nodes
    ``base`` and ``base + 1`` (``weights``)."""

    d: np.ndarray
    cols: np.ndarray
    base: np.ndarray
    weights: np.ndarray
    c: np.ndarray
    cv: np.ndarray
    depth: int

    @classmethod
    def of(cls, model: CutModel, o: Orbit) -> HistoryMap:
        m, s = o.x.shape
        dl = delays(model, o)
        _, d = step(model, o.depth, o.x, delayed_w(model, o.x, dl), o.period / m, tangent=True)
        n = model.revolutions
        terms = [(stage, k) for stage in range(3) for k in _used_delays(d, s, n)]

        def stacked(a):
            return np.ascontiguousarray(np.stack(a, axis=1))

        base = stacked([dl.base[:, stage, k] for stage, k in terms]).astype(np.int64)
        return cls(np.ascontiguousarray(d[:, :, :s]),
                   stacked([d[:, :, s + stage * n + k] for stage, k in terms]), base,
                   stacked([dl.weights[:, stage, k] for stage, k in terms]),
                   np.ascontiguousarray(model.c, dtype=float),
                   np.ascontiguousarray(model.cv, dtype=float), int(-base.min()) + 1)

    @property
    def size(self) -> int:
        """The map's dimension: the history's (W, W') pairs and node 0's state."""
        return 2 * self.depth + self.d.shape[1]

    def apply(self, v: np.ndarray, periods: int) -> np.ndarray:
        """v carried ``periods`` periods (v: the pairs, oldest first, then node 0)."""
        return cut_history_map(self.d, self.cols, self.base, self.weights, self.c, self.cv,
                               v, periods)


def _used_delays(d: np.ndarray, s: int, n: int) -> np.ndarray:
    """The revolutions k whose delayed W moves some stage (the chip's active term)."""
    moves = np.abs(d[:, :, s:]).reshape(len(d), s, 3, n).max(axis=(0, 1, 2)) > 0
    return np.flatnonzero(moves) if moves.any() else np.array([0])
