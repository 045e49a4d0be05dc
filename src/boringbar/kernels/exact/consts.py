"""The exact kernel's constants: grid, limits, regimes, event kinds, the segment record's
slots and the stack scratch's sizes.
"""

import math

from boringbar.kernels import layout as L

#: event-search grid points per shortest period: about 16, but not a whole number, so that
#: events half a forcing period apart (the symmetric two-impact orbit, started at an impact)
#: do not fall on grid points, where the graze guard would search the step again for nothing
GRID_PER_PERIOD = 16.382
#: step lengths of the grid of a free ball: h, 2 h, 4 h, 8 h; a step longer than h is taken
#: only where Taylor bounds prove that no event and no new extremum can fall in it
GRID_LEVELS = 4
#: most events in one run before it stops with EXACT_STATUS = 1
MAX_EVENTS = 50_000_000
#: consecutive zero-length events (shorter than 1e-14 (|t| + h)) before a run stops with
#: EXACT_STATUS = 2
MAX_ZERO_LENGTH = 64

#: lengths of the stack scratch (numba needs them as literal globals)
NZ_MAX = 2 * L.NMAX + 2
NB_MAX = NZ_MAX + 3
NB_MAX2 = NB_MAX * NB_MAX
NZB_MAX = NZ_MAX * NB_MAX
NB_MAX_2 = 2 * NB_MAX
NMAX6 = 6 * L.NMAX
DDC = 4 * (L.NMAX + 2)

FREE, STICK, CONTACT = 0, 1, 2
RECIP = (0.0,) + tuple(1.0 / k for k in range(1, 24))  # 1 / k
RFACT = tuple(1.0 / math.factorial(k) for k in range(20))  # 1 / k!
# event kinds; an event happens where g goes from <= 0 to > 0
EV_PLUS, EV_MINUS, EV_VSTOP, EV_YEXT, EV_REL_NEG, EV_REL_POS, EV_WALL_REL, EV_WEXT = range(8)
# regenerative cut: the tool leaves (in the cut) or re-enters (out of it) where the chip
# thickness h = S - W crosses zero; EV_HEXT = h' guards a graze of h = 0 inside a step
EV_CUT, EV_HEXT = 8, 9
N_EV = 10
# the segment's description ``seg``: see :func:`g_value`
SEG_SIZE = 18
SEG_KRB = 11  # Kr b in the cut, 0 out of it (and for harmonic forcing)
SEG_S = 12  # S(tau) = seg[12] + seg[13] tau + seg[14] tau^2 + seg[15] tau^3, the surface
SEG_CDIR = 16  # +1 in the cut, -1 out of it, 0 harmonic forcing
SEG_ACC = 17  # fb / m, the ball's acceleration (one division per segment)

# the driver's run constants, packed into one array ``cp`` (the driver's pieces take it
# whole instead of a dozen scalars)
CP_HALF = 0  # delta / 2
CP_E = 1  # restitution
CP_FC = 2  # kinetic friction F_c
CP_FS = 3  # static friction max(F_s, F_c)
CP_SR = 4  # reaction share s
CP_MEFF = 5  # effective mass of an impact
CP_VIMP = 6  # capture threshold
CP_KSTICK = 7  # kappa of a stuck ball
CP_KWALL = 8  # kappa on a wall
CP_STICK_MIN = 9  # shortest stick interval recorded
CP_T0 = 10  # the run's start
CP_T_STEADY = 11  # the steady window's start
CP_DT_OUT = 12  # a cut's step (the unit of N_ZERO_STEPS)
CP_STOP_AT_ZERO = 13  # 1: a cut stops at its first zero
CP_F0 = 14  # the harmonic force's amplitude and circular frequency
CP_OM = 15
CP_H = 16  # the event-search grid step h
CP_REC_DT = 17  # the history's sampling step (0: none)
CP_TSTROBE = 18  # the strobe's period (0: none)
CP_M = 19  # the ball's mass
CP_SIZE = 20
# the run's state between segments, packed into one array ``rs`` (floats; the regime and
# the cut flag as 0.0, 1.0, 2.0)
RS_MODE = 0  # FREE, STICK, CONTACT
RS_SDIR = 1  # the direction a free ball slides, 0 if it does not
RS_WALL = 2  # the wall a ball in CONTACT is on
RS_Y = 3  # the ball's y and y'
RS_YD = 4
RS_INCUT = 5  # 1.0 while the tool cuts
RS_FIRST_ZERO = 6  # the chatter verdict: the first exit from the cut (-1: none yet)
RS_T_END = 7  # the run's end (a cut stopped at its first zero ends early)
RS_STICK_T0 = 8  # when the current stick interval began
RS_SIZE = 9
# a regenerative cut's constants, packed into one array ``cq`` (the counts as floats)
CQ_T0 = 0  # the run's start, the first node
CQ_H = 1  # the history step H
CQ_TTOL = 2  # times closer than this are one
CQ_NREV = 3  # revolutions in the surface's minimum
CQ_TAU = 4  # the delay tau
CQ_FEED = 5  # h_m
CQ_W0 = 6  # W before the cut
CQ_MREV = 7  # nodes per revolution
CQ_CUBIC = 8  # 1: cubic Hermite history, 0: linear
CQ_KRB = 9  # Kr b
CQ_SIZE = 10
# the driver's running outputs, packed into one array ``ro`` (k_rec, the next history
# row's index, as a float)
RO_MAX_ABS_W = 0  # the largest |W| (steady)
RO_MAX_W = 1  # the steady extremes of W
RO_MIN_W = 2
RO_MAX_AUX = 3  # the largest |aux|, steady and over the run
RO_MAX_AUX_ALL = 4
RO_MAX_FORCE = 5  # a cut's largest force
RO_K_REC = 6  # the next history row is at t0 + k_rec rec_dt
RO_T_STROBE = 7  # the next strobe time
RO_SIZE = 8
# a segment's description for its search, packed into one array ``sv`` (flags 0.0 or 1.0)
SV_TLEN = 0  # its length
SV_B4 = 1  # bounds over it on |y^(4)|, |W^(4)| (-1: not needed), |y'''| and |W'''|
SV_BW4 = 2
SV_B3Y = 3
SV_B3W = 4
SV_STEADY = 5  # in the steady window
SV_WHOLE = 6  # a cut's whole step H from a node
SV_ADAPT = 7  # steps longer than h allowed
SV_YDD = 8  # y'' and W'' wanted at the grid points
SV_WATCH_V = 9  # a free ball's y' = 0 switch watched
SV_WATCH_EXT = 10  # a free ball's y extremum watched against grazes
SV_SIZE = 11
