// The equations of motion, written once: the bar's modes with the ball (sliding, held by
// friction or carried on a wall), the tuned absorber or the locked ball, under a force
// at the tip (docs/model.md, section 2).  derivative_with() is the stage derivative that
// RK4 steps with (rk4.hpp); the step's affine map (linmap.hpp) pushes basis vectors
// through it, and the regime matrices that shooting and the exact integrator take
// (dynamics.cpp) are its columns at unit vectors: between impacts, with the friction
// force held, the equations are linear in the state.
//
// The state is X = [u_1..u_n, u_1'..u_n', aux, aux'], aux the ball's relative
// displacement y (BALL, LOCKED) or the absorber's displacement x_a (TMD).
#pragma once

#include <cmath>

#include "compiler.hpp"
#include "layout.hpp"
#include "model.hpp"

#ifndef BB_INLINE
#define BB_INLINE BB_ALWAYS_INLINE
#endif

namespace bb::dynamics {

namespace L = layout;

constexpr int NX_MAX = 2 * L::NMAX + 2;  // state length 2n + 2 (a rolling ball's: 2n + 3)

// Mode i's acceleration under the tip force f alone, without the damper's force, from the
// premultiplied constants fm = psi_F,i / M_i, km = K_i / M_i, cm = C_i / M_i (Modes):
// a_i = psi_F,i f / M_i - K_i u_i / M_i - C_i u_i' / M_i.  T is real for a state, complex
// for the exact integrator's modal coefficients.
template <class T>
BB_INLINE T free_acceleration(double fm, double km, double cm, T f, T u, T v) {
    return (fm * f - km * u) - cm * v;
}

// The modes' velocity jumps when an impulse g (N s) acts on the ball's bore:
// u_i' += g psi_d,i / M_i (invM = 1 / M_i).
BB_INLINE void jump_modes(int n, const double* pD, const double* invM, double* X, double g) {
    for (int i = 0; i < n; ++i) X[n + i] += g * pD[i] * invM[i];
}

// The bar's retained modes (docs/model.md, 2): modal damping C_i, 1 / M_i and the mode
// shapes at the tip (psi_L), the damper (psi_d), the absorber (psi_a) and where the force
// acts (psi_F), with the premultiplied constants of the stage derivative:
// a_i = fm f - km u - cm v (- dm F_b for the ball, - lm sum psi_d a for the locked ball).
struct Modes {
    int n = 0;
    double C[L::NMAX], pL[L::NMAX], pD[L::NMAX], pA[L::NMAX], pF[L::NMAX], invM[L::NMAX];
    double fm[L::NMAX], km[L::NMAX], cm[L::NMAX], dm[L::NMAX], lm[L::NMAX];
};

// The force at the tip: F0 sin(Omega t), or a regenerative cut's (regen, rk4_run.hpp).
struct Forcing {
    bool regen = false;
    double f0, om;
    double chh, shh;  // cos, sin of Omega dt / 2: the forcing phase's half-step rotation
};

// Coulomb friction of the ball on the bore, F_b = -F_c sgn(y'), its reaction on the bar
// (the share sr), the stick law that may hold the ball, and the stick bookkeeping.
struct Friction {
    double fc, sr;
    double kappa;  // 1/m + sum psi_d dm: y'' = kappa F_b - sum psi_d a_free
    // F_b, dm F_b and kappa F_b for y' > 0, y' = 0, y' < 0 (F_b = -F_c, 0, F_c)
    // (sign_pick): the products a stage forms, computed once, so that a stage picks one
    // instead of multiplying after its sign test
    double fb[3], dmfb[L::NMAX][3], kfb[3];
    // no kappa F_b is -0: y'' = kappa F_b - sum psi_d a_i then has the same bits whether
    // the sum starts from 0 or from its first term (they differ only in the sign of a zero)
    bool ydd_sum_from_first;
    // the stick law (hold): inside |y'| < band the ball is held while the force that
    // carries it with the bar is at most F_s; 0: the published F_b = -F_c sgn(y')
    bool hold = false;
    double band = 0.0, fs = 0.0, inv_kappa = 0.0;
    // the stick records' shortest interval, and |y'| below which the ball counts as stuck
    double stick_min, vstick;
};

// The tuned absorber: its mass, stiffness and damping on the bar at psi_a.
struct Absorber {
    double m, k, c;
};

// A compliant contact in place of the impact law (docs/model.md, 2.6): past a wall the
// ball and the bar press each other with Hertz's K d^1.5 (1 + chi d'), Hunt and
// Crossley's damping chi = alpha / v_in set per contact by the run from the speed it
// began with.
struct Contact {
    bool on = false;
    double k = 0.0, alpha = 0.0, chi = 0.0;
};

// A rolling ball (docs/model.md, 2.7): its spin s = r omega a state; it rolls while the
// floor's friction that keeps y' = s is at most mu_s N (and the slip is inside band), and
// slips with mu_k N beyond; kroll = r^2 / I = 5 / (2 m).
struct Rolling {
    bool on = false;
    double mus_n = 0.0, muk_n = 0.0, band = 0.0, kroll = 0.0;
    double inv_kappa = 0.0;  // 1 / (kappa1 + kroll): what rolling needs, by a product
};

// The Poincare strobe: its period (0: none) and a time it samples.
struct Strobe {
    double period, t0;
};

// The system a run integrates, unpacked from p once (unpack): the case, the modes, the
// ball and what acts on it, the absorber, the force at the tip and the strobe.
struct Params {
    int kase = 0;
    bool stage_loop = false;  // every RK4 step by the stages, no affine map (tests, benchmarks)
    Modes modes;
    Ball ball;  // the ball and its walls (model.hpp)
    // carried_kappa at the share 1: the kappa with which a compliant contact's force
    // (always reciprocal) and a rolling ball's floor friction move the ball on the bar
    double kappa1 = 0.0;
    Friction fric;
    Contact contact;
    Rolling roll;
    Absorber tmd;
    Forcing force;
    Strobe strobe;
};

// The modes' velocity jumps of an impact with impulse factor g (model.hpp's impact_law).
BB_INLINE void jump_modes(const Params& q, int n, double* X, double g) {
    jump_modes(n, q.modes.pD, q.modes.invM, X, g);
}

// kappa of a ball the bar carries with the share s of the reaction: the force that moves
// it with the bar per unit of relative acceleration, 1/m + s sum psi_d,i^2 / M_i
// (0 without a ball); Friction::kappa is the share sr's, Params::kappa1 the share 1's.
inline double carried_kappa(const Params& q, double s) {
    const Modes& md = q.modes;
    double kappa = q.ball.m > 0.0 ? 1.0 / q.ball.m : 0.0;
    for (int i = 0; i < md.n; ++i) kappa += md.pD[i] * (s * md.pD[i] * md.invM[i]);
    return kappa;
}

// The contact force on the ball along y (N) at a stage, and the power its damping
// dissipates (W): with the penetration d = |y| - delta/2 > 0 and its rate d',
// F = -sgn(y) max(0, K d^1.5 (1 + chi d')) (it pushes, never pulls); the dissipated
// power is (max(0, ...) - K d^1.5) d', the force's work beyond the elastic energy
// (2/5) K d^2.5 it stores.  Zero off the walls.
struct ContactForce {
    double f, loss;
};

BB_INLINE ContactForce contact_force(const Params& q, double y, double yd) {
    const double d = std::fabs(y) - q.ball.half;
    if (!(d > 0.0)) return {0.0, 0.0};
    const double s = y > 0.0 ? 1.0 : -1.0;
    const double dd = s * yd;
    const double elastic = q.contact.k * d * std::sqrt(d);
    const double push = std::fmax(0.0, elastic * (1.0 + q.contact.chi * dd));
    return {-s * push, (push - elastic) * dd};
}

// F_c and what the stage derivative picks by y''s sign (Friction::fb, dmfb, kfb).
inline void set_friction(Params& q, double fc) {
    Friction& fr = q.fric;
    fr.fc = fc;
    const double fbs[3] = {-fc, 0.0, fc};
    fr.ydd_sum_from_first = true;
    for (int b = 0; b < 3; ++b) {
        fr.fb[b] = fbs[b];
        for (int i = 0; i < q.modes.n; ++i) {
            const double dmfb = q.modes.dm[i] * fbs[b];
            fr.dmfb[i][b] = dmfb;
        }
        const double kfb = fr.kappa * fbs[b];
        fr.kfb[b] = kfb;
        if (kfb == 0.0 && std::signbit(kfb)) fr.ydd_sum_from_first = false;
    }
}

// The system of the packed parameters p (layout.hpp), for RK4's step dt (the forcing's
// half-step rotation; any dt where no step is taken).  (Set in this order, not struct by
// struct: GCC's code for the RK4 kernels, into which this is inlined, follows the order
// of these stores; set struct by struct, the kernels came out up to 6 % larger, with
// other registers and spills.)
inline Params unpack(const double* p, double dt) {
    Params q;
    q.modes.n = int(p[L::N_MODES]);
    q.kase = int(p[L::CASE]);
    q.force.regen = int(p[L::FORCING]) == L::REGENERATIVE;
    q.stage_loop = p[L::STAGE_LOOP] != 0.0;
    q.force.f0 = p[L::F0];
    q.force.om = p[L::OMEGA];
    q.ball.half = p[L::HALF_GAP];
    q.ball.e = p[L::RESTITUTION];
    q.fric.fc = p[L::FRICTION];
    q.fric.sr = p[L::REACTION];
    q.ball.meff = p[L::M_EFF];
    q.ball.vimp = p[L::V_IMPACT];
    q.fric.stick_min = p[L::STICK_MIN];
    q.fric.vstick = p[L::V_STICK];
    q.fric.band = p[L::STICK_BAND];
    q.fric.fs = p[L::STATIC_FRICTION];
    q.fric.hold = q.fric.band > 0.0 && q.fric.fc > 0.0 && q.kase == L::BALL;
    q.tmd.m = p[L::TMD_MASS];
    q.tmd.k = p[L::TMD_K];
    q.tmd.c = p[L::TMD_C];
    q.strobe.period = p[L::STROBE_PERIOD];
    q.strobe.t0 = p[L::STROBE_T0];
    q.ball.m = p[L::BALL_MASS];
    for (int i = 0; i < q.modes.n; ++i) {
        q.modes.invM[i] = 1.0 / p[L::M_ + i];
        q.modes.C[i] = p[L::C_ + i];
        q.modes.pL[i] = p[L::PSI_L + i];
        q.modes.pD[i] = p[L::PSI_D + i];
        q.modes.pA[i] = p[L::PSI_A + i];
        q.modes.pF[i] = p[L::PSI_F + i];
        q.modes.fm[i] = q.modes.pF[i] * q.modes.invM[i];
        q.modes.km[i] = p[L::K_ + i] * q.modes.invM[i];
        q.modes.cm[i] = q.modes.C[i] * q.modes.invM[i];
        q.modes.dm[i] = q.fric.sr * q.modes.pD[i] * q.modes.invM[i];
        q.modes.lm[i] = q.ball.meff * q.modes.pD[i] * q.modes.invM[i];
    }
    q.fric.kappa = carried_kappa(q, q.fric.sr);
    q.contact.k = p[L::CONTACT_K];
    q.contact.alpha = p[L::CONTACT_ALPHA];
    q.contact.on = q.contact.k > 0.0 && q.kase == L::BALL;
    q.kappa1 = carried_kappa(q, 1.0);
    q.roll.on = p[L::ROLL] > 0.0 && q.kase == L::BALL;
    q.roll.mus_n = p[L::ROLL_STATIC];
    q.roll.muk_n = p[L::ROLL_KINETIC];
    q.roll.band = p[L::ROLL_BAND];
    q.roll.kroll = q.ball.m > 0.0 ? 2.5 / q.ball.m : 0.0;
    q.roll.inv_kappa = q.kappa1 + q.roll.kroll != 0.0 ? 1.0 / (q.kappa1 + q.roll.kroll) : 0.0;
    q.fric.inv_kappa = q.fric.kappa != 0.0 ? 1.0 / q.fric.kappa : 0.0;
    set_friction(q, q.fric.fc);
    q.force.chh = std::cos(q.force.om * 0.5 * dt);
    q.force.shh = std::sin(q.force.om * 0.5 * dt);
    return q;
}

// ROLLING: a kernel's case for a rolling ball (a ball bar, the roll law compiled in).
constexpr int ROLLING = 16;

// The mode count and the case of a kernel: compile-time constants where the kernel is
// specialised (N > 0, CASE >= 0), else the run's.  As constants from the start (not
// members set to them) they bound the mode loops before GCC's early passes, which unroll
// those loops and keep the state in registers.
template <int N, int CASE>
struct Shape {
    int run_n, run_kase;
    bool run_roll;
    explicit Shape(const Params& q) : run_n(q.modes.n), run_kase(q.kase), run_roll(q.roll.on) {}
    // a rolling ball: the spin after y' (its own kernels and those of a run-time shape;
    // a constant, so that the other kernels compile the roll law away)
    bool rolls() const { return CASE == ROLLING || (CASE < 0 && run_roll); }
    int n() const { return N > 0 ? N : run_n; }
    int kase() const { return CASE == ROLLING ? L::BALL : CASE >= 0 ? CASE : run_kase; }
    int nx() const { return 2 * n() + 2 + (rolls() ? 1 : 0); }
    int iy() const { return 2 * n(); }
    int iyd() const { return 2 * n() + 1; }
    bool ball() const { return kase() == L::BALL; }
    bool tmd() const { return kase() == L::TMD; }
    bool has_aux() const { return ball() || tmd(); }
    // in the solid and sliding ball bars a mode's rows of the map involve only its own
    // u, u' (a rolling ball's floor friction couples the modes)
    bool diag() const { return kase() == L::SOLID || (ball() && !rolls()); }
    int nxm() const { return 2 * n() + 2; }  // the step map's state: the spin aside
    int is() const { return 2 * n() + 2; }  // a rolling ball's spin s = r omega
    // the length of the state arrays: exact where N is a template constant (room for a
    // rolling ball's spin in the kernel of a run-time shape)
    static constexpr int NXC = N > 0 ? 2 * N + 2 + (CASE == ROLLING ? 1 : 0) : NX_MAX + 1;
    // a compliant contact runs in the kernel of a run-time shape alone (rk4_run.hpp's
    // dispatch), so that the others compile its branches away
    static constexpr bool CONTACT = CASE < 0;
    bool hertz(const Params& q) const { return CONTACT && q.contact.on; }
};

// One of three values by the sign of y (by_sign: for y > 0, y = 0, y < 0; NaN takes
// the middle one), by branches.  While the ball sticks under the sgn() law its stages' y'
// change sign in a pattern that repeats step after step, which the branch predictor
// learns; a predicted branch takes the pick off the stage's chain of dependences, which
// branch-free selects (vector masks) kept it on: with those the published sticking cases
// ran 1.2-1.3x longer on an AVX-512 Xeon, and within the noise of branches on the AVX2
// machines measured before (docs/performance.md).
BB_INLINE double sign_pick(double y, const double* by_sign) {
    if (y > 0.0) return by_sign[0];
    if (y < 0.0) return by_sign[2];
    return by_sign[1];
}

// What a stage's energy flows need besides the derivative.
struct StageTerms {
    double wf;     // the force's point velocity sum psi_F u' (psi_F = psi_L: W')
    double pvisc;  // sum c v^2 of the dashpots
    double fb;     // friction force on the ball
    double yds;    // ball's y'
    double pdv;    // sum psi_d u'
    bool held;     // the stick law held the ball (y'' = 0)
    double pcon;   // the power a compliant contact's damping dissipates
    double pfloor; // the power a slipping roll's floor friction dissipates
    bool rolled;   // a rolling ball rolled without slip at this stage
    double floor;  // a rolling ball's floor friction F
    double sfree;  // sum psi_d a_i of the modes' free accelerations
};

// The ball's stage under the stick law (Friction::hold) inside the band |y'| < band: the
// force that carries the ball with the bar (y'' = 0) is F = sum psi_d a_free / kappa;
// the ball is held while |F| <= F_s, else it slides with F_c the way the bar drags it
// (Karnopp's law; after a held step y' is zeroed, stop_slide).  The modes' accelerations
// are written again with this F_b in place of the sgn() law's; returns y''.
// A compliant contact's force fcon (Contact::on) acts beside it: the friction that holds
// the ball is then what carrying it needs less what the contact gives.
template <int N, int CASE>
BB_INLINE double hold_stage(const Params& q, Shape<N, CASE> sh, const double* Xs, double f,
                            double* Kd, double sfree, double fcon, StageTerms& t) {
    const int n = sh.n();
    const Modes& md = q.modes;
    const Friction& fr = q.fric;
    const bool hertz = sh.hertz(q);
    const double need = hertz ? sfree - q.kappa1 * fcon : sfree;
    const double carry = need * fr.inv_kappa;
    t.held = std::fabs(carry) <= fr.fs;
    const double fb = t.held ? carry : (carry > 0.0 ? fr.fc : -fr.fc);
    for (int i = 0; i < n; ++i) {
        Kd[n + i] = free_acceleration(md.fm[i], md.km[i], md.cm[i], f, Xs[i], Xs[n + i]) -
                    md.dm[i] * fb;
        if (hertz) Kd[n + i] -= md.pD[i] * md.invM[i] * fcon;
    }
    t.fb = fb;
    return t.held ? 0.0 : fr.kappa * fb - need;
}

// A rolling ball's stage (Shape::rolls; docs/model.md, 2.7): the floor's friction F on
// the ball (the bar feels -psi_d F) and the spin s = r omega, s' = -kroll F.  Rolling
// (y' = s) needs F = need / (kappa1 + kroll), need = sum psi_d a_free - kappa1 (F_b +
// the contact's force), the forces already on it; it rolls where the slip y' - s is
// inside the band and |F| <= mu_s N, else it slips with F = -mu_k N sgn(y' - s) (at
// zero slip, the way the need pulls).  ydd: y'' without F; returns y'' with it.
template <int N, int CASE>
BB_INLINE double roll_stage(const Params& q, Shape<N, CASE> sh, const double* Xs, double* Kd,
                            double ydd, double need, StageTerms& t) {
    const int n = sh.n(), is = sh.is();
    const Rolling& rl = q.roll;
    const double slip = Xs[sh.iyd()] - Xs[is];
    const double keep = need * rl.inv_kappa;
    t.rolled = std::fabs(slip) < rl.band && std::fabs(keep) <= rl.mus_n;
    const double dir = slip != 0.0 && !t.rolled ? (slip > 0.0 ? -1.0 : 1.0)
                                                : (keep > 0.0 ? 1.0 : -1.0);
    const double F = t.rolled ? keep : dir * rl.muk_n;
    for (int i = 0; i < n; ++i) Kd[n + i] -= q.modes.pD[i] * q.modes.invM[i] * F;
    Kd[is] = -rl.kroll * F;
    t.pfloor = t.rolled ? 0.0 : -F * slip;
    t.floor = F;
    return ydd + q.kappa1 * F;
}

// The stage derivative Kd at the stage state Xs under the force f at the tip: the bar
// M_i u_i'' + C_i u_i' + K_i u_i = psi_F,i f with the damper's terms (docs/model.md, 2;
// psi_F = psi_L but in an oriented cut, section 4.7),
// written with premultiplied constants and the stage velocity last, so that little of
// it waits on the previous stage.
//
// FAST: the ball's y'' sums psi_d a_i from its first term (Friction::ydd_sum_from_first),
// which takes an addition off the stage's longest chain (a_i, y'', y' at the next stage,
// F_b).
//
// ysign: the value whose sign picks the friction force F_b = -F_c sgn(ysign) (sign_pick);
// the stages give the stage's own y' (derivative), the regime matrices (dynamics.cpp) a
// sliding direction of their own.  RK4's stages and the matrices that shooting
// linearises are both built from this definition of the equations of motion (the step
// map's tables, linmap.hpp, push basis vectors through a copy of the stage recursion).
// ROLL: a rolling ball's law is compiled in (RK4's stages, derivative(); the matrices and
// the step map, a sliding ball's, leave it out: with it in their copy, GCC 12 stops with
// the internal error above).
template <int N, int CASE, bool FAST = false, bool ROLL = false>
BB_INLINE StageTerms derivative_with(const Params& q, Shape<N, CASE> sh, const double* Xs,
                                     double f, double* Kd, double ysign) {
    const int n = sh.n(), iy = sh.iy(), iyd = sh.iyd();
    const Modes& md = q.modes;
    StageTerms t{0.0, 0.0, 0.0, 0.0, 0.0, false, 0.0, 0.0, false, 0.0, 0.0};
    double sfree = 0.0;  // sum_i psi_d,i a_i of the free accelerations
    for (int i = 0; i < n; ++i) {
        const double vi = Xs[n + i];
        Kd[i] = vi;
        const double ai = free_acceleration(md.fm[i], md.km[i], md.cm[i], f, Xs[i], vi);
        Kd[n + i] = ai;
        sfree = (FAST && sh.ball() && i == 0) ? md.pD[i] * ai : sfree + md.pD[i] * ai;
        t.wf += md.pF[i] * vi;
        t.pvisc += md.C[i] * vi * vi;
    }
    t.sfree = sfree;
    double ydd = 0.0;
    if (sh.ball()) {
        const double yds = Xs[iyd];
        // F_b = -F_c sgn(y'), sgn(0) = 0 (and NaN), with dm F_b and kappa F_b picked by
        // y''s sign (sign_pick)
        const double fb = sign_pick(ysign, q.fric.fb);
        double pdv = 0.0;
        for (int i = 0; i < n; ++i) {
            // the reaction on the bar: -psi_d F_b (sr = 1) or as printed (sr = -1)
            Kd[n + i] -= sign_pick(ysign, q.fric.dmfb[i]);
            pdv += md.pD[i] * Xs[n + i];
        }
        ydd = sign_pick(ysign, q.fric.kfb) - sfree;
        t.fb = fb;
        t.yds = yds;
        t.pdv = pdv;
        // a compliant contact: the wall's force on the ball, its reaction on the bar
        double fcon = 0.0;
        if (sh.hertz(q)) {
            const ContactForce c = contact_force(q, Xs[iy], yds);
            fcon = c.f;
            for (int i = 0; i < n; ++i) Kd[n + i] -= md.pD[i] * md.invM[i] * fcon;
            ydd += q.kappa1 * fcon;
            t.pcon = c.loss;
        }
        // the stick law's band: its own F_b in place of the sgn() law's.  (After the
        // published pick, not around it: with the branch about the pick, when that was a
        // vector select, GCC 12 stopped with an internal error,
        // gimple_expand_vec_cond_expr, in the regime matrices' copy, dynamics.cpp; so the
        // held stage writes the modes again.)
        if (q.fric.hold && std::fabs(ysign) < q.fric.band)
            ydd = hold_stage(q, sh, Xs, f, Kd, sfree, fcon, t);
        if constexpr (ROLL) {
            if (sh.rolls())
                ydd = roll_stage(q, sh, Xs, Kd, ydd, sfree - q.kappa1 * (fb + fcon), t);
        }
    } else if (sh.tmd()) {
        double rel = Xs[iy], reld = Xs[iyd];
        for (int i = 0; i < n; ++i) {
            rel -= md.pA[i] * Xs[i];
            reld -= md.pA[i] * Xs[n + i];
        }
        const double ft = q.tmd.k * rel + q.tmd.c * reld;
        for (int i = 0; i < n; ++i) Kd[n + i] += md.pA[i] * ft * md.invM[i];
        ydd = -ft / q.tmd.m;
        t.pvisc += q.tmd.c * reld * reld;
    } else if (sh.kase() == L::LOCKED) {
        // the force that carries the ball with the bar, m_eff sum psi_d a_free, acts on
        // mode i with psi_d,i
        for (int i = 0; i < n; ++i) Kd[n + i] -= md.lm[i] * sfree;
    }
    Kd[iy] = sh.has_aux() ? Xs[iyd] : 0.0;
    Kd[iyd] = ydd;
    return t;
}

// The dashpots whose power derivative_with sums (StageTerms::pvisc = sum_d c_d v_d^2), as
// rows of the state: v_d = l_d . X.  Mode i's acts on its velocity u_i'; a tuned
// absorber's on the absorber's velocity relative to the bar's at its seat, x_a' - psi_a .
// u' (derivative_with's reld).  l (nd rows of nz, zeroed by the caller, nz >= 2n, and
// 2n + 2 with an absorber) and c (nd): nd = n, and n + 1 with an absorber (dashpot_count).
template <int N, int CASE>
int dashpot_count(Shape<N, CASE> sh) {
    return sh.tmd() ? sh.n() + 1 : sh.n();
}
template <int N, int CASE>
void dashpots(const Params& q, Shape<N, CASE> sh, int nz, double* l, double* c) {
    const int n = sh.n();
    for (int i = 0; i < n; ++i) {
        l[i * nz + n + i] = 1.0;
        c[i] = q.modes.C[i];
    }
    if (sh.tmd()) {
        double* row = l + n * nz;
        row[sh.iyd()] = 1.0;
        for (int i = 0; i < n; ++i) row[n + i] = -q.modes.pA[i];
        c[n] = q.tmd.c;
    }
}

// The stage derivative at Xs, F_b picked by the sign of the stage's own y'.
template <int N, int CASE, bool FAST = false>
BB_INLINE StageTerms derivative(const Params& q, Shape<N, CASE> sh, const double* Xs, double f,
                                double* Kd) {
    return derivative_with<N, CASE, FAST, true>(q, sh, Xs, f, Kd, Xs[sh.iyd()]);
}

}  // namespace bb::dynamics
