// The exact kernel's driver: see driver.hpp.
//
// The kernel is compiled once, for the baseline ISA (SSE2 on x86-64).  A second copy for
// AVX2, picked at run time for harmonic runs, gave 1.09x on an event-heavy harmonic run
// (benchmarks/bench_isa.py) for 13 s more compile in every build from source; the exact
// integrator's runs take fractions of a second, so it did not pay for its build.
#include "driver.hpp"

#include <cmath>
#include <tuple>
#include <vector>

#include "../dynamics.hpp"
#include "../model.hpp"
#include "consts.hpp"
#include "cut.hpp"
#include "nmath.hpp"
#include "propagate.hpp"
#include "segment.hpp"

namespace bb::exact {

namespace {

namespace L = layout;

// The system from p into sys (whose rows mk and ddc are views of the work arrays, zeroed):
// the system as every integrator unpacks it (dynamics::unpack), the bar's rows mk (M, K,
// C, psi_L, psi_d, psi_a and the equations of motion's constants), a free ball's y'' and
// W'' coefficients ddc and the ball's carrying; nreg: the regimes outside a cut.
void unpack_system(Vec p, idx nreg, System& sys) {
    const idx n = sys.n;
    const Mat mk = sys.mk, ddc = sys.ddc;
    sys.q = dynamics::unpack(p.d, 0.0);
    const dynamics::Params& q = sys.q;
    const dynamics::Modes& md = q.modes;
    sys.kase = layout::Case(q.kase);
    sys.nreg = nreg;
    for (idx i = 0; i < n; ++i) {
        mk(MK_M, i) = p[L::M_ + i];
        mk(MK_K, i) = p[L::K_ + i];
        mk(MK_C, i) = p[L::C_ + i];
        mk(MK_PSI_L, i) = p[L::PSI_L + i];
        mk(MK_PSI_D, i) = p[L::PSI_D + i];
        mk(MK_PSI_A, i) = p[L::PSI_A + i];
        mk(MK_FM, i) = md.fm[i];
        mk(MK_KM, i) = md.km[i];
        mk(MK_CM, i) = md.cm[i];
        mk(MK_INV_M, i) = md.invM[i];
        mk(MK_PSI_F, i) = p[L::PSI_F + i];
    }
    // psi . u'' of a free ball's bar from its state, force f and F_b: rows 0 (psi_d) and 1
    // (psi_L) hold the coefficients of u_i, then of f and F_b; rows 2 and 3 those of u_i'
    for (idx i = 0; i < n; ++i) {
        // a_i per unit of u_i, u_i', f (dynamics.hpp) and of F_b (the reaction on the bar)
        auto a = [&](double f, double u, double v) {
            return dynamics::free_acceleration(md.fm[i], md.km[i], md.cm[i], f, u, v);
        };
        for (idx row = 0; row < 2; ++row) {
            const double psi = mk(row == 0 ? MK_PSI_D : MK_PSI_L, i);
            ddc(row, i) = psi * a(0.0, 1.0, 0.0);
            ddc(row + 2, i) = psi * a(0.0, 0.0, 1.0);
            ddc(row, n) += psi * a(1.0, 0.0, 0.0);
            ddc(row, n + 1) -= psi * md.dm[i];
        }
    }
    const double m = q.ball.m;
    Carrying& cr = sys.carry;
    cr.fs = pymax(q.fric.fs, q.fric.fc);
    cr.kstick = m > 0.0 ? q.fric.kappa : 1.0;
    cr.kwall = m > 0.0 ? q.kappa1 : 1.0;
    if (q.roll.on) {
        cr.roll_cy = m * q.roll.kroll / (m * q.roll.kroll + 1.0);
        cr.roll_kappa = cr.kwall + q.roll.kroll;
    }
}

// The run's span and outputs from its arguments.
RunConsts run_consts(const ExactRun& a) {
    RunConsts cp;
    cp.t0 = a.t0;
    cp.t_steady = a.t_steady;
    cp.dt_out = a.dt_out;
    cp.stop_at_zero = a.p[L::STOP_AT_ZERO] > 0.0;
    cp.h = a.h;
    cp.rec_dt = a.rec_dt;
    cp.tstrobe = a.p[L::STROBE_PERIOD];
    return cp;
}

// A regenerative cut's constants cq from p, the run's span and the history step H.
CutConsts cut_consts(Vec p, double t0, double t_end, double hist_step, bool regen) {
    CutConsts cq;
    double tau_d = p[L::TAU];
    cq.t0 = t0;
    cq.h = hist_step;
    cq.ttol = pymax(1e-9 * hist_step, 4.0 * 2.2e-16 * (std::fabs(t0) + std::fabs(t_end)));
    cq.nrev = regen ? idx(p[L::N_REV]) : 0;
    cq.tau = tau_d;
    cq.feed = p[L::FEED];
    cq.w0 = p[L::HIST_W0];
    // nodes a revolution: tau / H to the nearest whole number, ties to even (nearbyint in the
    // default rounding mode)
    cq.mrev = regen ? idx(std::nearbyint(tau_d / hist_step)) : 1;
    cq.cubic = p[L::INTERP] > 0.0;
    cq.krb = p[L::KR_B];
    return cq;
}

// The first knot of a cut (constants cq), at its start, from the state X (mk: the bar's
// rows), and whether the tool starts in it (into rs); returns the largest cutting force so
// far.
double cut_start(History& hs, Vec X, Mat mk, const CutConsts& cq, RunState& rs,
                 double max_force) {
    const idx n = mk.n1;
    const double t0 = cq.t0, krb = cq.krb, feed = cq.feed, w_before = cq.w0;
    Knots& kn = hs.kn;
    const auto [w_, wd_] = psi_dot(mk, MK_PSI_L, X, n);
    kn(0, 0) = t0;
    kn(0, 1) = w_;
    kn(0, 2) = wd_;
    kn(0, 3) = wd_;
    kn(0, 4) = 0.0;
    hs.nk = 1;
    bool incut = feed + w_before - w_ > 0.0;
    rs.incut = incut;
    if (!incut && rs.first_zero < 0.0) rs.first_zero = t0;
    return pymax(max_force, krb * pymax(0.0, feed + w_before - w_));
}

// The knot of the node j_node + 1, reached at t without an event (W, W' there: wb, wdb;
// the state X), into hs.
void node_knot(History& hs, double t, double wb, double wdb, Vec X, Mat mk, double ttol,
               idx j_node) {
    Knots& kn = hs.kn;
    const idx nk = hs.nk;
    if (nk < kn.n0 && t > kn(nk - 1, 0) + ttol) {  // add_knot's usual case, written out
        kn(nk, 0) = t;
        kn(nk, 1) = wb;
        kn(nk, 2) = wdb;
        kn(nk, 3) = wdb;
        kn(nk, 4) = double(j_node + 1);
        hs.nk = nk + 1;
        return;
    }
    add_knot(hs, t, X, X, mk, ttol, double(j_node + 1));
}

// --- a rolling ball's regimes (docs/model.md, 2.7) -----------------------------------------

// A rolling ball at zero slip (y' = s) moving in direction d: it rolls (ROLL) if the floor's
// friction rolling needs, F = (sum psi_d a_free - kappa1 F_b) / (kappa1 + kroll), stays
// within mu_s N, else it slips the way that need pulls (F = mu_k N sgn(F_need)).
void roll_or_slip(Vec X, double f, double d, const System& sys, BallState& b) {
    const double fb = -sys.q.fric.fc * d;
    const double need = freq_rhs(X, f, sys.n, sys.mk, sys.carry.roll_kappa) -
                        sys.carry.kwall * fb / sys.carry.roll_kappa;
    b.sdir = d;
    b.spin = b.yd;
    if (std::fabs(need) <= sys.q.roll.mus_n) {
        b.mode = ROLL;
        b.slip = 0.0;
    } else {
        b.mode = FREE;
        b.slip = need > 0.0 ? -1.0 : 1.0;
    }
}

// A rolling ball leaving rest (y' = 0) in direction d: from zero slip if it does not spin,
// else slipping against its spin.
void leave_rest(Vec X, double f, double d, const System& sys, BallState& b) {
    b.yd = 0.0;
    if (b.spin == 0.0) {
        roll_or_slip(X, f, d, sys, b);
        return;
    }
    b.mode = FREE;
    b.sdir = sys.q.fric.fc > 0.0 ? d : 0.0;
    b.slip = b.spin > 0.0 ? -1.0 : 1.0;
}

// A rolling ball at rest on the bore: held (STICK) while the friction that carries it with
// the bar, less the floor's on its spin, stays within F_s (with rolling resistance, as a
// sliding ball is held), else moving off the way the bar leaves it.
void roll_at_rest(Vec X, double f, const System& sys, BallState& b) {
    b.yd = 0.0;
    const double F = freq_rhs(X, f, sys.n, sys.mk, sys.carry.kstick) -
                     spin_friction(sys.q.roll, b.spin);
    if (sys.q.fric.fc > 0.0 && std::fabs(F) <= sys.carry.fs) {
        b.mode = STICK;
        b.sdir = 0.0;
        b.slip = 0.0;
        return;
    }
    leave_rest(X, f, F > 0.0 ? -1.0 : (F < 0.0 ? 1.0 : 0.0), sys, b);
}

// A rolling ball at rest on wall w_: held there (CONTACT) while the carrying force less the
// floor's friction on its spin pushes it into the wall (within F_s), else leaving inward.
void roll_at_wall(Vec X, double f, double w_, const System& sys, BallState& b) {
    b.yd = 0.0;
    b.wall = w_;
    const double F = freq_rhs(X, f, sys.n, sys.mk, sys.carry.kwall) -
                     spin_friction(sys.q.roll, b.spin);
    if (w_ * F <= sys.carry.fs) {
        b.mode = CONTACT;
        b.sdir = 0.0;
        b.slip = 0.0;
        return;
    }
    leave_rest(X, f, -w_, sys, b);
}

// A rolling ball moving at y' (not 0) with its spin: rolling or slipping from zero slip
// where they agree, else slipping.
void roll_moving(Vec X, double f, const System& sys, BallState& b) {
    const double d = b.yd > 0.0 ? 1.0 : -1.0;
    if (b.yd == b.spin) {
        roll_or_slip(X, f, d, sys, b);
        return;
    }
    b.mode = FREE;
    b.sdir = d;
    b.slip = b.yd > b.spin ? 1.0 : -1.0;
}

// A ball's regime at the start (into b), from its y, y' and the tip force f_t0.
void initial_regime(Vec X, double f_t0, const System& sys, BallState& b) {
    const idx n = sys.n;
    const Mat mk = sys.mk;
    double half = sys.q.ball.half;
    double fc = sys.q.fric.fc;
    double fs = sys.carry.fs;
    double y = b.y;
    double yd = b.yd;
    if (sys.q.roll.on) {
        if (yd != 0.0) {
            roll_moving(X, f_t0, sys, b);
        } else if (std::fabs(y) >= half) {
            b.y = (y > 0.0 ? 1.0 : -1.0) * half;
            roll_at_wall(X, f_t0, y > 0.0 ? 1.0 : -1.0, sys, b);
        } else {
            roll_at_rest(X, f_t0, sys, b);
        }
        return;
    }
    Regime mode = FREE;
    double sdir = 0.0;
    double wall = 0.0;
    if (yd != 0.0) {
        sdir = yd > 0.0 ? 1.0 : -1.0;
    } else if (std::fabs(y) >= half) {
        wall = y > 0.0 ? 1.0 : -1.0;
        y = wall * half;
        double F = freq_rhs(X, f_t0, n, mk, sys.carry.kwall);
        if (wall * F <= fs) {
            mode = CONTACT;
        } else if (fc > 0.0) {
            sdir = -wall;
        }
    } else if (fc > 0.0) {
        double F = freq_rhs(X, f_t0, n, mk, sys.carry.kstick);
        if (std::fabs(F) <= fs) {
            mode = STICK;
        } else {
            sdir = F > 0.0 ? -1.0 : 1.0;
        }
    }
    b.mode = mode;
    b.sdir = sdir;
    b.wall = wall;
    b.y = y;
}

// Regime of a ball at rest on wall w_ under the tip force f (the bar's state X): held
// (CONTACT) or leaving inward (FREE), into b.
void at_wall(Vec X, double f, double w_, const System& sys, BallState& b) {
    double F = freq_rhs(X, f, sys.n, sys.mk, sys.carry.kwall);
    b.wall = w_;
    if (w_ * F <= sys.carry.fs) {
        b.mode = CONTACT;
        b.sdir = 0.0;
    } else {
        b.mode = FREE;
        b.sdir = sys.q.fric.fc > 0.0 ? -w_ : 0.0;
    }
}

// An impact or a capture of the ball b on wall w_ (EV_PLUS / EV_MINUS) at t under the tip
// force f_ev: X' jumps, the counts into log (steady: t in the steady part).
void wall_hit(double w_, double t, bool steady, Vec X, double f_ev, const System& sys,
              const EventLog& log, BallState& b) {
    const idx n = sys.n;
    const Mat mk = sys.mk;
    const Ball& ball = sys.q.ball;
    double* met = log.met;
    b.y = w_ * ball.half;
    double vb = b.yd;
    double& yd = b.yd;
    if (w_ * vb > 0.0) {
        double ee = std::fabs(vb) > ball.vimp ? ball.e : 0.0;  // Zeno: captured on the wall
        ImpactJump j = impact_law(vb, ee, ball.meff);
        yd = j.yd;
        dynamics::jump_modes(int(n), mk.row(MK_PSI_D), mk.row(MK_INV_M), X.d, j.g);
        met[L::D_IMPACT] += j.loss;
        if (std::fabs(vb) > ball.vimp) {
            count_impact(met, log.imp, t, w_, vb, steady);
        } else {
            met[L::N_MICRO] += 1;
        }
    } else if (w_ * vb < -ball.vimp) {
        // moving inward, faster than a capture: not a wall contact but the round-off of a
        // segment a few ulp long just after an impact; the ball goes on, from the wall
        yd = vb;
    } else {
        yd = 0.0;
    }
    if (sys.q.roll.on) {  // the impact leaves the spin as it was
        if (yd != 0.0) {
            roll_moving(X, f_ev, sys, b);
        } else {
            roll_at_wall(X, f_ev, w_, sys, b);
        }
    } else if (yd != 0.0) {
        b.mode = FREE;
        b.sdir = yd > 0.0 ? 1.0 : -1.0;
    } else {
        at_wall(X, f_ev, w_, sys, b);
    }
}

// A rolling ball's event ev_kind at t under the tip force f_ev (not a wall's, not the cut's)
// into b: its slip run out, its y' at zero, the friction rolling needs beyond mu_s N, its
// release from the bore or a wall, its spin run down.
void roll_event(idx ev_kind, Vec X, double f_ev, const System& sys, BallState& b) {
    if (ev_kind == EV_SLIP) {
        b.spin = b.yd;
        if (b.yd != 0.0) {
            roll_or_slip(X, f_ev, b.yd > 0.0 ? 1.0 : -1.0, sys, b);
        } else {
            roll_at_rest(X, f_ev, sys, b);
        }
    } else if (ev_kind == EV_VSTOP) {
        if (b.mode == ROLL) b.spin = 0.0;  // rolling, s = y'
        roll_at_rest(X, f_ev, sys, b);
    } else if (b.mode == ROLL && (ev_kind == EV_REL_NEG || ev_kind == EV_REL_POS)) {
        // the friction rolling needs passes mu_s N (EV_REL_NEG: upwards): it slips
        b.spin = b.yd;
        b.mode = FREE;
        b.slip = ev_kind == EV_REL_NEG ? -1.0 : 1.0;
    } else if (ev_kind == EV_REL_NEG || ev_kind == EV_REL_POS) {
        leave_rest(X, f_ev, ev_kind == EV_REL_NEG ? -1.0 : 1.0, sys, b);
    } else if (ev_kind == EV_WALL_REL) {
        b.y = b.wall * sys.q.ball.half;
        leave_rest(X, f_ev, -b.wall, sys, b);
    } else if (ev_kind == EV_SPIN0) {
        b.spin = 0.0;
        if (b.mode == CONTACT) {
            roll_at_wall(X, f_ev, b.wall, sys, b);
        } else {
            roll_at_rest(X, f_ev, sys, b);
        }
    }
}

// The event ev_kind at t under the tip force f_ev (the bar's state X): an impact, a
// capture, a stick, a slip or a release of the ball, or the tool leaving or re-entering the
// cut, into the run's state rs; its counts and the stick interval it closes into log.
void apply_event(idx ev_kind, double t, double f_ev, Vec X, const System& sys,
                 const RunConsts& cp, RunState& rs, const EventLog& log) {
    const bool steady = t >= cp.t_steady;
    BallState b = rs.ball;
    Regime& mode = b.mode;
    double& sdir = b.sdir;
    double& wall = b.wall;
    double& y = b.y;
    double& yd = b.yd;
    double fc = sys.q.fric.fc;
    bool was_stick = mode == STICK;
    if (ev_kind == EV_PLUS || ev_kind == EV_MINUS) {
        double w_ = ev_kind == EV_PLUS ? 1.0 : -1.0;
        wall_hit(w_, t, steady, X, f_ev, sys, log, b);
    } else if (sys.q.roll.on && ev_kind != EV_CUT) {
        roll_event(ev_kind, X, f_ev, sys, b);
    } else if (ev_kind == EV_VSTOP) {
        yd = 0.0;
        double F = freq_rhs(X, f_ev, sys.n, sys.mk, sys.carry.kstick);
        if (std::fabs(F) <= sys.carry.fs) {
            mode = STICK;
            sdir = 0.0;
        } else {
            mode = FREE;
            sdir = F > 0.0 ? -1.0 : 1.0;
        }
    } else if (ev_kind == EV_REL_NEG || ev_kind == EV_REL_POS) {
        mode = FREE;
        yd = 0.0;
        sdir = ev_kind == EV_REL_NEG ? -1.0 : 1.0;
    } else if (ev_kind == EV_WALL_REL) {
        mode = FREE;
        yd = 0.0;
        sdir = fc > 0.0 ? -wall : 0.0;
        y = wall * sys.q.ball.half;
    } else if (ev_kind == EV_CUT) {
        bool incut = !rs.incut;
        rs.incut = incut;
        if (!incut && rs.first_zero < 0.0) {
            rs.first_zero = t;  // the chatter verdict (docs/model.md, section 4)
            if (cp.stop_at_zero) {  // finish the step of length dt_out, as RK4 does
                double t0 = cp.t0;
                double dt_out = cp.dt_out;
                double k = double(idx(std::ceil((t - t0) / dt_out - 1e-9)));
                rs.t_end = pymin(rs.t_end, t0 + k * dt_out);
            }
        }
    }
    if (mode == FREE && fc == 0.0 && yd == 0.0 && !sys.q.roll.on) sdir = 0.0;
    // stick intervals
    if (mode == STICK && !was_stick) {
        rs.stick_t0 = t;
    } else if (was_stick && mode != STICK) {
        close_stick(log.met, log.stick, rs.stick_t0, t, log.t_steady, sys.q.fric.stick_min);
    }
    rs.ball = b;
}

// The running extremes from met and the first output times into ro.
void outputs_start(RunningOut& ro, Vec met, Vec p, double t0, double max_force) {
    double tstrobe = p[L::STROBE_PERIOD];
    ro.max_abs_w = met[L::MAX_ABS_W];
    ro.max_w = met[L::STEADY_MAX_W];
    ro.min_w = met[L::STEADY_MIN_W];
    ro.max_aux = met[L::MAX_ABS_AUX];
    ro.max_aux_all = met[L::MAX_ABS_AUX_ALL];
    ro.max_force = max_force;
    ro.k_rec = 1.0;  // the next history row is at t0 + k_rec rec_dt
    if (tstrobe > 0.0) {
        double t_next_strobe = p[L::STROBE_T0];
        if (t_next_strobe <= t0) {
            // math.floor gives an int: the sum is an integer's, then a float's product
            idx k = idx(std::floor((t0 - t_next_strobe) / tstrobe)) + 1;
            t_next_strobe += double(k) * tstrobe;
        }
        ro.t_strobe = t_next_strobe;
    }
}

// The final state into x and the running outputs into met.
void finish_run(const Work& w, bool regen, idx n_ev, int status) {
    Vec x = w.x;
    Vec met = w.met;
    const idx n = w.sys.n;
    for (idx j = 0; j < w.X.size(); ++j) x[j] = w.X[j];
    if (w.sys.has_ball()) {
        x[2 * n] = w.rs.ball.y;
        x[2 * n + 1] = w.rs.ball.yd;
        if (w.sys.q.roll.on) x[2 * n + 2] = w.rs.ball.spin;
    }
    met[L::MAX_ABS_W] = w.ro.max_abs_w;
    met[L::STEADY_MAX_W] = w.ro.max_w;
    met[L::STEADY_MIN_W] = w.ro.min_w;
    met[L::MAX_ABS_AUX] = w.ro.max_aux;
    met[L::MAX_ABS_AUX_ALL] = w.ro.max_aux_all;
    met[L::N_EVENTS] = double(n_ev);
    met[L::EXACT_STATUS] = status;
    if (regen) {
        met[L::FIRST_ZERO_T] = w.rs.first_zero;
        met[L::MAX_FORCE] = w.ro.max_force;
    }
}

// The views of the run's inputs and outputs in the work arrays.
void attach(Work& w, const ExactRun& a) {
    w.cf = {a.lam, a.V, a.Z, a.D, a.bq};
    w.Vi = a.Vi;
    w.Vfull = a.Vfull;
    w.dp = {a.lvis, a.cvis};
    w.isum = a.isum;
    w.kstep = a.kstep;
    w.bnd = a.bnd;
    w.levmax = a.levmax;
    w.eh = a.eh;
    w.tabE = a.tabE;
    w.tabP = a.tabP;
    w.x = a.x;
    w.rec = a.rec;
    w.strobe = a.strobe;
    w.met = a.met;
}

// The body of both exact kernels: Regen (a cut) is a constant of each.
template <bool Regen>
double exact_body(const ExactRun& a) {
    Vec p = a.p;
    Vec x = a.x;
    Vec met = a.met;
    double t0 = a.t0;
    double t_end = a.t_end;
    double t_steady = a.t_steady;
    double h = a.h;
    idx n = idx(p[L::N_MODES]);
    idx nz = a.lam.n1;
    Work w(n, nz);
    attach(w, a);
    System& sys = w.sys;
    unpack_system(p, a.nreg, sys);
    if constexpr (!Regen) w.flows.reset(a.nreg, nz);  // a cut sums its flows by quadrature
    w.cp = run_consts(a);
    const layout::Case kase = sys.kase;
    const bool ball = sys.has_ball();
    Mat mk = sys.mk;
    double f0 = sys.q.force.f0;
    double om = sys.q.force.om;
    const EventLog log{met.d, a.imp, a.stick, t_steady};
    Vec X = w.X;
    for (idx j = 0; j < nz; ++j) X[j] = x[j];

    // --- regenerative cut (docs/model.md, section 4): the history of W as knots ----------
    // Knots (t, W, W'-, W'+) at the nodes t0 + j H and at every event; ip[k]: the knot at
    // or before t - k tau (-1: before the cut, where W = HIST_W0).
    CutConsts cq = cut_consts(p, t0, t_end, a.hist_step, Regen);
    double krb = cq.krb;
    double feed = cq.feed;
    double w_before = cq.w0;
    idx nrev = cq.nrev;
    double ttol = cq.ttol;
    History hs(Regen ? nrev * cq.mrev + 64 : 1, nrev);  // the knots grow in add_knot
    RunState& rs = w.rs;
    rs.first_zero = met[L::FIRST_ZERO_T];
    rs.t_end = t_end;
    double max_force = met[L::MAX_FORCE];
    idx last_zero_step = -1;
    idx j_node = 0;  // the last node reached
    if constexpr (Regen) max_force = cut_start(hs, X, mk, cq, rs, max_force);
    double f_t0 = f0 * std::sin(om * t0);
    if (rs.incut) f_t0 += krb * (feed + w_before - hs.kn(0, 1));
    rs.ball.y = (ball || kase == L::LOCKED) ? x[2 * n] : 0.0;
    rs.ball.yd = ball ? x[2 * n + 1] : 0.0;
    rs.ball.spin = sys.q.roll.on ? x[2 * n + 2] : 0.0;

    // the running extremes and output times (the other metrics add up in met itself)
    outputs_start(w.ro, met, p, t0, max_force);
    idx n_ev = idx(met[L::N_EVENTS]);
    int status = 0;

    // --- the initial regime
    if (ball) initial_regime(X, f_t0, sys, rs.ball);
    rs.stick_t0 = t0;
    int n_zero = 0;

    // the grid's step lengths (h, 2 h, 4 h, ...) and their phase steps
    for (int lv = 0; lv < GRID_LEVELS; ++lv) {
        w.hl[lv] = h * ipow(2.0, lv);
        w.rotl[lv] = om != 0.0 ? kernel::phasor(om, w.hl[lv]) : ncplx(1.0, 0.0);
    }
    SegSearch sv;
    ncplx ph_next(1.0, 0.0);
    bool ph_next_ok = false;
    double t = t0;
    while (t < t_end) {
        if (n_ev >= MAX_EVENTS) {
            status = 1;
            break;
        }
        // eigen-coordinates of the homogeneous part at t
        ncplx ph = ph_next_ok ? ph_next  // exp(i Omega t), from the event's evaluation
                              : (om != 0.0 ? kernel::phasor(om, t) : ncplx(1.0, 0.0));
        ph_next_ok = false;
        double t_stop = t < t_steady ? pymin(t_steady, t_end) : t_end;
        SegStart st = start_segment<Regen>(w, t, t_stop, ph, hs, j_node, cq, sv);
        j_node = st.j_node;
        bool steady = t >= t_steady;
        idx sz = const_sizes(st.ks, n, nz);
        const SegCtx c{st.r, st.ks, sz, n, kase, rs.ball.mode, ball};
        SegEvent ev;
        if (!Regen && sz == 1) {  // the constant sizes of one and two modes
            ev = search_segment<false, 2>(w, t, c, ph, sv);
        } else if (!Regen && sz == 2) {
            ev = search_segment<false, 4>(w, t, c, ph, sv);
        } else {
            ev = search_segment<Regen>(w, t, c, ph, sv);
        }
        ph_next = ev.ph_next;

        // --- close the segment [t, t + T]
        double T = ev.tau;
        last_zero_step = close_segment<Regen>(w, c, t, T, ph, steady, st.pdu, last_zero_step);
        double t_new = ev.kind >= 0 ? t + T : st.t_seg_end;
        if (ev.kind < 0 && st.spin_end) ev.kind = EV_SPIN0;  // the spin ran down at its end
        if (ev.kind < 0) {
            t = t_new;
            if constexpr (Regen) {
                if (st.at_node) node_knot(hs, t, ev.wb, ev.wdb, X, mk, ttol, j_node);
            }
            continue;
        }
        n_ev += 1;
        // the next segment starts at t + T = seg.ts + T, where the event's evaluation was
        ph_next_ok = om != 0.0 && ev.kind != EV_SPIN0;  // (EV_SPIN0: no evaluation there)
        double f_ev = cut_force(w.seg, T, X, n, mk, f0, om);  // the tip force at the event
        if (T <= 1e-14 * (std::fabs(t) + h)) {  // no progress: a few ulp of t
            n_zero += 1;
            if (n_zero > MAX_ZERO_LENGTH) {
                status = 2;
                t = t_new;
                break;
            }
        } else {
            n_zero = 0;
        }
        t = t_new;
        for (idx j = 0; j < nz; ++j) w.Xa[j] = X[j];  // before the event (W'- of a knot)
        // --- apply the event
        apply_event(ev.kind, t, f_ev, X, sys, w.cp, rs, log);
        t_end = rs.t_end;
        if constexpr (Regen) add_knot(hs, t, w.Xa, X, mk, ttol, -1.0);
    }
    if (rs.ball.mode == STICK) {
        close_stick(met.d, a.stick, rs.stick_t0, t, w.cp.t_steady, sys.q.fric.stick_min);
    }
    finish_run(w, Regen, n_ev, status);
    return t;
}

}  // namespace

double run_exact(const ExactRun& a) {
    const bool regen = int(a.p[L::FORCING]) == L::REGENERATIVE;
    if (regen) return exact_body<true>(a);
    return exact_body<false>(a);
}

}  // namespace bb::exact
