// The exact kernel's constants: the grid, the limits, the regimes, the event kinds, the
// scratch's sizes, and the records the driver keeps between segments (the run's constants,
// its state, a cut's constants, the running outputs, a segment's description and its
// search's settings) as named structs.
#pragma once

#include "../arrays.hpp"
#include "../dynamics.hpp"
#include "../layout.hpp"
#include "../model.hpp"

namespace bb::exact {

// event-search grid points per shortest period: about 16, but not a whole number, so that
// events half a forcing period apart do not fall on grid points
constexpr double GRID_PER_PERIOD = 16.382;
// step lengths of a free ball's grid: h, 2 h, 4 h, 8 h
constexpr int GRID_LEVELS = 4;
// most events in one run before it stops with EXACT_STATUS = 1
constexpr idx MAX_EVENTS = 50'000'000;
// consecutive zero-length events before a run stops with EXACT_STATUS = 2
constexpr int MAX_ZERO_LENGTH = 64;

// lengths of the scratch (local arrays, sized for NMAX modes)
constexpr int NZ_MAX = 2 * layout::NMAX + 2;
constexpr int NB_MAX = NZ_MAX + 3;
constexpr int NB_MAX2 = NB_MAX * NB_MAX;
constexpr int NZB_MAX = NZ_MAX * NB_MAX;
constexpr int NB_MAX_2 = 2 * NB_MAX;
// the bar's rows mk (System::mk): M, K, C, psi_L, psi_d, psi_a, then the equations of
// motion's premultiplied constants fm, km, cm and 1 / M (dynamics.hpp's Modes), and
// psi_F, where the tip force acts (psi_L, where the chip reads W, but in an oriented cut)
constexpr int MK_M = 0, MK_K = 1, MK_C = 2, MK_PSI_L = 3, MK_PSI_D = 4, MK_PSI_A = 5;
constexpr int MK_FM = 6, MK_KM = 7, MK_CM = 8, MK_INV_M = 9, MK_PSI_F = 10;
constexpr int MK_ROWS = 11;
constexpr int MK_SIZE = MK_ROWS * layout::NMAX;
constexpr int DDC = 4 * (layout::NMAX + 2);

// A ball's regime: free (flying or sliding; a rolling ball's slipping), stuck to the bore,
// resting on a wall, or a rolling ball rolling without slip (docs/model.md, 2.7).  The
// regime's index r in prepare's matrices is the regime (ball bars), plus nreg in a cut.
enum Regime : int { FREE = 0, STICK = 1, CONTACT = 2, ROLL = 3 };

namespace detail {
constexpr double factorial(int k) {
    // k! for k < 20 is exact in a double (19! = 2^16 times an odd number below 2^53), so
    // 1.0 / k! rounds once, as Python's 1.0 / math.factorial(k) does
    unsigned long long f = 1;
    for (int i = 2; i <= k; ++i) f *= static_cast<unsigned long long>(i);
    return static_cast<double>(f);
}
}  // namespace detail

// RECIP[k] = 1 / k (RECIP[0] = 0), RFACT[k] = 1 / k!: one correctly rounded division each,
// so the series' coefficients are the nearest doubles to 1 / k and 1 / k!
constexpr double RECIP[24] = {
    0.0,       1.0 / 1,  1.0 / 2,  1.0 / 3,  1.0 / 4,  1.0 / 5,  1.0 / 6,  1.0 / 7,
    1.0 / 8,   1.0 / 9,  1.0 / 10, 1.0 / 11, 1.0 / 12, 1.0 / 13, 1.0 / 14, 1.0 / 15,
    1.0 / 16,  1.0 / 17, 1.0 / 18, 1.0 / 19, 1.0 / 20, 1.0 / 21, 1.0 / 22, 1.0 / 23};
constexpr double RFACT[20] = {
    1.0 / detail::factorial(0),  1.0 / detail::factorial(1),  1.0 / detail::factorial(2),
    1.0 / detail::factorial(3),  1.0 / detail::factorial(4),  1.0 / detail::factorial(5),
    1.0 / detail::factorial(6),  1.0 / detail::factorial(7),  1.0 / detail::factorial(8),
    1.0 / detail::factorial(9),  1.0 / detail::factorial(10), 1.0 / detail::factorial(11),
    1.0 / detail::factorial(12), 1.0 / detail::factorial(13), 1.0 / detail::factorial(14),
    1.0 / detail::factorial(15), 1.0 / detail::factorial(16), 1.0 / detail::factorial(17),
    1.0 / detail::factorial(18), 1.0 / detail::factorial(19)};

// event kinds; an event happens where g goes from <= 0 to > 0
constexpr idx EV_PLUS = 0, EV_MINUS = 1, EV_VSTOP = 2, EV_YEXT = 3, EV_REL_NEG = 4,
              EV_REL_POS = 5, EV_WALL_REL = 6, EV_WEXT = 7;
// regenerative cut: the tool leaves or re-enters where h = S - W crosses zero; EV_HEXT = h'
// guards a graze of h = 0 inside a step
constexpr idx EV_CUT = 8, EV_HEXT = 9;
// a rolling ball: its slip y' - s comes to zero (FREE); EV_SPIN0, not an event function,
// is a stuck or walled ball's spin run down (its segment ends there)
constexpr idx EV_SLIP = 10, EV_SPIN0 = 11;
constexpr int N_EV = 11;

// A segment's description: what the closed form on it holds constant (the regime's
// forces, the ball's start, a cut's surface polynomial); see g_value.
struct Segment {
    double ts = 0.0;     // the segment's start time
    double fb = 0.0;     // the ball's friction force F_b on it (constant)
    double ud0 = 0.0;    // the ball's absolute position y + psi_d . u at ts
    double vd0 = 0.0;    // ... and its absolute velocity y' + psi_d . u'
    double y0 = 0.0;     // the ball's y at ts (relative)
    double sdir = 0.0;   // the direction a free ball slides (0: none)
    double wall = 0.0;   // the wall a ball in CONTACT is on (+1 / -1)
    double kappa = 0.0;  // kappa of the regime (the force that carries the ball)
    double fs = 0.0;     // static friction F_s
    double half = 0.0;   // delta / 2
    double m = 0.0;      // the ball's mass (1 without a ball)
    double krb = 0.0;    // Kr b in the cut, 0 out of it and harmonic
    double s[4] = {0.0, 0.0, 0.0, 0.0};  // the surface S(tau) = s0 + s1 tau + s2 tau^2 + s3 tau^3
    double cdir = 0.0;   // +1 in the cut, -1 out of it, 0 harmonic
    double acc = 0.0;    // fb / m, the ball's acceleration (rolling: cy fb / m)
    // a rolling ball (docs/model.md, 2.7): the share cy of the floor's motion that y
    // follows (y = ud0 + vd0 tau + acc tau^2 / 2 - cy psi_d . u: 1 but rolling, 5/7), its
    // spin s = s0 + sd tau (rolling: y'), the slip's direction (FREE: -1, 0, 1), the
    // floor's friction ffl on it (the bar feels -psi_d ffl) and what the friction that
    // holds or rolls it has besides the carrying force (F - foff, against fs)
    bool rolls = false;
    double cy = 1.0;
    double s0 = 0.0, sd = 0.0;
    double slip = 0.0;
    double ffl = 0.0;
    double foff = 0.0;
};

// A free or rolling ball's y and y' relative to the bar at tau, from psi_d . u and
// psi_d . u' there: its own motion (ud0, vd0, acc) less cy of the floor's (a sliding
// ball's cy = 1 leaves pdu's bits as they are).
inline double ball_y(const Segment& seg, double tau, double pdu) {
    return seg.ud0 + tau * (seg.vd0 + 0.5 * seg.acc * tau) - seg.cy * pdu;
}
inline double ball_yd(const Segment& seg, double tau, double pdv) {
    return seg.vd0 + seg.acc * tau - seg.cy * pdv;
}

// What the exact integrator derives from the system to hold, carry and roll the ball: the
// static friction a held ball can take, max(F_s, F_c), and the kappa of the force that
// carries it with the bar (per unit of relative acceleration) when stuck (the share s of
// the reaction) and on a wall (the share 1), 1 without a ball's mass; a rolling ball's
// share cy = m kroll / (m kroll + 1) of the floor's motion it follows and its carrying
// force's kappa, kwall + kroll (docs/model.md, 2.7).
struct Carrying {
    double fs = 0.0;
    double kstick = 1.0;
    double kwall = 1.0;
    double roll_cy = 1.0;
    double roll_kappa = 0.0;
};

// The system a run integrates: the one description every integrator unpacks from p
// (dynamics::Params: the modes, the ball, its friction and rolling, the absorber, the
// forcing), with what the exact integrator derives from it: the bar's rows mk, a free
// ball's y'' and W'' coefficients ddc and the ball's carrying.  A tuned absorber enters
// through the regimes' matrices and its row psi_a; a cut through CutConsts.
struct System {
    dynamics::Params q;
    idx n = 0;                        // retained modes
    layout::Case kase = layout::SOLID;
    idx nreg = 1;                     // regimes outside a cut (3 for the ball bar)
    Mat mk;   // (MK_ROWS, n): modal mass M, stiffness K, damping C, psi_L (tip), psi_d
              // (damper), psi_a (absorber); fm, km, cm (free_acceleration's) and 1 / M
    Mat ddc;  // (4, n + 2): a free ball's y'' and W'' from u, f and F_b (rows 0, 1), and
              // from u' (rows 2, 3)
    Carrying carry;

    bool has_ball() const { return kase == layout::BALL; }
};

// The floor's friction on a rolling ball at rest on the bore or a wall (y' = 0) that
// spins: mu_k N the way the spin's slip -s is opposed (0 without spin).
inline double spin_friction(const dynamics::Rolling& roll, double spin) {
    return spin > 0.0 ? roll.muk_n : (spin < 0.0 ? -roll.muk_n : 0.0);
}

// The run's span and outputs: its start, the steady window's start, a cut's step, the
// event-search grid step, the history's and the strobe's sampling.
struct RunConsts {
    double t0 = 0.0;             // the run's start
    double t_steady = 0.0;       // the steady window's start
    double dt_out = 0.0;         // a cut's step (the unit of N_ZERO_STEPS)
    bool stop_at_zero = false;   // a cut stops at its first zero
    double h = 0.0;              // the event-search grid step h
    double rec_dt = 0.0;         // the history's sampling step (0: none)
    double tstrobe = 0.0;        // the strobe's period (0: none)
};

// A ball's state between segments: its regime, the direction it slides (0 if it does
// not), the wall it rests on (CONTACT), its y and y'.
struct BallState {
    Regime mode = FREE;
    double sdir = 0.0;
    double wall = 0.0;
    double y = 0.0;
    double yd = 0.0;
    double spin = 0.0;  // a rolling ball's s = r omega
    double slip = 0.0;  // the direction of its slip y' - s (FREE; 0: none)
};

// The run's state between segments (the bar's own state is the work vector X).
struct RunState {
    BallState ball;
    bool incut = false;       // the tool cuts
    double first_zero = 0.0;  // the chatter verdict: the first exit from the cut (-1: none)
    double t_end = 0.0;       // the run's end (a cut stopped at its first zero ends early)
    double stick_t0 = 0.0;    // when the current stick interval began
};

// A regenerative cut's constants.
struct CutConsts {
    double t0 = 0.0;     // the run's start, the first node
    double h = 0.0;      // the history step H
    double ttol = 0.0;   // times closer than this are one
    idx nrev = 0;        // revolutions in the surface's minimum
    double tau = 0.0;    // the delay tau
    double feed = 0.0;   // h_m
    double w0 = 0.0;     // W before the cut
    idx mrev = 1;        // nodes per revolution
    bool cubic = false;  // cubic Hermite history (else linear)
    double krb = 0.0;    // Kr b
};

// The driver's running outputs.
struct RunningOut {
    double max_abs_w = 0.0;    // the largest |W| (steady)
    double max_w = 0.0;        // the steady extremes of W
    double min_w = 0.0;
    double max_aux = 0.0;      // the largest |aux|, steady and over the run
    double max_aux_all = 0.0;
    double max_force = 0.0;    // a cut's largest force
    double k_rec = 0.0;        // the next history row is at t0 + k_rec rec_dt
    double t_strobe = 0.0;     // the next strobe time
};

// What a segment's search needs beyond the segment: its length, derivative bounds and
// what to watch.
struct SegSearch {
    double tlen = 0.0;       // its length
    double b4 = 0.0;         // bounds over it on |y^(4)|, |W^(4)| (-1: not needed),
    double bw4 = 0.0;        // |y'''| and |W'''|
    double b3y = 0.0;
    double b3w = 0.0;
    bool steady = false;     // in the steady window
    bool whole = false;      // a cut's whole step H from a node
    bool adapt = false;      // steps longer than h allowed
    bool ydd = false;        // y'' and W'' wanted at the grid points
    bool watch_v = false;    // a free ball's y' = 0 switch watched
    bool watch_ext = false;  // a free ball's y extremum watched against grazes
    bool watch_slip = false;  // a slipping ball's y' = s watched
    double slip = 0.0;        // ... the slip's direction and its spin's rate (longer steps)
    double sd = 0.0;
    double ydd_max = -1.0;    // a rolling ball's largest |y''| (kroll mu_s N; -1: not rolling)
};

}  // namespace bb::exact
