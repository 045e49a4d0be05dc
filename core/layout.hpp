// The packed parameter vector p and the metric vector met: their layout, in one place.
//
// Everything a run needs is packed by simulate/engine.py into one float64 vector p whose
// slots are named here; everything a run streams out as scalars goes into met at the
// slots named here.  The Python side reads these names from the compiled module
// (boringbar.core.layout()), so there is no second copy of the offsets.
#pragma once

namespace bb::layout {

// Largest number of retained bending modes the core supports.
constexpr int NMAX = 8;

// bar cases and forcing kinds
enum Case : int { SOLID = 0, BALL = 1, TMD = 2, LOCKED = 3 };
enum Forcing : int { HARMONIC = 0, REGENERATIVE = 1 };

// scalar slots of p (name, meaning in the comment of the Python docs, docs/model.md)
#define BB_P_SCALARS(X)                                                                    \
    X(CASE)             /* SOLID / BALL / TMD / LOCKED */                                  \
    X(N_MODES)                                                                             \
    X(FORCING)          /* HARMONIC / REGENERATIVE */                                      \
    X(F0)               /* harmonic amplitude (N) */                                       \
    X(OMEGA)            /* forcing circular frequency (rad/s) */                           \
    X(BALL_MASS)        /* m (kg) */                                                       \
    X(HALF_GAP)         /* delta / 2 (m) */                                                \
    X(RESTITUTION)      /* e */                                                            \
    X(FRICTION)         /* F_c (N) */                                                      \
    X(REACTION)         /* +1 reciprocal; -1 the printed reaction */                       \
    X(M_EFF)            /* effective mass of an impact (kg) */                             \
    X(V_IMPACT)         /* impacts slower than this are contact (m/s) */                   \
    X(V_STICK)          /* |y'| below this (off the walls) is sticking (m/s) */            \
    X(STICK_MIN)        /* shortest stick interval recorded (s) */                         \
    X(TMD_MASS)                                                                            \
    X(TMD_K)                                                                               \
    X(TMD_C)                                                                               \
    X(STROBE_PERIOD)    /* Poincare sampling period (s); 0 = off */                        \
    X(STROBE_T0)        /* first strobe time (s) */                                        \
    X(KR_B)             /* Kr b (N/m); Kienzle: K b (1 mm)^m_c (N/m^(1-m_c)) */            \
    X(FEED)             /* h_m (m) */                                                      \
    X(TAU)              /* delay, one spindle revolution (s) */                            \
    X(N_REV)            /* past revolutions in the chip-thickness minimum */               \
    X(INTERP)           /* 0 linear, 1 cubic Hermite for the delayed W */                  \
    X(STOP_AT_ZERO)     /* 1: stop the run at the first h = 0 */                           \
    X(HIST_W0)          /* W of the surface before the cut began */                        \
    X(STATIC_FRICTION)  /* F_s >= F_c, static limit of stick-slip (exact) (N) */           \
    X(STAGE_LOOP)       /* 1: every RK4 step by the stage loop (tests, benchmarks) */      \
    X(CUT_MC)           /* Kienzle's m_c: f = KR_B h^(1 - m_c); 0 the linear law */        \
    X(NOISE_STD)        /* relative std of the cut's force noise eps; 0 = off */           \
    X(NOISE_INTERVAL)   /* eps is constant over this long (s), in whole steps */           \
    X(NOISE_SEED)       /* the noise's seed, an integer in [0, 2^53] */                    \
    X(STICK_BAND)       /* RK4's stick law: |y'| below this holds the ball; 0 = sgn() (m/s) */ \
    X(CONTACT_K)        /* Hertz contact K (N/m^1.5), F = K d^1.5 (1 + chi d'); 0 = impacts */ \
    X(CONTACT_ALPHA)    /* Hunt-Crossley's chi v_in that gives the restitution e */      \
    X(ROLL)             /* 1: the ball rolls (its spin a state); 0 = it slides */         \
    X(ROLL_STATIC)      /* mu_s m g: the most friction that keeps it rolling (N) */       \
    X(ROLL_KINETIC)     /* mu_k m g: the friction of a slipping roll (N) */               \
    X(ROLL_BAND)        /* |y' - r omega| below this may roll (m/s) */

#define BB_ENUM_ENTRY(name) name,
enum PSlot : int { BB_P_SCALARS(BB_ENUM_ENTRY) P_SCALARS_END };

// per-mode blocks of NMAX entries each
constexpr int M_ = P_SCALARS_END;
constexpr int K_ = M_ + NMAX;
constexpr int C_ = K_ + NMAX;
constexpr int PSI_L = C_ + NMAX;
constexpr int PSI_D = PSI_L + NMAX;
constexpr int PSI_A = PSI_D + NMAX;
// the force's shape at the tip: psi_L of the force's direction where it differs from the
// chip's (an oriented cut, docs/model.md, section 4.7); psi_L itself otherwise
constexpr int PSI_F = PSI_A + NMAX;
constexpr int P_SIZE = PSI_F + NMAX;

// metric slots of met
#define BB_METRICS(X)                                                                      \
    X(SUM_W2)           /* sum of W^2 over steady steps (exact: the integral) */           \
    X(SUM_W)                                                                               \
    X(N_STEADY)         /* steady samples (exact: the window's length, s) */               \
    X(MAX_ABS_W)                                                                           \
    X(MAX_ABS_AUX)      /* steady: |y| (ball) or |x_a - psi_a u| (TMD) */                  \
    X(MAX_ABS_AUX_ALL)  /* whole run */                                                    \
    X(N_IMP_PLUS)       /* counted impacts on the + wall, steady part */                   \
    X(N_IMP_MINUS)                                                                         \
    X(N_IMP_ALL)        /* counted impacts, whole run */                                   \
    X(N_MICRO)          /* sub-threshold impacts (contact), whole run */                   \
    X(T_CONTACT)        /* steady time with the ball on a wall (s) */                      \
    X(T_STICK)          /* steady time in recorded stick intervals (s) */                  \
    X(W_FORCE)          /* work of the force at the tip (J) */                             \
    X(D_VISC)           /* dissipated by the dashpots (J) */                               \
    X(D_IMPACT)         /* lost in impacts (J) */                                          \
    X(D_FRICTION)       /* dissipated by friction (J) */                                   \
    X(W_NONRECIP)       /* work of a non-reciprocal friction reaction (J) */               \
    X(N_IMP_REC)        /* impact rows written */                                          \
    X(N_STICK_REC)      /* stick rows written */                                           \
    X(N_REC)            /* history rows written */                                         \
    X(N_STROBE)         /* strobe rows written */                                          \
    X(FIRST_ZERO_T)     /* time the chip thickness first reached zero (-1: never) */       \
    X(N_ZERO_STEPS)     /* steps with h = 0 at any stage */                                \
    X(MAX_FORCE)        /* largest cutting force (N) */                                    \
    X(SUM_F)            /* sum of force over steady steps */                               \
    X(STEPS_DONE)                                                                          \
    X(SUM_AUX2)         /* steady sum of aux^2 */                                          \
    X(STEADY_MAX_W)                                                                        \
    X(STEADY_MIN_W)                                                                        \
    X(N_EVENTS)         /* exact: events handled */                                        \
    X(EXACT_STATUS)     /* exact: 0 done, 1 event cap reached, 2 stalled */              \
    X(MAX_HOLD_FORCE)   /* RK4's stick law: largest |F_b| that held the ball (N) */        \
    X(N_FREE_STEPS)     /* RK4's stick law: steps the ball was not held through */        \
    X(N_CONTACT_REC)    /* Hertz contact: contact rows written (counted, steady) */        \
    X(MAX_CONTACT_FORCE) /* Hertz contact: largest contact force, whole run (N) */         \
    X(CONTACT_ON)       /* Hertz contact: 1 while the ball presses a wall (kept between */ \
    X(CONTACT_WALL)     /*   calls, with the contact's wall, start, speed and peak) */     \
    X(CONTACT_T0)                                                                          \
    X(CONTACT_VIN)                                                                         \
    X(CONTACT_PEAK)                                                                        \
    X(CONTACT_COUNTED)  /*   1: it began faster than V_IMPACT, an impact */              \
    X(CONTACT_STEADY)   /*   1: it began in the steady part */

enum MetSlot : int { BB_METRICS(BB_ENUM_ENTRY) MET_SIZE };
#undef BB_ENUM_ENTRY

// columns of the record arrays
constexpr int REC_NCOL = 6;     // t, W, W', aux, aux', force; a rolling ball's run may
                                // give rec one column more, for its spin s = r omega
constexpr int IMP_NCOL = 3;     // t, wall, v_before
constexpr int STICK_NCOL = 2;   // start, end
constexpr int STROBE_NCOL = 5;  // t, W, W', aux, aux'
constexpr int CONTACT_NCOL = 6; // start, wall, v_in, duration, peak force, v_out

}  // namespace bb::layout
