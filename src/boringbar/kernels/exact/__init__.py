"""The exact event-driven integrator (docs/model.md, sections 2 and 5).

Between events the motion is linear with a constant friction force and the
harmonic input F0 sin(Omega t), so it has a closed form.  The ball case has
three regimes, each a linear system X' = A_r X + B_r f(t) + c_r F_b of the
bar coordinates X = [u, u'] (the ball is treated separately):

- FREE (the ball slides or flies): the modes decouple, A is block diagonal,
  F_b = -F_c sgn(y') is constant on the segment, and the ball's absolute
  motion is a parabola, u_d'' = F_b / m;
- STICK (off the walls, y' = 0): the ball is carried by the bar through
  friction, the bar sees (M + s m psi_d psi_d^T) u'' + C u' + K u = psi_L f
  with s = p[REACTION] (the reaction as printed, s = -1, applies to the
  friction force that carries the ball);
- CONTACT (on a wall, y' = 0): the same with s = +1 (a wall force is always
  reciprocal).

The solid bar (one FREE regime without ball), the locked ball (one coupled
regime) and the TMD bar (one regime of the 2n + 2 coordinates
[u, u', x_a, x_a']) have no events.  For each regime the per-run setup
(:func:`prepare`, NumPy, once per run) diagonalises A_r = V diag(lambda) V^-1
and solves for the particular solutions: X_p(t) = Im(Z e^{i Omega t}) + F_b D.
On a segment that starts at t_s the state is

    X(t_s + tau) = X_p(t_s + tau) + Re(V (q0 * exp(lambda tau))),
    q0 = V^-1 (X(t_s) - X_p(t_s)),

evaluated directly (complex exponentials) wherever an answer is needed, and
by the recurrence q <- q exp(lambda h) on the event-search grid.

Events (located by a safeguarded regula falsi, Illinois variant, to a
bracket of 4 ulp of t):

- FREE: y = +-delta/2 (impact, or capture on the wall when the impact is
  slower than p[V_IMPACT], the threshold of docs/model.md, section 2: a Zeno
  sequence ends in CONTACT after finitely many impacts); y' = 0 when
  F_c > 0 (a friction switch: the ball sticks if the force needed to carry
  it, |F_req| = |psi_d . a_0| / (1/m + s sum psi_d^2 / M), is at most F_s,
  else it slides back);
- STICK: |F_req| = F_s (slip starts, in the direction opposite to F_req);
- CONTACT: the wall force needed changes sign, wall * F_req = F_s (released
  into FREE, sliding inward).

Event search grid: h = (shortest period among the forcing and every
regime's eigenvalues) / ``GRID_PER_PERIOD``.  A sign change of an event
function between grid points brackets the event.  Grazing (a double
crossing inside one grid step) is guarded three ways: with friction the
ball's relative motion is monotone up to the y' = 0 switch, so walls are
sought on [a, switch] when the switch falls in the step; without friction
a sign change of y' inside a step near a wall is located and the extremum
of y checked, which splits the step into two monotone pieces; and when the
cubic Hermite interpolant of y (from y, y' at the step ends), widened by
twice its error bound h^4 max|y^(4)| / 384 (max|y^(4)| bounded per segment
from the closed form), comes within reach of a wall, the step is searched
again on NSUB sub-steps.  A segment never starts past a wall (y(0) is
clamped for the search).  Not guarded: an excursion of F_req across F_s and
back inside one grid step.  A free ball with more than one mode steps 2 h,
4 h, ... where Taylor bounds (|y'''|, |W'''| bounded per segment) prove that
the step holds no event and no new extremum (docs/exact.md, "Longer steps").

Metrics: the same vector as the RK4 kernel, but the steady sums are exact
integrals over the steady window [t_steady, t_end]: SUM_W2 = int W^2 dt,
SUM_W = int W dt, SUM_F = int f dt and N_STEADY = the window length (s), so
that SUM_W2 / N_STEADY is the mean square in both kernels.  The energy flows
are exact too: the work of the force, int f psi_L . u' dt, and the viscous
loss, int sum C_i u_i'^2 dt (+ the absorber's dashpot), are integrals of
products of exponentials, done in closed form per segment; friction
dissipation is -F_b (y(t_e) - y(t_s)) per sliding segment; the
non-reciprocal work (1 - s) int F_b psi_d . u' dt is closed form too.  The
balance then closes to round-off.  The ball's int y^2 (SUM_AUX2) is closed
form too under harmonic forcing (a parabola minus exponentials: phi_j
functions); an absorber's stroke (TMD) and a ball in a regenerative cut use the
endpoint-corrected trapezoid rule on the grid.  Maxima of
|W| are located exactly (W' = 0 roots on the grid); maxima of |aux| are
taken on the grid and at events.

Regenerative cutting (docs/model.md, section 4; docs/exact.md "Regenerative cuts"):
in the cut f = Kr b (S(t) - W), and -Kr b W joins the matrix (a second set of
regimes, ``prepare``); the surface S = min_k [k h_m + W(t - k tau)] is one cubic
per segment, the cubic Hermite of W, W' between stored knots (at the nodes
t0 + j H, H = tau / ceil(tau / dt), and at every event), and the input
bq Kr b S is propagated exactly with phi-functions (:func:`state_at`), so the
error is the interpolation's, O(H^4).  Segments end at every node, delayed
knot and change of the minimising revolution.  The tool leaving and
re-entering the cut (h = 0) are events (EV_CUT, with the extremum of h,
EV_HEXT, against grazes); the first exit is the chatter verdict.  The flows
of a cut are integrated by 4-point Gauss-Legendre per step (O(H^9) per step);
a whole step from node to node uses tabulated exponentials and phi's.

The package, by concern:

- :mod:`.consts`: the grid, the limits, the regimes, the event kinds, the segment
  record's slots (``SEG_*``) and the stack scratch's sizes;
- :mod:`.prepare`: the per-run setup, :func:`prepare` (the regimes' matrices, diagonalised);
- :mod:`.propagate`: the closed form on a segment (:func:`state_at`) and its integrals
  (:func:`segment_integrals`);
- :mod:`.events`: the event functions, their roots, the W extrema and a free ball's wall step;
- :mod:`.cut`: a regenerative cut's delay history (knots, surface, Gauss-Legendre flows);
- :mod:`.segment`: one segment between two events: its start, the grid search for its
  first event (with the outputs on the way) and its flows, inlined into the driver;
- :mod:`.driver`: the kernel :func:`_exact` (the run's setup, the loop over segments, the
  events applied between them) and its entry point :func:`run_exact`.

The impact law, the records of impacts and stick intervals and the load and store of the
running extremes are shared with the RK4 kernels (:mod:`boringbar.kernels.core`).
"""

# the names the rest of the package, the tests and the benchmarks import from here
from boringbar.kernels.exact.consts import EV_PLUS, EV_WEXT, SEG_SIZE
from boringbar.kernels.exact.driver import run_exact
from boringbar.kernels.exact.events import (
    find_root,
    find_root_1,
    find_root_2,
    g_value,
    w_extremum,
    w_extremum_1,
    w_extremum_2,
)
from boringbar.kernels.exact.prepare import prepare
from boringbar.kernels.exact.propagate import (
    segment_integrals,
    segment_integrals_1,
    segment_integrals_2,
)

__all__ = [
    "EV_PLUS",
    "EV_WEXT",
    "SEG_SIZE",
    "g_value",
    "segment_integrals",
    "segment_integrals_1",
    "segment_integrals_2",
    "find_root",
    "find_root_1",
    "find_root_2",
    "w_extremum",
    "w_extremum_1",
    "w_extremum_2",
    "prepare",
    "run_exact",
]
