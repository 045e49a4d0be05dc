// What the integrators share, written once: the impact law, the impact and stick
// records, the fixed-step scheme's wall rule and stick bookkeeping, the Poincare strobe
// row and the steady metrics (docs/model.md, sections 2.4-2.5).
//
// The RK4 run (rk4.cpp), the lock-step batch (rk4_batch.cpp) and the exact event-driven
// integrator (exact/) call these.  Each does the operations in the order the published
// scheme states them, so that the same run gives the same bits in every integrator that
// shares the step (no fast-math; -ffp-contract=off; explicit std::fma only where written).
#pragma once

#include <cmath>

#include "arrays.hpp"
#include "layout.hpp"

namespace bb {

namespace L = layout;

// The ball of an impact damper and its walls: half the diametral gap, the restitution, the
// effective mass of an impact, the capture threshold (impacts slower than vimp are contact)
// and the ball's mass (0: no ball).
struct Ball {
    double half = 0.0;  // delta / 2
    double e = 0.0;     // restitution
    double meff = 0.0;  // effective mass of an impact
    double vimp = 0.0;  // capture threshold
    double m = 0.0;     // the ball's mass
};

// Where a run's events go: the metric vector (the counts and sums), the impact and stick
// records, and the start of the steady part (counts and rows are kept from there on).
struct EventLog {
    double* met;
    Mat imp, stick;
    double t_steady;
};

// outcome of wall_rule at a step's end
enum WallOutcome : int { OFF_WALL = 0, IMPACT = 1, MICRO_IMPACT = 2, ON_WALL = 3 };

// An impact of a ball arriving with relative velocity vb (docs/model.md, 2.4):
// y'+ = -e y'-, the modes' jumps u_i'+ = u_i'- + g psi_d,i / M_i with
// g = (1 + e) m_eff y'-, and the kinetic energy lost, (1 - e^2) m_eff y'-^2 / 2.
struct ImpactJump {
    double yd;    // y'+
    double g;     // impulse factor
    double loss;  // kinetic energy lost
};

inline ImpactJump impact_law(double vb, double e, double meff) {
    return {-e * vb, (1.0 + e) * meff * vb, 0.5 * (1.0 - e * e) * meff * vb * vb};
}

// A counted impact at t on wall (+1/-1) at relative velocity vb: N_IMP_ALL, and in the
// steady part the wall's count and the row (t, wall, vb) of imp while there is room
// (N_IMP_REC counts the rows, written or not).
inline void count_impact(double* met, Mat imp, double t, double wall, double vb, bool steady) {
    met[L::N_IMP_ALL] += 1;
    if (steady) {
        if (wall > 0)
            met[L::N_IMP_PLUS] += 1;
        else
            met[L::N_IMP_MINUS] += 1;
        idx n_imp = idx(met[L::N_IMP_REC]);
        if (n_imp < imp.n0) {
            imp(n_imp, 0) = t;
            imp(n_imp, 1) = wall;
            imp(n_imp, 2) = vb;
        }
        met[L::N_IMP_REC] += 1;
    }
}

// The stick interval from t_start to t ends: clipped to the steady part (from t_steady)
// and, if at least stick_min long, its time into T_STICK and its row (start, end) into
// stick while there is room (N_STICK_REC counts the rows).
inline void close_stick(double* met, Mat stick, double t_start, double t, double t_steady,
                        double stick_min) {
    double s0 = t_start > t_steady ? t_start : t_steady;  // Python's max(t_start, t_steady)
    if (t - s0 >= stick_min) {
        met[L::T_STICK] += t - s0;
        idx n_stk = idx(met[L::N_STICK_REC]);
        if (n_stk < stick.n0) {
            stick(n_stk, 0) = s0;
            stick(n_stk, 1) = t;
        }
        met[L::N_STICK_REC] += 1;
    }
}

// The fixed-step scheme's walls at the end t1 of a step (docs/model.md, 2.5): a ball at
// or past a wall (|y| >= half) is put back on it and, if moving outward (y y' > 0), takes
// the impact law, counted (count_impact) if faster than vimp, else a micro impact
// (N_MICRO, contact); the energy lost into D_IMPACT.
struct WallResult {
    int outcome;  // WallOutcome
    double y, yd, g;
};

inline WallResult wall_rule(double* met, Mat imp, double y, double yd, double t1, bool steady,
                            const Ball& ball) {
    const double half = ball.half, e = ball.e, meff = ball.meff, vimp = ball.vimp;
    if (!(std::fabs(y) >= half)) return {OFF_WALL, y, yd, 0.0};
    double wall = y > 0.0 ? 1.0 : -1.0;
    if (!(wall * yd > 0.0)) return {ON_WALL, wall * half, yd, 0.0};
    ImpactJump j = impact_law(yd, e, meff);
    met[L::D_IMPACT] += j.loss;
    if (std::fabs(yd) > vimp) {
        count_impact(met, imp, t1, wall, yd, steady);
        return {IMPACT, wall * half, j.yd, j.g};
    }
    met[L::N_MICRO] += 1;
    return {MICRO_IMPACT, wall * half, j.yd, j.g};
}

// The fixed-step scheme's stick bookkeeping for the step [t, t1]: an interval opens at t
// when the ball is stuck (off the walls, |y'| inside the band where the sgn() law
// chatters) and closes at t1 when it no longer is.
struct StickState {
    bool in_stick = false;
    double t0 = 0.0;
};

inline void stick_step(bool stuck, StickState& s, double t, double t1, const EventLog& log,
                       double stick_min) {
    if (stuck && !s.in_stick) {
        s.in_stick = true;
        s.t0 = t;
    } else if (s.in_stick && !stuck) {
        close_stick(log.met, log.stick, s.t0, t1, log.t_steady, stick_min);
        s.in_stick = false;
    }
}

// (W, W') at s in [0, 1] of a step of dt from (w0, wd0) to (w1, wd1): the cubic Hermite,
// every multiply-add an explicit fma so the rounding is the same wherever it is used.
struct WAndRate {
    double w, wd;
};

inline WAndRate hermite(double s, double dt, double w0, double wd0, double w1, double wd1) {
    double s2 = s * s;
    double s3 = s2 * s;
    double h00 = std::fma(2.0, s3, -(3.0 * s2)) + 1.0;  // 2 s^3 - 3 s^2 + 1
    double h10 = std::fma(-2.0, s2, s3) + s;            // s^3 - 2 s^2 + s
    double h01 = std::fma(-2.0, s3, 3.0 * s2);          // -2 s^3 + 3 s^2
    double h11 = s3 - s2;
    double w = std::fma(h11 * dt, wd1, std::fma(h01, w1, std::fma(h10 * dt, wd0, h00 * w0)));
    double g = std::fma(6.0, s2, -(6.0 * s)) / dt;  // (6 s^2 - 6 s) / dt
    double d0 = std::fma(3.0, s2, -(4.0 * s)) + 1.0;  // 3 s^2 - 4 s + 1
    double d1 = std::fma(3.0, s2, -(2.0 * s));        // 3 s^2 - 2 s
    double wd = std::fma(d1, wd1, std::fma(d0, wd0, g * (w0 - w1)));
    return {w, wd};
}

// (1 - s) a0 + s a1
inline double lerp(double s, double a0, double a1) { return std::fma(1.0 - s, a0, s * a1); }

// The tip's W, W' and the auxiliary coordinate and its rate: the ball's y or the absorber's
// stroke x_a - psi_a u (what a history or strobe row holds besides its time).
struct TipAux {
    double w, wd, aux, auxd;
};

// A Poincare strobe row (tn, W, W', aux, aux') at tn inside the step [t, t + dt] from its
// end values s0 and s1: W, W' by the cubic Hermite, aux, aux' linearly.
inline void strobe_row(double* row, double tn, double t, double dt, const TipAux& s0,
                       const TipAux& s1) {
    double s = (tn - t) / dt;
    row[0] = tn;
    WAndRate h = hermite(s, dt, s0.w, s0.wd, s1.w, s1.wd);
    row[1] = h.w;
    row[2] = h.wd;
    row[3] = lerp(s, s0.aux, s1.aux);
    row[4] = lerp(s, s0.auxd, s1.auxd);
}

// The steady part's running sums and extremes, kept in registers by the RK4 kernels and
// stored into met at the end of a call.
struct Steady {
    double sum_w2, sum_w, n_steady, sum_aux2, sum_f, t_contact;
    double max_abs_w, max_w, min_w, max_aux, max_aux_all;

    static Steady load(const double* met) {
        return {met[L::SUM_W2],    met[L::SUM_W],        met[L::N_STEADY],
                met[L::SUM_AUX2],  met[L::SUM_F],        met[L::T_CONTACT],
                met[L::MAX_ABS_W], met[L::STEADY_MAX_W], met[L::STEADY_MIN_W],
                met[L::MAX_ABS_AUX], met[L::MAX_ABS_AUX_ALL]};
    }

    void store(double* met) const {
        met[L::SUM_W2] = sum_w2;
        met[L::SUM_W] = sum_w;
        met[L::N_STEADY] = n_steady;
        met[L::SUM_AUX2] = sum_aux2;
        met[L::SUM_F] = sum_f;
        met[L::T_CONTACT] = t_contact;
        met[L::MAX_ABS_W] = max_abs_w;
        met[L::STEADY_MAX_W] = max_w;
        met[L::STEADY_MIN_W] = min_w;
        met[L::MAX_ABS_AUX] = max_aux;
        met[L::MAX_ABS_AUX_ALL] = max_aux_all;
    }

    // A step's steady metrics: the sums and extremes with the step end's W, aux and f
    // (Python's max(a, b): b if b > a else a, so a NaN never replaces a number).
    void sample(double w, double aux, double f) {
        sum_w2 = sum_w2 + w * w;
        sum_w = sum_w + w;
        n_steady = n_steady + 1.0;
        sum_aux2 = sum_aux2 + aux * aux;
        sum_f = sum_f + f;
        max_abs_w = pymax(max_abs_w, std::fabs(w));
        max_w = pymax(max_w, w);
        min_w = pymin(min_w, w);
        max_aux = pymax(max_aux, std::fabs(aux));
    }

    static double pymax(double a, double b) { return b > a ? b : a; }
    static double pymin(double a, double b) { return b < a ? b : a; }
};

// The energy flows integrated step by step.
struct Flows {
    double w_force, d_visc, d_fric, w_nr;
    // lost in a compliant contact's damping in this call (added to D_IMPACT at the end:
    // the impact law adds its losses to met as they happen)
    double d_con = 0.0;

    static Flows load(const double* met) {
        return {met[L::W_FORCE], met[L::D_VISC], met[L::D_FRICTION], met[L::W_NONRECIP]};
    }

    void store(double* met) const {
        met[L::W_FORCE] = w_force;
        met[L::D_VISC] = d_visc;
        met[L::D_FRICTION] = d_fric;
        met[L::W_NONRECIP] = w_nr;
    }
};

}  // namespace bb
