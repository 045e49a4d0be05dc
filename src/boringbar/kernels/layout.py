"""The packed parameter vector and the metric vector: their layout, in one place.

The numba kernels see only arrays and scalars.  Everything a run needs is
packed into one float64 vector ``p`` whose slots are named here; everything a
run streams out as scalars goes into ``met`` at the indices named here.
This module imports nothing from the layers above it.
"""

import numpy as np

#: Largest number of retained bending modes the kernel supports.
NMAX = 8

# --- bar cases and forcing kinds --------------------------------------------
SOLID, BALL, TMD, LOCKED = 0, 1, 2, 3
HARMONIC, REGENERATIVE = 0, 1

# --- scalar slots of p ---------------------------------------------------------
_SCALARS = (
    "CASE",  # SOLID / BALL / TMD / LOCKED
    "N_MODES",
    "FORCING",  # HARMONIC / REGENERATIVE
    "F0",  # harmonic amplitude (N)
    "OMEGA",  # forcing circular frequency (rad/s)
    "BALL_MASS",  # m (kg)
    "HALF_GAP",  # delta / 2 (m)
    "RESTITUTION",  # e
    "FRICTION",  # F_c (N)
    "REACTION",  # +1: bar feels -psi_d F_b (reciprocal); -1: +psi_d F_b (printed)
    "M_EFF",  # 1 / (1/m + sum psi_d^2 / M): effective mass of an impact (kg)
    "V_IMPACT",  # impacts with |y'-| below this are contact, not counted (m/s)
    "V_STICK",  # |y'| below this (off the walls) is sticking (m/s)
    "STICK_MIN",  # shortest stick interval recorded (s)
    "TMD_MASS",
    "TMD_K",
    "TMD_C",
    "STROBE_PERIOD",  # Poincare sampling period (s); 0 = off
    "STROBE_T0",  # first strobe time (s)
    # regenerative cutting (docs/model.md, section 4)
    "KR_B",  # Kr * b (N/m)
    "FEED",  # h_m (m)
    "TAU",  # delay, one spindle revolution (s)
    "N_REV",  # past revolutions in the chip-thickness minimum
    "INTERP",  # 0 linear, 1 cubic Hermite for the delayed W
    "STOP_AT_ZERO",  # 1: stop the run at the first h = 0
    "HIST_W0",  # W of the surface before the cut began (0: from rest)
    "STATIC_FRICTION",  # F_s >= F_c, static limit of true stick-slip (exact integrator) (N)
    "STAGE_LOOP",  # 1: every RK4 step by the stage loop, never the step map (tests, benchmarks)
)
for _i, _name in enumerate(_SCALARS):
    globals()[_name] = _i
_OFF = len(_SCALARS)
# per-mode blocks of NMAX entries each
M_ = _OFF
K_ = M_ + NMAX
C_ = K_ + NMAX
PSI_L = C_ + NMAX
PSI_D = PSI_L + NMAX
PSI_A = PSI_D + NMAX
P_SIZE = PSI_A + NMAX

# --- metric slots of met -------------------------------------------------------
_METRICS = (
    "SUM_W2",  # sum of W^2 over steady steps
    "SUM_W",
    "N_STEADY",  # number of steady samples
    "MAX_ABS_W",  # steady
    "MAX_ABS_AUX",  # steady: |y| (ball) or |x_a - psi_a u| (TMD)
    "MAX_ABS_AUX_ALL",  # whole run
    "N_IMP_PLUS",  # counted impacts on the + wall, steady part
    "N_IMP_MINUS",
    "N_IMP_ALL",  # counted impacts, whole run
    "N_MICRO",  # sub-threshold impacts (contact), whole run
    "T_CONTACT",  # steady time with the ball on a wall (s)
    "T_STICK",  # steady time in recorded stick intervals (s)
    "W_FORCE",  # work done by the cutting/harmonic force at the tip (J)
    "D_VISC",  # energy dissipated by modal and absorber dashpots (J)
    "D_IMPACT",  # kinetic energy lost in impacts (J)
    "D_FRICTION",  # energy dissipated by friction, F_c |y'| (J)
    "W_NONRECIP",  # work injected by a non-reciprocal ("printed") friction reaction (J)
    "N_IMP_REC",  # impact rows written
    "N_STICK_REC",  # stick rows written
    "N_REC",  # history rows written
    "N_STROBE",  # strobe rows written
    "FIRST_ZERO_T",  # time the chip thickness first reached zero (-1: never)
    "N_ZERO_STEPS",  # steps with h = 0 at any stage
    "MAX_FORCE",  # largest cutting force (N)
    "SUM_F",  # sum of force over steady steps
    "STEPS_DONE",
    "SUM_AUX2",  # steady sum of aux^2 (ball y or absorber stroke)
    "STEADY_MAX_W",
    "STEADY_MIN_W",
    "N_EVENTS",  # exact integrator: events handled (impacts, switches, releases)
    "EXACT_STATUS",  # exact integrator: 0 done, 1 event cap reached, 2 stalled (zero-length events)
)
for _i, _name in enumerate(_METRICS):
    globals()[_name] = _i
MET_SIZE = len(_METRICS)
METRIC_NAMES = _METRICS

#: columns of the decimated history
REC_COLS = ("t", "W", "W_dot", "aux", "aux_dot", "force")
#: columns of an impact row: time, wall (+1/-1), relative velocity before
IMP_COLS = ("t", "wall", "v_before")
#: columns of a strobe row
STROBE_COLS = ("t", "W", "W_dot", "aux", "aux_dot")


def empty_params() -> np.ndarray:
    return np.zeros(P_SIZE)
