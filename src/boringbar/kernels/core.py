"""What the three integrators share, written once (#11).

The RK4 kernel (``rk4.py``, one run), the lock-step batch (``rk4_batch.py``) and the
exact event-driven integrator (``exact/``) call these small functions:

- :func:`impact_law`: the velocity jumps of an impact (docs/model.md, section 2.4);
  all three kernels;
- :func:`count_impact` and :func:`close_stick`: an impact's counts and row, a stick
  interval's time and row, into the metric vector and the record arrays; all three;
- :func:`wall_rule` and :func:`stick_step`: the fixed-step scheme's wall rule at a
  step's end (section 2.5: back on the wall, the law only if y y' > 0, counted only
  above the velocity threshold, otherwise contact) and its stick bookkeeping; the two
  RK4 kernels (the exact kernel locates its impacts as events instead);
- :func:`strobe_row` and :func:`steady_sample`: a Poincare strobe row interpolated
  inside a step and a step's steady metrics; the two RK4 kernels;
- ``load_*`` / ``store_*``: groups of the metric vector as tuples of locals (a kernel
  keeps its running sums and extremes in registers, not in ``met``); the single-run
  RK4 kernel and the exact kernel's running extremes.

Every function does the operations its callers did, in the same order, so the results
stay bit-identical (no fast-math flag: under plain IEEE arithmetic the same operations
give the same bits wherever they are compiled).  What runs at every step
(:func:`impact_law` inside :func:`wall_rule`, :func:`stick_step`, :func:`steady_sample`)
is inlined by numba (``inline="always"``): as plain ``njit`` calls, which LLVM did not
inline, they made the RK4 kernels 1.6-2.1x slower per step (docs/performance.md).  What
runs at events only (:func:`count_impact`, :func:`close_stick`, :func:`strobe_row`) and
the loads and stores stay plain calls, compiled once per signature rather than into
every kernel specialisation.  The arrays the kernels pass are borrowed views
(kernels/views.py), so the calls are not reference-counted.

numba's cache checks only the caller's own source file: after a change here, clear the
cached kernels (``src/boringbar/kernels/**/__pycache__``) or they keep the old code.
"""

from numba import njit

from boringbar.kernels import layout as L
from boringbar.kernels.interp import hermite, lerp

#: outcome of :func:`wall_rule` at a step's end
OFF_WALL, IMPACT, MICRO_IMPACT, ON_WALL = 0, 1, 2, 3


@njit(cache=True, error_model="numpy", inline="always")
def impact_law(vb, e, meff):
    """The impact of a ball arriving with relative velocity ``vb`` (docs/model.md, 2.4):
    (y'+, g, loss) with y'+ = -e y'-, the modes' jumps u_i'+ = u_i'- + g psi_d,i / M_i,
    g = (1 + e) m_eff y'-, and the kinetic energy lost, (1 - e^2) m_eff y'-^2 / 2."""
    return -e * vb, (1.0 + e) * meff * vb, 0.5 * (1.0 - e * e) * meff * vb * vb


@njit(cache=True, error_model="numpy")
def count_impact(met, imp, t, wall, vb, steady):
    """A counted impact at t on ``wall`` (+1/-1) at relative velocity vb: N_IMP_ALL, and in
    the steady part the wall's count and the row (t, wall, vb) of ``imp`` while there is
    room (N_IMP_REC counts the rows, written or not)."""
    met[L.N_IMP_ALL] += 1
    if steady:
        if wall > 0:
            met[L.N_IMP_PLUS] += 1
        else:
            met[L.N_IMP_MINUS] += 1
        n_imp = int(met[L.N_IMP_REC])
        if n_imp < imp.shape[0]:
            imp[n_imp, 0] = t
            imp[n_imp, 1] = wall
            imp[n_imp, 2] = vb
        met[L.N_IMP_REC] += 1


@njit(cache=True, error_model="numpy")
def close_stick(met, stick, t_start, t, t_steady, stick_min):
    """The stick interval from ``t_start`` to ``t`` ends: clipped to the steady part
    (from ``t_steady``), and if at least ``stick_min`` long, its time into T_STICK and its
    row (start, end) into ``stick`` while there is room (N_STICK_REC counts the rows)."""
    s0 = max(t_start, t_steady)
    if t - s0 >= stick_min:
        met[L.T_STICK] += t - s0
        n_stk = int(met[L.N_STICK_REC])
        if n_stk < stick.shape[0]:
            stick[n_stk, 0] = s0
            stick[n_stk, 1] = t
        met[L.N_STICK_REC] += 1


@njit(cache=True, error_model="numpy", inline="always")
def wall_rule(met, imp, y, yd, t1, steady, half, e, meff, vimp):
    """The fixed-step scheme's walls at the end t1 of a step (docs/model.md, 2.5): a ball at
    or past a wall (|y| >= half) is put back on it and, if moving outward (y y' > 0), takes
    the impact law, counted (:func:`count_impact`) if faster than ``vimp``, else a micro
    impact (N_MICRO, contact); the energy lost into D_IMPACT.  Returns (outcome, y, y', g):
    outcome OFF_WALL, IMPACT, MICRO_IMPACT (both: the modes jump by g psi_d,i / M_i) or
    ON_WALL (at rest on the wall or moving inward: contact, no impact)."""
    if not abs(y) >= half:
        return OFF_WALL, y, yd, 0.0
    wall = 1.0 if y > 0.0 else -1.0
    if not wall * yd > 0.0:
        return ON_WALL, wall * half, yd, 0.0
    yd1, g, loss = impact_law(yd, e, meff)
    met[L.D_IMPACT] += loss
    if abs(yd) > vimp:
        count_impact(met, imp, t1, wall, yd, steady)
        return IMPACT, wall * half, yd1, g
    met[L.N_MICRO] += 1
    return MICRO_IMPACT, wall * half, yd1, g


@njit(cache=True, error_model="numpy", inline="always")
def stick_step(stuck, in_stick, stick_t0, t, t1, met, stick, t_steady, stick_min):
    """The fixed-step scheme's stick bookkeeping for the step [t, t1]: an interval opens at
    t when the ball is ``stuck`` (off the walls, |y'| inside the band where the sgn() law
    chatters) and closes at t1 when it is no longer (:func:`close_stick`).  Returns
    (in_stick, stick_t0)."""
    if stuck and not in_stick:
        return True, t
    if in_stick and not stuck:
        close_stick(met, stick, stick_t0, t1, t_steady, stick_min)
        return False, stick_t0
    return in_stick, stick_t0


@njit(cache=True, error_model="numpy")
def strobe_row(row, tn, t, dt, w0, wd0, w1, wd1, a0, ad0, a1, ad1):
    """A Poincare strobe row (tn, W, W', aux, aux') at tn inside the step [t, t + dt] from
    its end values: W, W' by the cubic Hermite, aux, aux' linearly (roundings pinned,
    kernels/interp.py)."""
    s = (tn - t) / dt
    row[0] = tn
    row[1], row[2] = hermite(s, dt, w0, wd0, w1, wd1)
    row[3] = lerp(s, a0, a1)
    row[4] = lerp(s, ad0, ad1)


@njit(cache=True, error_model="numpy", inline="always")
def steady_sample(w, aux, f, sum_w2, sum_w, n_steady, sum_aux2, sum_f, max_abs_w, max_w, min_w,
                  max_aux):
    """A step's steady metrics: the sums and extremes with the step end's W, aux and f."""
    return (sum_w2 + w * w, sum_w + w, n_steady + 1.0, sum_aux2 + aux * aux, sum_f + f,
            max(max_abs_w, abs(w)), max(max_w, w), min(min_w, w), max(max_aux, abs(aux)))


@njit(cache=True, error_model="numpy")
def load_steady(met):
    """(SUM_W2, SUM_W, N_STEADY, SUM_AUX2, SUM_F, T_CONTACT)."""
    return (met[L.SUM_W2], met[L.SUM_W], met[L.N_STEADY], met[L.SUM_AUX2], met[L.SUM_F],
            met[L.T_CONTACT])


@njit(cache=True, error_model="numpy")
def store_steady(met, sum_w2, sum_w, n_steady, sum_aux2, sum_f, t_contact):
    met[L.SUM_W2] = sum_w2
    met[L.SUM_W] = sum_w
    met[L.N_STEADY] = n_steady
    met[L.SUM_AUX2] = sum_aux2
    met[L.SUM_F] = sum_f
    met[L.T_CONTACT] = t_contact


@njit(cache=True, error_model="numpy")
def load_extremes(met):
    """(MAX_ABS_W, STEADY_MAX_W, STEADY_MIN_W, MAX_ABS_AUX, MAX_ABS_AUX_ALL)."""
    return (met[L.MAX_ABS_W], met[L.STEADY_MAX_W], met[L.STEADY_MIN_W], met[L.MAX_ABS_AUX],
            met[L.MAX_ABS_AUX_ALL])


@njit(cache=True, error_model="numpy")
def store_extremes(met, max_abs_w, max_w, min_w, max_aux, max_aux_all):
    met[L.MAX_ABS_W] = max_abs_w
    met[L.STEADY_MAX_W] = max_w
    met[L.STEADY_MIN_W] = min_w
    met[L.MAX_ABS_AUX] = max_aux
    met[L.MAX_ABS_AUX_ALL] = max_aux_all


@njit(cache=True, error_model="numpy")
def load_flows(met):
    """(W_FORCE, D_VISC, D_FRICTION, W_NONRECIP): the energy flows integrated step by step."""
    return met[L.W_FORCE], met[L.D_VISC], met[L.D_FRICTION], met[L.W_NONRECIP]


@njit(cache=True, error_model="numpy")
def store_flows(met, w_force, d_visc, d_fric, w_nr):
    met[L.W_FORCE] = w_force
    met[L.D_VISC] = d_visc
    met[L.D_FRICTION] = d_fric
    met[L.W_NONRECIP] = w_nr
