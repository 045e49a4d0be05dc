// One segment of the exact kernel, between two events:
// its start (start_segment), the grid search for its first event with the outputs on the way
// (search_segment) and its flows (close_segment): templates on Regen (a cut), instantiated
// by the driver's two kernels and inlined into them.
//
// Complex arithmetic goes through ncplx and max/min through pymax/pymin (nmath.hpp), so
// that the rounding and the handling of NaN are this code's, whatever the compiler.
//
//   struct Work                         the driver's arrays and the system, passed whole
//   struct SegCtx                       a segment's regime, sizes, bar and ball regime
//   start_segment<Regen>(w, t, t_stop, ph, hs, j_node, cq, sv)
//       -> SegStart {r, ks, t_seg_end, at_node, j_node, pdu}
//   search_segment<Regen, NZ = 0>(w, t, c, ph, sv)
//       -> SegEvent {kind, tau, ph_next, wb, wdb}
//   close_segment<Regen>(w, c, t, T, ph, steady, pdu, last_zero_step)
//       -> the last step of length dt_out counted with h = 0
#pragma once

#include <array>
#include <cmath>
#include <utility>

#include "../arrays.hpp"
#include "../layout.hpp"
#include "consts.hpp"
#include "cut.hpp"
#include "events.hpp"
#include "flows.hpp"
#include "nmath.hpp"
#include "propagate.hpp"

namespace bb::exact {

namespace L = layout;

// Rows between two exact ones in history_rows: the products' rounding grows by about one
// unit a row, so 64 keep it near 1e-14 of the state.
constexpr idx REC_ANCHOR = 64;

// history_rows' recurrence, carried from one grid step's call to the next: exp(lambda_k tau)
// at the last row of the segment from t_seg (regime r), the forcing's phasor there, and
// their factors over rec_dt (of regime r_step).
struct RowRecurrence {
    double t_seg = NAN;
    idx r = -1, r_step = -1;
    idx since = REC_ANCHOR;
    ncplx ex[NZ_MAX] = {}, step[NZ_MAX] = {};
    ncplx ph, ph_step;
};

// The driver's arrays: the scratch, owned here (zeroed once per run and reused by every
// segment, so a segment allocates nothing), and views of the run's inputs and outputs.  The views point into this object: it is never copied or moved.
struct Work {
    // --- scratch storage
    std::array<double, NZ_MAX> X_{}, Xa_{}, Xd_{}, dX_{};
    std::array<cplx, NZ_MAX> q0_{}, qs_{}, qg_{};
    std::array<double, N_EV> ev_a_{}, ev_b_{}, ev_s_{}, ev_t_{}, ev_u_{};
    std::array<double, 6> qsum_{};
    std::array<double, 7> out_{};
    std::array<cplx, NB_MAX_2> me_{};
    std::array<cplx, NB_MAX2> G_{};
    std::array<cplx, NZB_MAX> Cx_{};
    std::array<cplx, NB_MAX> c_{}, ce_{}, ca_{}, cb_{};
    std::array<cplx, 3> phj_{};
    std::array<double, MK_SIZE> mk_{};
    std::array<double, DDC> ddc_{};

    // --- the system (its rows mk and ddc in the scratch above) and the run's constants
    System sys;
    RunConsts cp;

    // --- views of the scratch, with the run's shapes (nz, nb = nz + 3, n modes)
    Vec X, Xa, Xd, dX;       // states: at the grid point, the step's start, X', a work vector
    CVec q0, qs, qg;         // eigen-coordinates: the segment's start, scratch, the grid's
    Vec ev_a, ev_b, ev_s, ev_t;  // event functions at a step's and a sub-step's ends
    Vec ev_u;                    // ... and where a rolling ball's slip runs out
    Vec qsum, out;           // a cut's flow sums; a segment's integrals
    FlowsScratch isc;        // segment_integrals' scratch
    FlowTables flows;        // and each regime's tables, built on its first segment

    // exp(lambda_k tau_end) (k = 0, ks, ...) of regime r_end, kept by the search's last
    // state_at at tau_end (outside a cut, the constant sizes) for segment_integrals
    ncplx ex_end[2] = {};
    double tau_end = NAN;
    idx r_end = -1;
    RowRecurrence rr;  // history_rows' recurrence through one segment

    Segment seg;
    RunState rs;
    RunningOut ro;

    // --- prepare's matrices and the cut's tables (inputs)
    ClosedForm cf;       // lam, V (the halved eigenvectors, prepare's Vh), Z, D, bq
    CArr3 Vi, Vfull;     // the inverse eigenvectors; Vfull: prepare's V
    Dashpots dp;         // prepare's lvis, cvis
    CArr3 isum;
    Span1<idx> kstep;
    Arr3 bnd;
    Span1<idx> levmax;
    CArr3 eh, tabE;
    CArr4 tabP;

    // the grid's step lengths h, 2 h, 4 h, ... and their phase steps
    double hl[GRID_LEVELS] = {};
    ncplx rotl[GRID_LEVELS] = {};

    // --- the run's outputs
    Vec x;
    Mat rec, strobe;
    Vec met;

    Work(idx n, idx nz) {
        idx nb = nz + 3;
        X = {X_.data(), nz};
        Xa = {Xa_.data(), nz};
        Xd = {Xd_.data(), nz};
        dX = {dX_.data(), nz};
        q0 = {q0_.data(), nz};
        qs = {qs_.data(), nz};
        qg = {qg_.data(), nz};
        ev_a = {ev_a_.data(), N_EV};
        ev_b = {ev_b_.data(), N_EV};
        ev_s = {ev_s_.data(), N_EV};
        ev_t = {ev_t_.data(), N_EV};
        ev_u = {ev_u_.data(), N_EV};
        qsum = {qsum_.data(), 6};
        out = {out_.data(), 7};
        isc.me = {me_.data(), 2, nb};
        isc.G = {G_.data(), nb, nb};
        isc.Cx = {Cx_.data(), nz, nb};
        isc.c = {c_.data(), nb};
        isc.ce = {ce_.data(), nb};
        isc.ca = {ca_.data(), nb};
        isc.cb = {cb_.data(), nb};
        isc.phj = {phj_.data(), 3};
        sys.n = n;
        sys.mk = {mk_.data(), MK_ROWS, n};
        sys.ddc = {ddc_.data(), 4, n + 2};
    }
    Work(const Work&) = delete;
    Work& operator=(const Work&) = delete;
};

// A segment's context: its regime r in prepare's matrices and the step ks of the evaluated
// eigen-coordinates (2: conjugate pairs, the first of each); the bar's mode count n and the
// copy with constant sizes that fits it (sz: 1 or 2 modes, else 0; const_sizes); the bar's
// case and whether it carries a ball; the ball's regime.  Passed by value: a copy's fields
// stay constants where the search has them so.
struct SegCtx {
    idx r, ks, sz, n;
    layout::Case kase;
    Regime mode;
    bool ball;
};

// The segment's closed form in the context c as the event functions read it, evaluated
// into the work vectors qs, dX and Xd.
inline SegView view(Work& w, SegCtx c) {
    return {w.seg, c.r, w.q0, w.cf, c.ks, w.qs, w.dX, w.Xd, c.n, w.sys.mk, w.sys.q.force.f0,
            w.sys.q.force.om};
}

namespace kernel {

// Re(V[r, j, :] q) over the evaluated eigen-coordinates, added to s one at a time in k's
// order (a conjugate pair's second member is not evaluated: ks = 2)
inline double add_modes(double s, CArr3 V, idx r, idx j, CVec q, idx nz, idx ks) {
    for (idx kq = 0; kq < nq(nz, ks); ++kq) {
        idx k = kq * ks;
        s += (ncplx(V(r, j, k)) * ncplx(q[k])).real();
    }
    return s;
}

// All event functions from the state X at tau (see g_value): the ball's regime mode, the
// bar's rows mk (n = mk.n1 modes), the forcing fo; sn: sin(Omega (ts + tau)) if known.
inline void events(Vec ev, Vec X, double tau, const Segment& seg, Regime mode, Mat mk,
                   const dynamics::Forcing& fo, double sn = NAN) {
    const idx n = mk.n1;
    const double f0 = fo.f0, om = fo.om;
    auto [pdu, pdv] = psi_dot(mk, MK_PSI_D, X, n);
    double y = ball_y(seg, tau, pdu);
    double yd = ball_yd(seg, tau, pdv);
    ev[EV_PLUS] = y - seg.half;
    ev[EV_MINUS] = -seg.half - y;
    ev[EV_VSTOP] = -seg.sdir * yd;
    ev[EV_YEXT] = yd;
    if (seg.rolls) ev[EV_SLIP] = -seg.slip * (yd - (seg.s0 + seg.sd * tau));
    if (seg.cdir != 0.0) {
        auto [w, wd] = psi_dot(mk, MK_PSI_L, X, n);
        auto [sv, sd] = surface_at(seg, tau);
        ev[EV_CUT] = seg.cdir * (w - sv);
        ev[EV_HEXT] = sd - wd;
    }
    if (mode != FREE) {
        double F = freq_rhs(X, cut_force(seg, tau, X, n, mk, f0, om, sn), n, mk, seg.kappa);
        if (seg.rolls) F -= seg.foff;
        ev[EV_REL_NEG] = F - seg.fs;
        ev[EV_REL_POS] = -F - seg.fs;
        ev[EV_WALL_REL] = seg.wall * F - seg.fs;
    }
}

// (aux, aux'): the ball's y, y' or the absorber's stroke and its rate (a locked ball: its
// y, from the run's state x); mk: the bar's rows (n = mk.n1 modes).
inline std::pair<double, double> aux(Vec X, double tau, const Segment& seg, SegCtx c, Mat mk,
                                     Vec x) {
    const idx n = mk.n1;
    const layout::Case kase = c.kase;
    if (c.ball) {
        if (c.mode == STICK || c.mode == CONTACT) return {seg.y0, 0.0};
        auto [pdu, pdv] = psi_dot(mk, MK_PSI_D, X, n);
        return {ball_y(seg, tau, pdu), ball_yd(seg, tau, pdv)};
    }
    if (kase == L::TMD) {
        double a = X[2 * n];
        double ad = X[2 * n + 1];
        for (idx i = 0; i < n; ++i) {
            a -= mk(MK_PSI_A, i) * X[i];
            ad -= mk(MK_PSI_A, i) * X[n + i];
        }
        return {a, ad};
    }
    if (kase == L::LOCKED) return {x[2 * n], 0.0};
    return {0.0, 0.0};
}

// (y'', W'') of a free ball's bar state X under the tip force f and F_b: y'' = acc -
// psi_d . u'', W'' = psi_L . u'', M u'' = psi_L f - K u - C u' - s psi_d F_b (ddc's rows).
inline std::pair<double, double> ydd(Vec X, double f, double fb, double acc, Mat ddc, idx n) {
    double yv = acc - (ddc(0, n) * f + ddc(0, n + 1) * fb);
    double wv = ddc(1, n) * f + ddc(1, n + 1) * fb;
    // unrolled where n is constant (grid_point): the loop vectoriser would load X in pairs
    // just after from_q stored it one by one (a stalled store forwarding)
#pragma GCC unroll 8
    for (idx i = 0; i < n; ++i) {
        yv -= ddc(0, i) * X[i] + ddc(2, i) * X[n + i];
        wv += ddc(1, i) * X[i] + ddc(3, i) * X[n + i];
    }
    return {yv, wv};
}

// (y'', W'') of a moving ball's bar state X under the tip force f: a free (or slipping)
// ball's (ydd), or a rolling one's, y'' = -kroll F with F = sum psi_d a_free / kappa - foff
// the floor's friction rolling needs, W'' with F + F_b on the bar (ddc's F_b column).
inline std::pair<double, double> ball_ydd(Vec X, double f, const Segment& seg, Mat ddc, idx n,
                                          Regime mode, double kroll) {
    if (mode != ROLL) return ydd(X, f, seg.fb, seg.acc, ddc, n);
    auto [yv0, wv0] = ydd(X, f, 0.0, 0.0, ddc, n);  // -sum psi_d a_free, the free W''
    const double F = -yv0 / seg.kappa - seg.foff;
    return {-kroll * F, wv0 + ddc(1, n + 1) * (F + seg.fb)};
}

struct GridPoint {
    ncplx phg;
    double ydd, wdd;
};

// A whole grid step of level lev outside a cut: the eigen-coordinates qg and the forcing
// phasor phg advanced, X from them, the event functions at the step's end b and (if ydd_on)
// y'' and W'' there (else NaN).  NZ > 0: the sizes as compile-time constants (one and two
// modes, ks = 2), so the compiler unrolls them; the same operations.  The phasors come by
// reference: a complex passed by value reaches the callee as two halves that it stores and
// reloads as one (a stalled store forwarding, a fifth of the step's time).  Inlined in the
// search's loop (GCC called it: with the rare work out of the loop, inlined it is ~10%
// faster on zero-event runs).
template <idx NZ>
BB_ALWAYS_INLINE GridPoint grid_point(Work& w, SegCtx c, double b, idx lev, const ncplx& phg_a,
                                      const ncplx& rot, bool ydd_on, idx nz) {
    idx r = c.r, ks = c.ks, n = c.n;
    const double f0 = w.sys.q.force.f0, om = w.sys.q.force.om;
    // the regime's tables seen with their row lengths as constants where the sizes are (the
    // shapes the bindings checked: eh (R, GRID_LEVELS, nz), Vh (R, nz, nz), Z and D (R, nz),
    // mk (6, n), ddc (4, n + 2)): an element's offset without multiplications by run-time
    // strides, re-read from Work at each step
    CArr3 eh = w.eh;
    ClosedForm cf = w.cf;
    Mat mk = w.sys.mk;
    Mat ddc = w.sys.ddc;
    if constexpr (NZ > 0) {
        nz = NZ;
        ks = 2;
        n = NZ / 2;
        eh = {w.eh.d, w.eh.n0, GRID_LEVELS, NZ};
        cf.V = {w.cf.V.d, w.cf.V.n0, NZ, NZ};
        cf.Z = {w.cf.Z.d, w.cf.Z.n0, NZ};
        cf.D = {w.cf.D.d, w.cf.D.n0, NZ};
        mk = {w.sys.mk.d, 6, NZ / 2};
        ddc = {w.sys.ddc.d, 4, NZ / 2 + 2};
    }
    const Segment& seg = w.seg;
    // the tip force's sine for a ball off FREE first: glibc's sin saves MXCSR (stmxcsr),
    // which waits for every floating-point operation in flight; at the step's start, before
    // from_q's chains, it waits for fewer (a stuck ball's step ~8% faster)
    double sn = c.mode != FREE ? std::sin(om * (seg.ts + b)) : NAN;
    CVec qg = w.qg;
    for (idx kq = 0; kq < nq(nz, ks); ++kq) {
        idx k = kq * ks;
        qg[k] = ncplx(qg[k]) * ncplx(eh(r, lev, k));
    }
    ncplx phg = phg_a * rot;
    Vec X{w.X.d, nz};
    from_q(cf, r, ks, qg, phg, seg.fb, X);
    events(w.ev_b, X, b, seg, c.mode, mk, w.sys.q.force, sn);
    if (ydd_on) {
        auto [yv, wv] = ball_ydd(X, f0 * phg.imag(), seg, ddc, n, c.mode, w.sys.q.roll.kroll);
        return {phg, yv, wv};
    }
    return {phg, NAN, NAN};
}

// Adds a segment's flows ``out`` (over its length T) to the metrics and moves a free ball to
// the segment's end (into rs; pdu: psi_d . u at its start).
inline void close_flows(Work& w, SegCtx c, double T, bool steady, double pdu) {
    Vec out = w.out;
    Vec met = w.met;
    const Segment& seg = w.seg;
    const Regime mode = c.mode;
    const idx n = c.n;
    const double fb = seg.fb;
    met[L::W_FORCE] += out[0];
    met[L::D_VISC] += out[1];
    met[L::W_NONRECIP] += out[5];
    if (steady) {
        met[L::SUM_W2] += out[2];
        met[L::SUM_W] += out[3];
        met[L::SUM_F] += out[4];
        met[L::N_STEADY] += T;
        if (mode == CONTACT) met[L::T_CONTACT] += T;
    }
    if (c.ball) {
        auto [pdu1, pdv1] = psi_dot(w.sys.mk, MK_PSI_D, w.X, n);
        BallState& b = w.rs.ball;
        if (mode == FREE || mode == ROLL) {
            double y = b.y;
            double ynew = ball_y(seg, T, pdu1);
            b.yd = ball_yd(seg, T, pdv1);
            met[L::D_FRICTION] -= fb * (ynew - y);
            met[L::W_NONRECIP] += (1.0 - w.sys.q.fric.sr) * fb * (pdu1 - pdu);
            b.y = ynew;
        }
        if (seg.rolls) {
            // the spin: y' while rolling, else s0 + sd T, the floor's friction dissipating
            // ffl int s (beside the -ffl (y_end - y_start) counted in fb above when slipping)
            if (mode == ROLL) {
                b.spin = b.yd;
            } else {
                met[L::D_FRICTION] += seg.ffl * T * (seg.s0 + 0.5 * seg.sd * T);
                b.spin = seg.s0 + seg.sd * T;
            }
        }
    }
}

struct CutSegment {
    double t_seg_end;
    bool at_node, from_node;
    idx j_node;
};

// Where a segment of a cut that starts at t ends (the next node, delayed knot or change of
// the minimising revolution, before t_stop) and the surface on it, one cubic (into seg.s);
// j_node: the last node reached.
inline CutSegment cut_segment(double t, double t_stop, idx j_node, History& hs, Segment& seg,
                              const CutConsts& cq, const RunState& rs) {
    const Mat kn = hs.kn.view();
    const idx nk = hs.nk;
    const Span1<idx> ip = hs.ip;
    double t0 = cq.t0;
    double hh_ = cq.h;
    double ttol = cq.ttol;
    idx nrev = cq.nrev;
    double tau_d = cq.tau;
    double feed = cq.feed;
    double w_before = cq.w0;
    idx m_rev = cq.mrev;
    bool cubic = cq.cubic;
    // this segment ends at the next node, delayed knot or change of the minimising
    // revolution: the surface is one cubic on it
    while (t0 + double(j_node + 1) * hh_ <= t + ttol) j_node += 1;
    double t_seg_end = pymin(t0 + double(j_node + 1) * hh_, t_stop);
    bool at_node = t_seg_end < t_stop;
    bool from_node = std::fabs(t - (t0 + double(j_node) * hh_)) <= ttol;
    if (rs.first_zero < 0.0) {
        // one revolution (the minimum until the first zero), as surface_piece's k = 1
        for (idx k = 1; k <= nrev; ++k) {
            double kt = double(k) * tau_d;
            idx i = ip[k];
            while (i + 1 < nk && kn(i + 1, 0) + kt <= t + ttol) i += 1;
            ip[k] = i;
        }
        idx i = ip[1];
        if (i < 0) {
            seg.s[0] = feed + w_before;
            seg.s[1] = 0.0;
            seg.s[2] = 0.0;
            seg.s[3] = 0.0;
        } else {
            double x0 = (t - tau_d) - kn(i, 0);
            if (from_node && kn(i, 4) == double(j_node - m_rev)) x0 = 0.0;
            auto [c0, c1, c2, c3] = hermite_at(kn(i, 0), kn(i, 1), kn(i, 3), kn(i + 1, 0),
                                               kn(i + 1, 1), kn(i + 1, 2), x0, cubic);
            seg.s[0] = feed + c0;
            seg.s[1] = c1;
            seg.s[2] = c2;
            seg.s[3] = c3;
        }
        if (i + 1 < nk) {
            double tn = kn(i + 1, 0) + tau_d;
            if (t + ttol < tn && tn < t_seg_end - ttol) {
                t_seg_end = tn;
                at_node = false;
            }
        }
    } else {
        double t_piece =
            surface_piece(t, t_seg_end, hs, cq, nrev, seg, from_node ? j_node : idx(-1));
        if (t_piece < t_seg_end) {
            t_seg_end = t_piece;
            at_node = false;
        }
    }
    return {t_seg_end, at_node, from_node, j_node};
}

struct Bounds {
    double b4, bw4, b3y, b3w;
};

// Which bounds a segment's search needs: |y^(4)| (a ball; incut: in a cut, whose input
// the bound must take off), |W^(4)| (w_steady) and |y^(3)|, |W^(3)| (adapt).
struct BoundsWanted {
    bool ball, incut, w_steady, adapt;
};

// Bounds over the segment of w (regime r, eigen-coordinates w.q0, surface w.seg.s; Kr b
// krb) from prepare's bnd: |y^(4)| if ball, |W^(4)| if w_steady (else -1), |y^(3)| and
// |W^(3)| if adapt (else 0).
inline Bounds bounds(const Work& w, idx r, double krb, BoundsWanted want) {
    const CVec q0 = w.q0;
    const Segment& seg = w.seg;
    const CMat lam = w.cf.lam, bq = w.cf.bq;
    const Arr3 bnd = w.bnd;
    const bool ball = want.ball, incut = want.incut, w_steady = want.w_steady;
    const bool adapt = want.adapt;
    idx nz = q0.size();
    // a bound on |y^(4)| = |psi_d . u^(4)| over the segment (|exp(lambda tau)| <= 1)
    double b4 = 0.0;
    // |q0_k| (hypot) once for the three sums below: the same values
    std::array<double, NZ_MAX> aqs;
    bool aq_done = false;
    auto abs_q0 = [&]() {
        if (!aq_done) {
            for (idx k = 0; k < nz; ++k) aqs[k] = abs(ncplx(q0[k]));
            aq_done = true;
        }
    };
    if (ball) {
        if (!incut) abs_q0();
        b4 = bnd(r, 0, nz);  // Omega^4 |psi_d . Z|
        for (idx k = 0; k < nz; ++k) {
            ncplx qk = q0[k];
            if (incut) {
                // minus the polynomial particular solution P of q' = lambda q + g(tau)
                // (P^(4) = 0 for a cubic g); |exp(lambda tau)| <= 1 still
                ncplx lk = lam(r, k);
                ncplx gk = krb * ncplx(bq(r, k));
                ncplx p3 = -gk * seg.s[3] / lk;
                ncplx p2 = (3.0 * p3 - gk * seg.s[2]) / lk;
                ncplx p1 = (2.0 * p2 - gk * seg.s[1]) / lk;
                qk = qk - (p1 - gk * seg.s[0]) / lk;
            }
            b4 += bnd(r, 0, k) * (incut ? abs(qk) : aqs[k]);  // |lambda_k|^4 |psi_d . V_k| |q_k|
        }
    }
    // the same bound on |W^(4)| in the steady window under harmonic forcing: a W' = 0
    // extremum is located only where it may beat the running extremes
    double bw4 = -1.0;
    if (w_steady) {
        bw4 = bnd(r, 1, nz);
        abs_q0();
        for (idx k = 0; k < nz; ++k) bw4 += bnd(r, 1, k) * aqs[k];
    }
    // a free ball under harmonic forcing: bounds on |y'''| and |W'''| for its longer steps
    double b3y = 0.0;
    double b3w = 0.0;
    if (adapt) {
        b3y = bnd(r, 2, nz);
        b3w = bnd(r, 3, nz);
        abs_q0();
        for (idx k = 0; k < nz; ++k) {
            double aq = aqs[k];
            b3y += bnd(r, 2, k) * aq;
            b3w += bnd(r, 3, k) * aq;
        }
    }
    return {b4, bw4, b3y, b3w};
}

// quad_range(p, d, dd, s) (events.hpp) for several s: its vertex, which does not depend on
// s, computed once (the same operations, so the same (lo, hi)), and only where it may lie
// at x > 0: -d / dd is positive only if d and dd have opposite signs (a NaN, a zero or equal
// signs give x <= 0 or NaN, which at() ignores as it ignores the default x = 0)
struct QuadRange {
    double p, d, dd, x = 0.0, v = 0.0;

    QuadRange(double p_, double d_, double dd_) : p(p_), d(d_), dd(dd_) {
        if ((d < 0.0 && dd > 0.0) || (d > 0.0 && dd < 0.0)) {
            x = -d / dd;
            v = p + 0.5 * d * x;
        }
    }

    std::pair<double, double> at(double s) const {
        double p1 = p + s * (d + 0.5 * dd * s);
        double lo = pymin(p, p1);
        double hi = pymax(p, p1);
        if (dd != 0.0 && 0.0 < x && x < s) {
            lo = pymin(lo, v);
            hi = pymax(hi, v);
        }
        return {lo, hi};
    }
};

// The Taylor remainders of the longer steps 2^lv h of a segment (level's e3, e2 and W's e3
// without its margin), the same per step: computed once per segment; hl: the step lengths,
// top: the highest level allowed.
struct LevelBounds {
    double e3y[GRID_LEVELS] = {}, e2y[GRID_LEVELS] = {}, e3w[GRID_LEVELS] = {};
    double e1y[GRID_LEVELS] = {};  // b3y s (1 + 1e-9): how far y'' may move in a step
    const double* hl;
    idx top;

    LevelBounds(double b3y, double b3w, const double* hl_, idx top_) : hl(hl_), top(top_) {
        for (idx lv = 1; lv <= top; ++lv) {
            double hs = hl[lv];
            e3y[lv] = b3y * hs * hs * hs / 6.0;
            e2y[lv] = b3y * hs * hs * (0.5 + 1e-9);
            e3w[lv] = b3w * hs * hs * hs / 6.0;
            e1y[lv] = b3y * hs * (1.0 + 1e-9);
        }
    }
};

// The longest step 2^lev h (lev <= lb.top) from a free ball's grid point a (its event
// functions ev_a, y'' = ydd_a, W, W', W'' = wa) that Taylor's theorem proves free of events
// and of new extrema of |y| (beyond the running extremes e, below the walls at half) or, in
// the steady window, of W: on [a, a + s], y lies within b3y s^3 / 6 of its quadratic Taylor
// polynomial at a, y' within b3y s^2 / 2 of its linear one, W within b3w s^3 / 6 of its
// quadratic (docs/exact.md, "Longer steps").  (Inlined: GCC had stopped inlining it in the
// constant-size searches, ~3% on zero-event runs.)
BB_ALWAYS_INLINE idx level(Vec ev_a, double ydd_a, TipW wa, const LevelBounds& lb,
                           const Extremes& e, double half, const SegSearch& sv) {
    const bool steady = sv.steady, watch_v = sv.watch_v;
    const double ylim = pymin(half, steady ? e.max_aux : e.max_aux_all) * (1.0 - 1e-9);
    const double wmar = 1e-9 * e.max_abs_w, max_w = e.max_w, min_w = e.min_w;
    const double ya = ev_a[EV_PLUS] + half, yda = ev_a[EV_YEXT];
    const double* hl = lb.hl;
    const idx top = lb.top;
    idx lev = 0;
    QuadRange qy(ya, yda, ydd_a);
    QuadRange qw(0.0, 0.0, 0.0);  // W's, built where first needed
    bool qw_set = false;
    for (idx lv = 1; lv <= top; ++lv) {
        double hs = hl[lv];
        auto [lo, hi] = qy.at(hs);
        double e3 = lb.e3y[lv];
        if (!(hi + e3 < ylim && lo - e3 > -ylim)) break;
        if (watch_v) {
            double e2 = lb.e2y[lv];
            double v1 = yda + ydd_a * hs;
            if (!((yda > e2 && v1 > e2) || (yda < -e2 && v1 < -e2))) break;
        }
        // a rolling ball's y'' = -kroll F stays below kroll mu_s N (it keeps rolling)
        if (sv.ydd_max >= 0.0 && !(std::fabs(ydd_a) + lb.e1y[lv] < sv.ydd_max)) break;
        if (sv.watch_slip) {  // a slipping ball's slip keeps its sign (s is linear in tau)
            double e2 = lb.e2y[lv];
            double v0 = -ev_a[EV_SLIP];
            double v1 = v0 + sv.slip * (ydd_a - sv.sd) * hs;
            if (!(v0 > e2 && v1 > e2)) break;
        }
        if (steady) {
            if (!qw_set) {
                qw = QuadRange(wa.w, wa.wd, wa.wdd);
                qw_set = true;
            }
            auto [wlo, whi] = qw.at(hs);
            double we3 = lb.e3w[lv] + wmar;
            if (!(whi + we3 < max_w && wlo - we3 > min_w)) break;
        }
        lev = lv;
    }
    return lev;
}

struct Found {
    idx kind;
    double t;
};

// A ball held on the bore or a wall, or rolling: the first of its release events (a stuck
// ball's slip, a rolling one's beyond mu_s N, a wall's release) in [a, b].
inline Found regime_event(Work& w, SegCtx c, double a, double b) {
    const Regime mode = c.mode;
    double best = b;
    idx kind = -1;
    for (idx kk : {EV_REL_NEG, EV_REL_POS, EV_WALL_REL}) {
        if ((mode != CONTACT) == (kk != EV_WALL_REL)) {  // a rolling ball: its roll's limit
            if (w.ev_a[kk] <= 0.0 && 0.0 < w.ev_b[kk]) {
                double tr = find_root_any(kk, a, w.ev_a[kk], b, w.ev_b[kk], view(w, c), -1.0);
                if (tr < best || kind < 0) {
                    best = tr;
                    kind = kk;
                }
            }
        }
    }
    return {kind, best};
}

// may_graze's margin b4 h^4 / 192 for the step length h, kept while h and b4 repeat (the
// usual grid step): the same value without its division at every step
struct GrazeMargin {
    double h = NAN, b4 = NAN, m = 0.0;

    double at(double h_, double b4_) {
        if (!(h_ == h && b4_ == b4)) {
            h = h_;
            b4 = b4_;
            m = b4_ * ipow(h_, 4) / 192.0;
        }
        return m;
    }
};

// may_graze (events.hpp) with its margin from gm: the same test, operation for operation
inline bool may_graze_m(double a, double b, Vec ev_a, Vec ev_b, double half, double b4,
                        GrazeMargin& gm) {
    double h = b - a;
    double p0 = ev_a[EV_PLUS] + half;
    double p1 = ev_b[EV_PLUS] + half;
    double m0 = ev_a[EV_YEXT] * h;
    double m1 = ev_b[EV_YEXT] * h;
    double margin = gm.at(h, b4);
    // |p| <= max(|p0|, |p1|) + 4/27 (|m0| + |m1|) on [0, 1]: far from both walls, done
    if (pymax(std::fabs(p0), std::fabs(p1)) + 0.15 * (std::fabs(m0) + std::fabs(m1)) +
            margin < half)
        return false;
    auto [lo, hi] = _cubic_range(p0, p1, m0, m1);
    return hi + margin >= half || lo - margin <= -half;
}

// wall_event_found's search of the step st for the walls and y' = 0.
inline Found wall_event_any(Work& w, SegCtx c, const SegSearch& sv, StepEnds st, bool graze,
                            bool search) {
    const double a = st.a, b = st.b;
    const bool watch_v = sv.watch_v, watch_ext = sv.watch_ext;
    Vec ev_a = st.ev_a;
    Vec ev_b = st.ev_b;
    double best = b;
    idx kind = -1;
    if (search) {
        auto [k, tb] = wall_step(st, watch_v, watch_ext, view(w, c));
        kind = k;
        best = tb;
    }
    if (kind < 0 && graze) {
        // look again on NSUB sub-steps (direct evaluations)
        Vec ev_s = w.ev_s;
        Vec ev_t = w.ev_t;
        for (idx kk = 0; kk < N_EV; ++kk) ev_s[kk] = ev_a[kk];
        double sa = a;
        for (idx j = 1; j <= NSUB; ++j) {
            double sb = j < NSUB ? a + (b - a) * double(j) / double(NSUB) : b;
            if (j < NSUB) {
                state_at(view(w, c), sb, w.qs, w.dX);
                events(ev_t, w.dX, sb, w.seg, c.mode, w.sys.mk, w.sys.q.force);
            } else {
                for (idx kk = 0; kk < N_EV; ++kk) ev_t[kk] = ev_b[kk];
            }
            auto [k, tb] = wall_step(StepEnds{sa, sb, 0, ev_s, ev_t, NAN, NAN}, watch_v,
                                     watch_ext, view(w, c));
            kind = k;
            best = tb;
            if (kind >= 0) break;
            sa = sb;
            for (idx kk = 0; kk < N_EV; ++kk) ev_s[kk] = ev_t[kk];
        }
    }
    return {kind, best};
}

// The largest value of c0 + c1 s + c2 s^2 + c3 s^3 on [lo, hi]: at an end or where its
// derivative is zero.
inline double cubic_max(double c0, double c1, double c2, double c3, double lo, double hi) {
    auto at = [&](double s) { return c0 + s * (c1 + s * (c2 + s * c3)); };
    double best = pymax(at(lo), at(hi));
    const double qa = 3.0 * c3, qb = 2.0 * c2, qc = c1;  // the derivative's coefficients
    if (std::fabs(qa) > 1e-300) {
        const double disc = qb * qb - 4.0 * qa * qc;
        if (disc >= 0.0) {
            const double sq = std::sqrt(disc);
            for (double r : {(-qb - sq) / (2.0 * qa), (-qb + sq) / (2.0 * qa)})
                if (lo < r && r < hi) best = pymax(best, at(r));
        }
    } else if (std::fabs(qb) > 1e-300) {
        const double r = -qc / qb;
        if (lo < r && r < hi) best = pymax(best, at(r));
    }
    return best;
}

// Whether an event function v, below zero at both ends of a grid step of length h (p0,
// p1) with rates d0, d1 there and |v'''| <= b4 over it, may reach zero inside the step.
// The cubic Hermite interpolant H of v differs from v by e, with double zeros at both
// ends and |e'''| <= 6 b4 (H''' = 3 v'''(x1) - 2 v'''(x2)), so |e| <= b4 (x - a)^2 (b - x)
// and |e| <= b4 (x - a) (b - x)^2: in s = (x - a) / h, v <= H + b4 h^3 s^2 (1 - s) on
// [0, 1/2] and v <= H + b4 h^3 s (1 - s)^2 on [1/2, 1], two cubics whose largest values
// say whether v may rise above 0 (a step that starts at v = 0, just after the event there,
// is not taken for one that comes back to it).  (The bound's largest value, 4 b4 h^3 / 27,
// rejects most steps first.  An excursion shorter than a grid step shows at neither end,
// and the search would pass it by.)
inline bool may_come_back(double p0, double p1, double d0, double d1, double h, double b4) {
    const double m0 = d0 * h;
    const double m1 = d1 * h;
    const double margin = 4.0 * b4 * h * h * h / 27.0;
    // H <= max(p0, p1) + 4/27 (|m0| + |m1|) on [0, 1]: far below zero, done
    if (pymax(p0, p1) + 0.15 * (std::fabs(m0) + std::fabs(m1)) + margin < 0.0) return false;
    const double B = b4 * h * h * h;
    // H in powers of s: p0 + m0 s + c2 s^2 + c3 s^3
    const double c2 = -3.0 * p0 - 2.0 * m0 + 3.0 * p1 - m1;
    const double c3 = 2.0 * p0 + m0 - 2.0 * p1 + m1;
    return cubic_max(p0, m0, c2 + B, c3 - B, 0.0, 0.5) > 0.0
           || cubic_max(p0, m0 + B, c2 - 2.0 * B, c3 + B, 0.5, 1.0) > 0.0;
}

// The rate of the event function kind from y'' (sdir: a sliding ball's direction): -sdir
// y'' for EV_VSTOP, -slip (y'' - s') for EV_SLIP.
inline double rate_from_ydd(const SegSearch& sv, double sdir, idx kind, double ydd) {
    return kind == EV_VSTOP ? -sdir * ydd : -sv.slip * (ydd - sv.sd);
}

// Whether a slipping ball's slip may run out and come back inside the grid step st, whose
// ends show it slipping: its event function v = -slip (y' - s) has v' = -slip (y'' - s')
// at the ends, and |v'''| = |y^(4)| <= b4.  (Missed, the floor's friction keeps its sign
// through the excursion.)
inline bool slip_may_turn(const SegSearch& sv, const StepEnds& st) {
    return may_come_back(st.ev_a[EV_SLIP], st.ev_b[EV_SLIP],
                         rate_from_ydd(sv, 0.0, EV_SLIP, st.ydd_a),
                         rate_from_ydd(sv, 0.0, EV_SLIP, st.ydd_b), st.b - st.a, sv.b4);
}

// Whether a sliding ball with friction may come to y' = 0 and back inside the grid step
// st, whose ends show it sliding the way sdir says: its event function v = -sdir y' has
// v' = -sdir y'' at the ends, and |v'''| = |y^(4)| <= b4.  (Missed, the friction keeps
// its sign through the excursion, where the ball would have stuck or turned.)
// (Out of the search's loop: inlined there, it moved GCC's inlining of the loop's other
// helpers, and runs without friction took 5-14 % longer.)
BB_NOINLINE inline bool stop_may_turn(const SegSearch& sv, double sdir, const StepEnds& st) {
    const double p0 = st.ev_a[EV_VSTOP], p1 = st.ev_b[EV_VSTOP];
    if (!(p0 <= 0.0 && p1 <= 0.0)) return false;  // a crossing at the ends is searched
    if (!(st.ydd_a == st.ydd_a && st.ydd_b == st.ydd_b)) return false;  // (a cut: no y'')
    return may_come_back(p0, p1, rate_from_ydd(sv, sdir, EV_VSTOP, st.ydd_a),
                         rate_from_ydd(sv, sdir, EV_VSTOP, st.ydd_b), st.b - st.a, sv.b4);
}

// The rate of the event function kind at tau of the segment (X the state there).
inline double turn_rate(Work& w, SegCtx c, const SegSearch& sv, idx kind, double tau, Vec X) {
    const double f = w.sys.q.force.f0 * std::sin(w.sys.q.force.om * (w.seg.ts + tau));
    const double ydd = ball_ydd(X, f, w.seg, w.sys.ddc, c.n, c.mode, w.sys.q.roll.kroll).first;
    return rate_from_ydd(sv, w.seg.sdir, kind, ydd);
}

// Most halvings of a step in turn_root: beyond, an excursion of v above zero would last
// less than 2^-TURN_DEPTH of the step, and its height be below b4 (h 2^-TURN_DEPTH)^3.
constexpr int TURN_DEPTH = 12;

// An event function's value v and rate d at the time t.
struct VEnd {
    double t, v, d;
};

// The first crossing from below of the event function kind (EV_SLIP, EV_VSTOP) in [a.t,
// b.t] (both ends below zero, and may_come_back allowing one): v at the midpoint, and if
// it is not above zero each half tested again, left first, its bound 8 times tighter,
// and searched the same way where it allows one, until the halves are proven free or v is
// above zero at a midpoint (the root then lies between it and the half's start); -1 if
// none.  A sliding ball's y' that leaves zero the wrong way at the step's start (as only
// inconsistent inputs, such as a massless ball, make it) is no return: a root there would
// end segment after segment a few ulp long.
inline double turn_root(Work& w, SegCtx c, const SegSearch& sv, idx kind, VEnd a, VEnd b,
                        int depth) {
    const double m = 0.5 * (a.t + b.t);
    state_at(view(w, c), m, w.qs, w.dX);
    events(w.ev_t, w.dX, m, w.seg, c.mode, w.sys.mk, w.sys.q.force);
    const double vm = w.ev_t[kind];
    if (vm > 0.0) {
        const bool from_below = kind == EV_VSTOP ? a.v < 0.0 : a.v <= 0.0;
        return from_below ? find_root_any(kind, a.t, a.v, m, vm, view(w, c), -1.0) : -1.0;
    }
    if (depth == TURN_DEPTH) return -1.0;
    const VEnd mid{m, vm, turn_rate(w, c, sv, kind, m, w.dX)};
    for (const auto& [lo, hi] : {std::pair{a, mid}, std::pair{mid, b}}) {
        if (may_come_back(lo.v, hi.v, lo.d, hi.d, hi.t - lo.t, sv.b4)) {
            const double r = turn_root(w, c, sv, kind, lo, hi, depth + 1);
            if (r >= 0.0) return r;
        }
    }
    return -1.0;
}

// turn_root on the grid step st (slip_may_turn or stop_may_turn allowing a return inside
// it), whose ends' rates come from y'' there.
inline double turn_root(Work& w, SegCtx c, const SegSearch& sv, const StepEnds& st, idx kind) {
    const double sdir = w.seg.sdir;
    return turn_root(w, c, sv, kind,
                     VEnd{st.a, st.ev_a[kind], rate_from_ydd(sv, sdir, kind, st.ydd_a)},
                     VEnd{st.b, st.ev_b[kind], rate_from_ydd(sv, sdir, kind, st.ydd_b)}, 0);
}

// Whether the step may hold a crossing and return of the slip (a slipping rolling ball)
// or of y' (a sliding ball with friction) that its ends do not show (slip_may_turn,
// stop_may_turn).
struct Turns {
    bool slip, stop;
};

// The friction's end inside the step st that the walls are looked for before: a rolling
// ball's slip running out (at a crossing the ends show, or one that turns.slip allows
// inside the step), or a sliding ball's y' coming to zero and back (turns.stop; a crossing
// that the ends show is the wall search's own).  {-1, -1}: none.
inline Found friction_end(Work& w, SegCtx c, const SegSearch& sv, const StepEnds& st,
                          Turns turns) {
    Found end{-1, -1.0};
    if (sv.watch_slip && st.ev_a[EV_SLIP] <= 0.0 && 0.0 < st.ev_b[EV_SLIP]) {
        end = {EV_SLIP, find_root_any(EV_SLIP, st.a, st.ev_a[EV_SLIP], st.b, st.ev_b[EV_SLIP],
                                      view(w, c), -1.0)};
    } else if (turns.slip) {
        end = {EV_SLIP, turn_root(w, c, sv, st, EV_SLIP)};
    }
    if (turns.stop) {
        const double t = turn_root(w, c, sv, st, EV_VSTOP);
        if (t >= 0.0 && !(end.t >= 0.0 && end.t <= t)) end = {EV_VSTOP, t};
    }
    return end;
}

// What wall_event does when a step shows something (see there): kept out of the loop.
BB_NOINLINE inline Found wall_event_found(Work& w, SegCtx c, const SegSearch& sv, StepEnds st,
                                          bool graze, bool search, Turns turns) {
    // the friction's end inside the step: the walls are looked for before it
    const Found end = friction_end(w, c, sv, st, turns);
    if (end.t >= 0.0) {
        state_at(view(w, c), end.t, w.qs, w.dX);
        events(w.ev_u, w.dX, end.t, w.seg, c.mode, w.sys.mk, w.sys.q.force);
        st = StepEnds{st.a, end.t, st.lev, st.ev_a, w.ev_u, st.ydd_a, NAN};
        graze = st.lev == 0 && may_graze(st.a, end.t, st.ev_a, w.ev_u, w.sys.q.ball.half, sv.b4);
        search = (st.ev_a[EV_PLUS] <= 0.0 && 0.0 < w.ev_u[EV_PLUS])
                 || (st.ev_a[EV_MINUS] <= 0.0 && 0.0 < w.ev_u[EV_MINUS])
                 || (sv.watch_v && st.ev_a[EV_VSTOP] <= 0.0 && 0.0 < w.ev_u[EV_VSTOP]);
    }
    Found f = wall_event_any(w, c, sv, st, graze, search);
    if (f.kind < 0 && end.t >= 0.0) return end;
    return f;
}

// A free ball's wall and friction-switch events in the step st, with the graze guard's
// sub-steps where the bound on y^(4) allows a crossing and return inside the step.  The
// tests on the step's ends are here, in the search's loop; the rare search out of it.
inline Found wall_event(Work& w, SegCtx c, const SegSearch& sv, StepEnds st, GrazeMargin& gm) {
    const double a = st.a, b = st.b;
    const bool watch_v = sv.watch_v, watch_ext = sv.watch_ext;
    const idx lev = st.lev;
    const double b4 = sv.b4;
    Vec ev_a = w.ev_a;
    Vec ev_b = w.ev_b;
    double half = w.sys.q.ball.half;
    // call the search only when an end value shows something, or y' changes sign and the
    // bound on y lets the ball reach a wall (a longer step than h holds no wall event)
    bool graze = lev == 0 && may_graze_m(a, b, ev_a, ev_b, half, b4, gm);
    bool search = (ev_a[EV_PLUS] <= 0.0 && 0.0 < ev_b[EV_PLUS])
                  || (ev_a[EV_MINUS] <= 0.0 && 0.0 < ev_b[EV_MINUS])
                  || (watch_v && ev_a[EV_VSTOP] <= 0.0 && 0.0 < ev_b[EV_VSTOP])
                  || (graze && watch_ext && ev_a[EV_YEXT] * ev_b[EV_YEXT] < 0.0)
                  || (sv.watch_slip && ev_a[EV_SLIP] <= 0.0 && 0.0 < ev_b[EV_SLIP]);
    // (a longer step, lev > 0, is proven free of the slip's end and of y' = 0 by level())
    const bool slip_turn = sv.watch_slip && lev == 0 && slip_may_turn(sv, st);
    const bool stop_turn = watch_v && lev == 0 && stop_may_turn(sv, w.seg.sdir, st);
    if (!search && !graze && !slip_turn && !stop_turn) return {-1, b};
    return wall_event_found(w, c, sv, st, graze, search, Turns{slip_turn, stop_turn});
}

// The tool leaving (in the cut) or re-entering (out of it) in [a, b]: h = 0, or a graze of
// h = 0 between the step's ends, found at the extremum of h.  -1: none.
inline double cut_event(Work& w, SegCtx c, double a, double b) {
    Vec ev_a = w.ev_a;
    Vec ev_b = w.ev_b;
    double tr = -1.0;
    if (ev_a[EV_CUT] <= 0.0 && 0.0 < ev_b[EV_CUT]) {
        tr = find_root_any(EV_CUT, a, ev_a[EV_CUT], b, ev_b[EV_CUT], view(w, c), -1.0);
    } else if (ev_a[EV_HEXT] * ev_b[EV_HEXT] < 0.0) {
        double te = find_root_any(EV_HEXT, a, ev_a[EV_HEXT], b, ev_b[EV_HEXT], view(w, c), -1.0);
        double ge = g_value(EV_CUT, te, view(w, c));
        if (ev_a[EV_CUT] <= 0.0 && 0.0 < ge) {
            tr = find_root_any(EV_CUT, a, ev_a[EV_CUT], te, ge, view(w, c), -1.0);
        }
    }
    return tr;
}

// The first event in the grid step st of the segment (context c) from the event functions
// at its ends (w.ev_a, w.ev_b) and (a free ball) y'' there: kind -1 if none.
template <bool Regen>
inline Found find_event(Work& w, SegCtx c, const SegSearch& sv, StepEnds st, GrazeMargin& gm) {
    const double a = st.a, b = st.b;
    Found f{-1, b};
    if (c.ball && (c.mode == STICK || c.mode == CONTACT)) {
        f = regime_event(w, c, a, b);
    } else if (c.ball) {
        f = wall_event(w, c, sv, st, gm);
        if (c.mode == ROLL) {  // and the friction rolling needs beyond mu_s N
            Found g = regime_event(w, c, a, b);
            if (g.kind >= 0 && (f.kind < 0 || g.t < f.t)) f = g;
        }
    }
    if constexpr (Regen) {
        double tr = cut_event(w, c, a, b);
        if (tr >= 0.0 && (f.kind < 0 || tr < f.t)) f = {EV_CUT, tr};
    }
    return f;
}

// (q0 tabE + sum_j S_j tabP_j) at the table's column g: a cut's whole step from its tables
inline void tab_state(Work& w, idx r, idx g, idx ks, CVec q, Vec X) {
    const Segment& seg = w.seg;
    CVec q0 = w.q0;
    idx nz = q0.size();
    for (idx kq = 0; kq < nq(nz, ks); ++kq) {
        idx k = kq * ks;
        q[k] = ncplx(q0[k]) * ncplx(w.tabE(r, g, k)) + seg.s[0] * ncplx(w.tabP(r, g, 0, k))
               + seg.s[1] * ncplx(w.tabP(r, g, 1, k)) + seg.s[2] * ncplx(w.tabP(r, g, 2, k))
               + seg.s[3] * ncplx(w.tabP(r, g, 3, k));
    }
    for (idx j = 0; j < nz; ++j) X[j] = add_modes(seg.fb * w.cf.D(r, j), w.cf.V, r, j, q, nz, ks);
}

// Adds a cut's flows over the grid step [a, b] to w.qsum (the slots of segment_integrals'
// out); whole: a whole step H from a node, without event, from the tables; wb: W at b.
// Returns the largest cutting force so far.
inline double cut_flows(Work& w, SegCtx c, double a, double b, bool whole, bool steady,
                        double wb, double max_force) {
    const idx r = c.r, ks = c.ks, n = c.n;
    const bool sticking = c.mode == STICK;
    const Segment& seg = w.seg;
    CVec q0 = w.q0;
    CVec qs = w.qs;
    Vec dX = w.dX;
    Vec qsum = w.qsum;
    Mat mk = w.sys.mk;
    idx nz = q0.size();
    double sr = w.sys.q.fric.sr;
    double krb_seg = seg.krb;
    double s_0 = seg.s[0];
    double s_1 = seg.s[1];
    double s_2 = seg.s[2];
    double s_3 = seg.s[3];
    // Gauss-Legendre (4 points, exact to degree 7) for the flows of the step: the input is
    // a cubic, no longer a sum of exponentials
    if (whole && !(sticking && sr != 1.0)) {
        // a whole step: tabulated values
        for (idx g = 0; g < 4; ++g) {
            tab_state(w, r, g, ks, qs, dX);
            const double wq = psi_dot(mk, MK_PSI_L, dX, n).first;  // W, which the chip reads
            double xg = GL_X[g] * b;
            double fq = krb_seg * (s_0 + xg * (s_1 + xg * (s_2 + xg * s_3)) - wq);
            max_force = pymax(max_force, fq);
            double wg = GL_W[g] * b;
            // the force works on psi_F . u' (W' but in an oriented cut)
            qsum[0] += wg * fq * psi_dot(mk, MK_PSI_F, dX, n).second;
            double dv = 0.0;
            for (idx d = 0; d < w.dp.l.n0; ++d) {
                double vv = 0.0;
                for (idx j = 0; j < nz; ++j) vv += w.dp.l(d, j) * dX[j];
                dv += w.dp.c[d] * vv * vv;
            }
            qsum[1] += wg * dv;
            if (steady) {
                qsum[2] += wg * wq * wq;
                qsum[3] += wg * wq;
                qsum[4] += wg * fq;
            }
        }
    } else {
        // the flows of a cut: the input is Kr b S, the harmonic force is off
        SegView s = view(w, c);
        s.f0 = 0.0;
        s.om = 0.0;
        max_force = pymax(max_force, quad_cut(a, b, s, w.dp, sticking, w.sys, qsum, steady));
    }
    return pymax(max_force, krb_seg * (s_0 + b * (s_1 + b * (s_2 + b * s_3)) - wb));
}

// row[1:5] of a history or strobe row, W, W', aux, aux', from the state in the work vector
// dX at tau (its time, row[0], is the caller's).
inline void row_state(Work& w, SegCtx c, double tau, double* row) {
    auto [wv, wdv] = psi_dot(w.sys.mk, MK_PSI_L, w.dX, c.n);
    auto [av, adv] = aux(w.dX, tau, w.seg, c, w.sys.mk, w.x);
    row[1] = wv;
    row[2] = wdv;
    row[3] = av;
    row[4] = adv;
}

// The state at tau into dX and row[1:5] (row_state); s: view(w, c), built once a segment.
inline void sample(Work& w, const SegView& s, SegCtx c, double tau, double* row) {
    state_at(s, tau, w.qs, w.dX);
    row_state(w, c, tau, row);
}

// A history row's W, W', aux, aux' and tip force from the state X (in w.dX) at tau of the
// segment from t, its forcing phasor ph = e^{i Omega (t + tau)}.
inline void history_row(Work& w, SegCtx c, double tau, ncplx ph, double* row) {
    row_state(w, c, tau, row);
    row[5] = cut_force(w.seg, tau, w.dX, c.n, w.sys.mk, w.sys.q.force.f0, w.sys.q.force.om, ph.im);
    // a rolling ball's spin where rec has its column: y' while rolling, else s0 + sd tau
    if (w.rec.n1 > L::REC_NCOL)
        row[L::REC_NCOL] = c.mode == ROLL ? row[4] : w.seg.s0 + w.seg.sd * tau;
}

// The history rows of a segment (every rec_dt from t0, in (t, t + b], before t_end, while
// rec has room), the next row's index into w.ro.k_rec.  Outside a cut by recurrence: from
// one row to the next each exp(lambda_k tau) and the forcing's phasor advance by one
// complex product with their values over rec_dt, so a row costs no exp, sin or cos (a 2 s
// run keeps 20000 rows, and those functions were most of its cost).  The recurrence w.rr
// runs on through the grid steps of one segment; the segment's first row and every
// REC_ANCHOR-th are the closed form's own, as is every row in a cut (its input's
// polynomial is no product of exponentials).
inline void history_rows(Work& w, const SegView& s, SegCtx c, double t, double b,
                         double t_end) {
    const idx r = s.r, ks = s.ks, nz = w.dX.n;
    const double t0 = w.cp.t0, rec_dt = w.cp.rec_dt, om = w.sys.q.force.om;
    Mat rec = w.rec;
    RowRecurrence& rr = w.rr;
    idx n_rec = idx(w.met[L::N_REC]);
    double k_rec = w.ro.k_rec;
    const bool recur = w.seg.krb == 0.0;
    if (rr.t_seg != t || rr.r != r) rr.since = REC_ANCHOR;
    while (n_rec < rec.n0 && t0 + k_rec * rec_dt <= t + b + 1e-9 * rec_dt) {
        const double ts_ = t0 + k_rec * rec_dt;
        if (ts_ > t_end) break;
        const double tau = ts_ - t;
        if (!recur || rr.since == REC_ANCHOR) {
            rr.ph = state_at(s, tau, w.qs, w.dX, rr.ex);
            rr.since = 0;
            rr.t_seg = t;
            rr.r = r;
        } else {
            if (rr.r_step != r) {
                for (idx kq = 0; kq < nq(nz, ks); ++kq)
                    rr.step[kq] = cexp(ncplx(s.cf.lam(r, kq * ks)) * rec_dt);
                rr.ph_step = cexp(ncplx(0.0, 1.0) * om * rec_dt);
                rr.r_step = r;
            }
            for (idx kq = 0; kq < nq(nz, ks); ++kq) {
                rr.ex[kq] = rr.ex[kq] * rr.step[kq];
                w.qs[kq * ks] = ncplx(s.q0[kq * ks]) * rr.ex[kq];
            }
            rr.ph = rr.ph * rr.ph_step;
            from_q(s.cf, r, ks, w.qs, rr.ph, w.seg.fb, w.dX);
        }
        rr.since += 1;
        double* row = rec.row(n_rec);
        row[0] = ts_;
        history_row(w, c, tau, rr.ph, row);
        n_rec += 1;
        k_rec += 1;
    }
    w.met[L::N_REC] = double(n_rec);
    w.ro.k_rec = k_rec;
}

// The history rows (every rec_dt from t0) and strobe rows (every tstrobe) that fall in
// (t + a, t + b] of the segment from t (context c, its view s), before t_end, into rec and
// strobe while they have room; the next ones' times into w.ro.
inline void samples(Work& w, const SegView& s, SegCtx c, double t, double b, double t_end) {
    double tstrobe = w.cp.tstrobe;
    Mat strobe = w.strobe;
    Vec met = w.met;
    double t_next_strobe = w.ro.t_strobe;
    if (w.cp.rec_dt > 0.0) history_rows(w, s, c, t, b, t_end);
    idx n_stb = idx(met[L::N_STROBE]);
    while (tstrobe > 0.0 && t_next_strobe <= t + b && t_next_strobe <= t_end) {
        if (n_stb < strobe.n0) {
            double* row = strobe.row(n_stb);
            row[0] = t_next_strobe;
            sample(w, s, c, t_next_strobe - t, row);
            n_stb += 1;
        }
        t_next_strobe += tstrobe;
    }
    met[L::N_STROBE] = double(n_stb);
    w.ro.t_strobe = t_next_strobe;
}

// e^{i om t} as cexp((i om) t): the products taken in complex arithmetic (ncplx)
inline ncplx phasor(double om, double t) { return cexp(ncplx(0.0, 1.0) * om * t); }

// The grid point b a step reaches (the step h 2^lev) and how its state is had: usual, by
// the grid's tables (a whole step outside a cut); tab_end, the tabulated end of a cut's
// whole step; else the closed form.
struct GridAt {
    double b;
    idx lev;
    bool usual, tab_end;
};

// What advance does off the usual grid (every 64th step, a segment's end): kept out of the
// search's loop.
template <bool Regen>
BB_NOINLINE GridPoint advance_other(Work& w, double t, SegCtx c, bool ydd_on, GridAt g,
                                    const ncplx& phg_a, double ydd_b, double wdd_b) {
    const idx r = c.r, ks = c.ks, n = c.n;
    const double b = g.b;
    const Segment& seg = w.seg;
    Vec X = w.X;
    double f0 = w.sys.q.force.f0;
    double om = w.sys.q.force.om;
    ncplx phg = phg_a;
    if (g.tab_end) {
        tab_state(w, r, 4, ks, w.qg, X);
    } else {
        if (c.sz != 0 && seg.krb == 0.0) {  // kept for segment_integrals, if b ends it
            state_at(view(w, c), b, w.qg, X, w.ex_end);
            w.tau_end = b;
            w.r_end = r;
        } else {
            state_at(view(w, c), b, w.qg, X);
        }
        phg = phasor(om, t + b);
    }
    if (c.ball || !Regen) {
        events(w.ev_b, X, b, seg, c.mode, w.sys.mk, w.sys.q.force);
        if (ydd_on) {
            auto [yv, wv] = ball_ydd(X, f0 * phg.imag(), seg, w.sys.ddc, n, c.mode,
                                     w.sys.q.roll.kroll);
            ydd_b = yv;
            wdd_b = wv;
        }
    } else {
        double s_0 = seg.s[0], s_1 = seg.s[1], s_2 = seg.s[2], s_3 = seg.s[3];
        auto [wq, wdq] = psi_dot(w.sys.mk, MK_PSI_L, X, n);
        w.ev_b[EV_CUT] = seg.cdir * (wq - (s_0 + b * (s_1 + b * (s_2 + b * s_3))));
        w.ev_b[EV_HEXT] = s_1 + b * (2.0 * s_2 + 3.0 * b * s_3) - wdq;
    }
    return {phg, ydd_b, wdd_b};
}

// The state at the grid point g.b of the segment from t into w.X (and w.qg and phg on the
// usual grid) and the event functions there into w.ev_b.  Returns phg and y'', W'' at b
// (ydd_b, wdd_b as they were where not evaluated).
template <bool Regen>
inline GridPoint advance(Work& w, double t, SegCtx c, bool ydd_on, GridAt g, const ncplx& phg_a,
                         double ydd_b, double wdd_b) {
    Vec X = w.X;
    idx nz = X.size();
    if (g.usual) {
        // the usual grid point, with the sizes constant for one and two modes
        const ncplx& rot = w.rotl[g.lev];
        if (c.sz == 1) return grid_point<2>(w, c, g.b, g.lev, phg_a, rot, ydd_on, 2);
        if (c.sz == 2) return grid_point<4>(w, c, g.b, g.lev, phg_a, rot, ydd_on, 4);
        return grid_point<0>(w, c, g.b, g.lev, phg_a, rot, ydd_on, nz);
    }
    return advance_other<Regen>(w, t, c, ydd_on, g, phg_a, ydd_b, wdd_b);
}

// What search_segment returns: the event kind (-1: none), its time from t or the segment's
// length, the forcing phasor there, W and W' at the end.
struct SegEvent {
    idx kind;
    double tau;
    ncplx ph_next;
    double wb, wdb;
};

// W at its W' = 0 extremum inside the grid step [a, b] (kind: the step's event, -1 if none;
// wa, wb: W, W', W'' at its ends): a start from the Hermite interpolant of W, then
// w_extremum_any.  Out of the search's loop.
BB_NOINLINE inline double w_extremum_in(Work& w, SegCtx c, double a, double b, idx kind,
                                        TipW wa, TipW wb) {
    double c0;
    if (kind < 0 && wa.wdd == wa.wdd && wb.wdd == wb.wdd) {  // W'' at both ends
        c0 = hermite5(a, b, Jet{wa.w, wa.wd, wa.wdd}, Jet{wb.w, wb.wd, wb.wdd}, 1);
    } else {
        c0 = hermite(a, b, wa.w, wb.w, wa.wd, wb.wd, 1);
    }
    return w_extremum_any(a, wa.wd, b, wb.wd, c0, w.cp.h, view(w, c));
}

// W's extremes at the end b of the grid step st and, where W' changes sign inside the step
// and the extremum may beat them (w_may_exceed, with the bound sv.bw4), at the located
// W' = 0 extremum.  Inlined in the search's loop (the extremes stay in registers), the rare
// search out of it.
BB_ALWAYS_INLINE void w_extremes(Work& w, Extremes& e, SegCtx c, const SegSearch& sv,
                                 StepEnds st, idx kind, TipW wa, TipW wb) {
    const double a = st.a, b = st.b, bw4 = sv.bw4;
    const idx lev = st.lev;
    const double wda = wa.wd, wdb = wb.wd;
    e.max_abs_w = pymax(e.max_abs_w, std::fabs(wb.w));
    e.max_w = pymax(e.max_w, wb.w);
    e.min_w = pymin(e.min_w, wb.w);
    if (lev == 0 && wda * wdb < 0.0
        && (bw4 < 0.0
            || w_may_exceed(b - a, wa, wb, bw4, e.max_w, e.min_w, e.max_abs_w))) {
        double we = w_extremum_in(w, c, a, b, kind, wa, wb);
        e.max_abs_w = pymax(e.max_abs_w, std::fabs(we));
        e.max_w = pymax(e.max_w, we);
        e.min_w = pymin(e.min_w, we);
    }
}

// The grid search of the segment from t (context c_in, forcing phasor ph at t, its
// description sv) for its first event, with the outputs on the way: the running extremes
// and output times in w.ro, a cut's flows in w.qsum, history and strobe rows.  NZ > 0 (one
// or two modes outside a cut, sz = NZ / 2): the sizes and mk's row length as constants.
template <bool Regen, idx NZ = 0>
inline SegEvent search_segment(Work& w, double t, SegCtx c_in, ncplx ph, const SegSearch& sv) {
    idx r = c_in.r, ks = c_in.ks, sz = c_in.sz, n = c_in.n;
    const layout::Case kase = c_in.kase;
    const Regime mode = c_in.mode;
    Vec X = w.X;
    Vec Xa = w.Xa;
    CVec q0 = w.q0;
    CVec qg = w.qg;
    const Segment& seg = w.seg;
    Vec ev_a = w.ev_a;
    Vec ev_b = w.ev_b;
    Mat mk = w.sys.mk;
    Vec met = w.met;
    idx nz = q0.size();
    if constexpr (NZ > 0) {
        static_assert(!Regen, "the constant sizes are for harmonic runs");
        nz = NZ;
        n = NZ / 2;
        ks = 2;
        sz = NZ / 2;
        X = {w.X.d, NZ};
        Xa = {w.Xa.d, NZ};
        q0 = {w.q0.d, NZ};
        qg = {w.qg.d, NZ};
        mk = {w.sys.mk.d, 6, NZ / 2};
    }
    bool ball = kase == L::BALL;
    // the context with the sizes as the search has them (constants in the copies)
    const SegCtx c{r, ks, sz, n, kase, mode, ball};
    const SegView out_view = view(w, c);  // the history's and the strobe's samples
    double f0 = w.sys.q.force.f0;
    double om = w.sys.q.force.om;
    double half = w.sys.q.ball.half;
    bool outputs = w.cp.rec_dt > 0.0 || w.cp.tstrobe > 0.0;
    double t_end = w.rs.t_end;
    double s_0 = seg.s[0];
    double s_1 = seg.s[1];
    double tlen = sv.tlen;
    bool steady = sv.steady;
    bool whole = sv.whole;
    bool adapt = sv.adapt;
    bool ydd_on = sv.ydd;
    Extremes e{w.ro.max_abs_w, w.ro.max_w,       w.ro.min_w,
               w.ro.max_aux,   w.ro.max_aux_all, w.ro.max_force};
    ncplx ph_next = ph;
    double wb = 0.0;
    double wdb = 0.0;
    // values at tau = 0
    double a = 0.0;
    for (idx j = 0; j < nz; ++j) Xa[j] = X[j];
    for (idx k = 0; k < nz; ++k) qg[k] = q0[k];
    w.tau_end = NAN;  // no state_at of this segment yet
    ncplx phg = ph;
    idx ev_kind = -1;
    double tau_ev = tlen;
    idx istep = 0;
    // the values at a (carried over from the previous grid point)
    auto [wa, wda] = psi_dot(mk, MK_PSI_L, Xa, n);
    if (ball || !Regen) {
        events(ev_a, Xa, a, seg, mode, mk, w.sys.q.force);
    } else {  // only h matters
        ev_a[EV_CUT] = seg.cdir * (wa - s_0);
        ev_a[EV_HEXT] = s_1 - wda;
    }
    // a segment never starts beyond a wall (events put the ball on it); the closed form's
    // y(0) may be a few ulp past it, which would hide a return to that wall
    ev_a[EV_PLUS] = pymin(ev_a[EV_PLUS], 0.0);
    ev_a[EV_MINUS] = pymin(ev_a[EV_MINUS], 0.0);
    // nor past h = 0 (an event put it there; the re-evaluated h may be a few ulp off)
    ev_a[EV_CUT] = pymin(ev_a[EV_CUT], 0.0);
    for (idx c = 0; c < 6; ++c) w.qsum[c] = 0.0;
    double auxa = 0.0;
    double auxda = 0.0;
    if (kase != L::SOLID) std::tie(auxa, auxda) = aux(Xa, a, seg, c, mk, w.x);
    double ydd_a = NAN;
    double wdd_a = NAN;
    double ydd_b = NAN;
    double wdd_b = NAN;
    if (ydd_on)
        std::tie(ydd_a, wdd_a) = ball_ydd(Xa, f0 * ph.imag(), seg, w.sys.ddc, n, c.mode,
                                          w.sys.q.roll.kroll);
    idx top = adapt ? w.levmax[r] : 0;
    LevelBounds lb(sv.b3y, sv.b3w, w.hl, top);
    GrazeMargin gm;
    while (true) {
        // the step: h, or 2^lv h where Taylor's theorem proves that it holds no event and
        // no new extremum of |y| or (steady) of W
        idx lev = 0;
        if (adapt) lev = level(ev_a, ydd_a, TipW{wa, wda, wdd_a}, lb, e, half, sv);
        double b = a + w.hl[lev];
        bool full = true;
        if (b >= tlen) {
            b = tlen;
            full = false;
        }
        istep += 1;
        bool usual = full && istep % 64 != 0 && !Regen;
        GridPoint gp = advance<Regen>(w, t, c, ydd_on, GridAt{b, lev, usual, whole && !full}, phg,
                                      ydd_b, wdd_b);
        phg = gp.phg;
        ydd_b = gp.ydd;
        wdd_b = gp.wdd;
        // --- events in [a, b]
        Found f = find_event<Regen>(w, c, sv, StepEnds{a, b, lev, ev_a, ev_b, ydd_a, ydd_b}, gm);
        idx kind = f.kind;
        if (kind >= 0) {
            b = f.t;
            // the closed form with the search's sizes
            const SegView s{seg, r, q0, w.cf, ks, w.qs, X, w.Xd, n, mk, f0, om};
            if (sz != 0 && seg.krb == 0.0) {  // kept for segment_integrals
                ph_next = state_at(s, b, w.qs, X, w.ex_end);
                w.tau_end = b;
                w.r_end = r;
            } else {
                ph_next = state_at(s, b, w.qs, X);
            }
            ev_kind = kind;
            tau_ev = b;
        }
        // --- outputs on (a, b]
        std::tie(wb, wdb) = psi_dot(mk, MK_PSI_L, X, n);
        if (steady) {
            w_extremes(w, e, c, sv, StepEnds{a, b, lev, ev_a, ev_b, ydd_a, ydd_b}, kind,
                       TipW{wa, wda, wdd_a}, TipW{wb, wdb, wdd_b});
        }
        if constexpr (Regen) {
            e.max_force = cut_flows(w, c, a, b, whole && kind < 0, steady, wb, e.max_force);
        }
        // aux and aux' at b
        double auxb = 0.0;
        double auxdb = 0.0;
        if (kase != L::SOLID) std::tie(auxb, auxdb) = aux(X, b, seg, c, mk, w.x);
        if (kind == EV_PLUS || kind == EV_MINUS) {
            auxb = kind == EV_PLUS ? half : -half;  // on the wall, up to round-off
        }
        e.max_aux_all = pymax(e.max_aux_all, std::fabs(auxb));
        if (steady) {
            e.max_aux = pymax(e.max_aux, std::fabs(auxb));
            if (Regen || !ball) {  // a ball's int y^2 is closed form (segment_integrals)
                double hh = b - a;
                met[L::SUM_AUX2] += (0.5 * hh * (auxa * auxa + auxb * auxb)
                                     + hh * hh / 6.0 * (auxa * auxda - auxb * auxdb));
            }
        }
        // history and strobe samples in (t + a, t + b]
        if (outputs) samples(w, out_view, c, t, b, t_end);
        if (kind >= 0 || !full) break;
        a = b;
        wa = wb;
        wda = wdb;
        ydd_a = ydd_b;
        wdd_a = wdd_b;
        auxa = auxb;
        auxda = auxdb;
        // b's event functions become a's: the two views swap instead of a copy (an entry
        // that this segment's evaluations do not write is never read in it, so the older
        // value left there serves as well as the copied one)
        std::swap(w.ev_a, w.ev_b);
        ev_a = w.ev_a;
        ev_b = w.ev_b;
    }
    w.ro.max_abs_w = e.max_abs_w;
    w.ro.max_w = e.max_w;
    w.ro.min_w = e.min_w;
    w.ro.max_aux = e.max_aux;
    w.ro.max_aux_all = e.max_aux_all;
    w.ro.max_force = e.max_force;
    return {ev_kind, tau_ev, ph_next, wb, wdb};
}

// What start_segment returns: the regime, its eigen-coordinates' step, the segment's end (at
// most t_stop), whether that is a cut's node, the last node reached, psi_d . u at t.
struct SegStart {
    idx r, ks;
    double t_seg_end;
    bool at_node;
    idx j_node;
    double pdu;
    bool spin_end;  // the segment ends where a stuck or walled ball's spin runs down
};

// A segment from t (forcing phasor ph there, at most to t_stop) in the run's state w.rs:
// its regime r, its eigen-coordinates into w.q0, its record into w.seg, its description
// into sv and, in a cut (history hs, constants cq, j_node the last node reached), its end
// and surface.
template <bool Regen>
inline SegStart start_segment(Work& w, double t, double t_stop, ncplx ph, History& hs,
                              idx j_node, const CutConsts& cq, SegSearch& sv) {
    Vec X = w.X;
    Vec dX = w.dX;
    CVec q0 = w.q0;
    Segment& seg = w.seg;
    const RunConsts& cp = w.cp;
    const System& sys = w.sys;
    const RunState& rs = w.rs;
    const idx n = sys.n;
    idx nz = q0.size();
    bool ball = sys.has_ball();
    double fc = sys.q.fric.fc;
    double m = sys.q.ball.m;
    Regime mode = rs.ball.mode;
    double sdir = rs.ball.sdir;
    bool incut = rs.incut;
    double t_seg_end = t_stop;
    bool steady = t >= cp.t_steady;
    idx r = 0;
    if (ball) r = mode;
    if (incut) r += sys.nreg;
    double fb = 0.0;
    if ((mode == FREE || mode == ROLL) && ball) fb = -fc * sdir;
    double kap = mode == STICK ? sys.carry.kstick : sys.carry.kwall;
    // a rolling ball: the floor's friction on it where it slips (beside F_b: the bar feels
    // both, reciprocally) or spins at rest (inside the held regime: only its release and
    // its spin feel it); rolling, the carrying force's kappa and offset are the roll's
    const dynamics::Rolling& rl = sys.q.roll;
    double ffl = 0.0;
    double foff = 0.0;
    if (rl.on && mode == FREE) {
        ffl = -rl.muk_n * rs.ball.slip;
        fb += ffl;
    } else if (rl.on && mode == ROLL) {
        kap = sys.carry.roll_kappa;
        foff = sys.carry.kwall * fb / sys.carry.roll_kappa;
    } else if (rl.on) {
        ffl = spin_friction(rl, rs.ball.spin);
        foff = ffl;
    }
    idx ks = w.kstep[r];
    for (idx j = 0; j < nz; ++j) {
        dX[j] = X[j] - ((ncplx(w.cf.Z(r, j)) * ph).imag() + fb * w.cf.D(r, j));
    }
    for (idx k = 0; k < nz; ++k) {
        ncplx s(0.0, 0.0);
        for (idx j = 0; j < nz; ++j) s += ncplx(w.Vi(r, k, j)) * dX[j];
        q0[k] = s;
    }
    bool at_node = false;
    bool whole = false;
    if constexpr (Regen) {
        CutSegment cs = cut_segment(t, t_stop, j_node, hs, seg, cq, rs);
        t_seg_end = cs.t_seg_end;
        at_node = cs.at_node;
        j_node = cs.j_node;
        seg.krb = incut ? cq.krb : 0.0;
        seg.cdir = incut ? 1.0 : -1.0;
        // a whole step H from node to node, inside one grid step: tabulated values
        whole = at_node && cs.from_node && cq.h <= cp.h;
    }
    auto [pdu, pdv] = psi_dot(sys.mk, MK_PSI_D, X, n);
    // bounds on |y^(4)|, |W^(4)| (steady, harmonic) and |y^(3)|, |W^(3)| (a free ball)
    bool ydd_on = ball && (mode == FREE || mode == ROLL) && !Regen;
    bool adapt = ydd_on && w.levmax[r] > 0;
    Bounds bd = bounds(w, r, cq.krb, BoundsWanted{ball, incut, steady && !Regen, adapt});
    seg.ts = t;
    seg.fb = fb;
    seg.rolls = rl.on;
    seg.cy = mode == ROLL ? sys.carry.roll_cy : 1.0;
    seg.ud0 = rs.ball.y + seg.cy * pdu;  // the ball's absolute position and velocity
    seg.vd0 = rs.ball.yd + seg.cy * pdv;  // (a rolling ball's: cy of the floor's)
    seg.y0 = rs.ball.y;
    seg.sdir = sdir;
    seg.wall = rs.ball.wall;
    seg.kappa = kap;
    seg.fs = mode == ROLL ? rl.mus_n : sys.carry.fs;
    seg.half = sys.q.ball.half;
    seg.m = m > 0.0 ? m : 1.0;
    seg.acc = seg.cy * fb / seg.m;
    seg.ffl = ffl;
    seg.foff = foff;
    seg.slip = mode == FREE ? rs.ball.slip : 0.0;
    seg.s0 = rs.ball.spin;
    seg.sd = mode == ROLL ? 0.0 : -rl.kroll * ffl;
    // a spinning ball at rest: its spin runs down (to 0) at s0 / -sd, where the segment ends
    bool spin_end = false;
    if (rl.on && (mode == STICK || mode == CONTACT) && seg.sd != 0.0) {
        double t_down = t - seg.s0 / seg.sd;
        if (t_down < t_seg_end) {
            t_seg_end = t_down;
            spin_end = true;
        }
    }
    // which events are watched
    bool watch_wall = ball && (mode == FREE || mode == ROLL);
    bool watch_v = watch_wall && fc > 0.0 && sdir != 0.0;
    bool watch_ext = watch_wall && !watch_v;
    sv.tlen = t_seg_end - t;
    sv.b4 = bd.b4;
    sv.bw4 = bd.bw4;
    sv.b3y = bd.b3y;
    sv.b3w = bd.b3w;
    sv.steady = steady;
    sv.whole = whole;
    sv.adapt = adapt;
    sv.ydd = ydd_on;
    sv.watch_v = watch_v;
    sv.watch_ext = watch_ext;
    // (without the floor's friction, mu_s = mu_k = 0, a slip's end changes nothing)
    sv.watch_slip = rl.on && mode == FREE && seg.slip != 0.0 && (rl.mus_n > 0.0 || rl.muk_n > 0.0);
    sv.slip = seg.slip;
    sv.sd = seg.sd;
    sv.ydd_max = mode == ROLL ? rl.kroll * rl.mus_n : -1.0;
    return {r, ks, t_seg_end, at_node, j_node, pdu, spin_end};
}

// The flows of the segment [t, t + T] (context c, forcing phasor ph at t; a cut's from
// w.qsum, else closed form) into the metrics, a cut's steps with h = 0 counted, a free ball
// moved to t + T (pdu: psi_d . u at t).  Returns the last step of length dt_out counted
// with h = 0 (last_zero_step: the last one so far).
template <bool Regen>
inline idx close_segment(Work& w, SegCtx c, double t, double T, ncplx ph, bool steady,
                         double pdu, idx last_zero_step) {
    const Segment& seg = w.seg;
    const RunConsts& cp = w.cp;
    const System& sys = w.sys;
    const idx r = c.r, mode = c.mode;
    Vec out = w.out;
    Vec met = w.met;
    bool ball = c.ball;
    if constexpr (Regen) {
        for (idx k = 0; k < 6; ++k) out[k] = w.qsum[k];
        if (!w.rs.incut) {  // the steps of length dt_out touched with h = 0
            double t0 = cp.t0;
            double dt_out = cp.dt_out;
            idx js = std::max(idx(std::floor((t - t0) / dt_out)), last_zero_step + 1);
            idx je = idx(std::ceil((t + T - t0) / dt_out)) - 1;
            if (je >= js) {
                met[L::N_ZERO_STEPS] += double(je - js + 1);
                last_zero_step = je;
            }
        }
    } else {
        double kst = (ball && mode == STICK) ? sys.carry.kstick : 0.0;
        // what to integrate: 0 the energy flows, 1 also the steady W sums, 2 also a free
        // ball's y^2
        const bool moves = mode == FREE || mode == ROLL;
        idx lvl = steady ? ((ball && moves) ? 2 : 1) : 0;
        // the search's exp(lambda_k T), if its last state_at was at T (same regime and
        // segment: tau_end is reset at each search's start)
        const ncplx* exc =
            (w.r_end == r && w.tau_end == T && seg.krb == 0.0) ? w.ex_end : nullptr;
        const FlowSources src{w.Vfull, w.cf.Z, w.cf.D, w.isum, sys.mk, w.dp};
        const FlowsIn in{seg,          r,           w.q0, ph,  T,   w.cf.lam,
                         src,          w.flows.of(r, src, c.n, c.ks),
                         sys.q.force.f0, sys.q.force.om, kst,  sys.q.fric.sr, lvl, exc};
        if (c.sz == 1) {
            segment_integrals_1(in, w.isc.phj, out);
        } else if (c.sz == 2) {
            segment_integrals_2(in, w.isc.phj, out);
        } else {
            segment_integrals(in, c.n, c.ks, w.isc, out);
        }
        if (ball && steady) {
            // the ball's int y^2: closed form when free, y constant otherwise
            met[L::SUM_AUX2] += moves ? out[6] : seg.y0 * seg.y0 * T;
        }
    }
    close_flows(w, c, T, steady, pdu);
    return last_zero_step;
}

}  // namespace kernel

using kernel::close_segment;
using kernel::search_segment;
using kernel::SegEvent;
using kernel::SegStart;
using kernel::start_segment;

}  // namespace bb::exact
