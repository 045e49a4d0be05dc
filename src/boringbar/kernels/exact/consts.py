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
_NZ_MAX = 2 * L.NMAX + 2
_NB_MAX = _NZ_MAX + 3
_NB_MAX2 = _NB_MAX * _NB_MAX
_NZB_MAX = _NZ_MAX * _NB_MAX
_NB_MAX_2 = 2 * _NB_MAX
_NMAX6 = 6 * L.NMAX
_DDC = 4 * (L.NMAX + 2)

FREE, STICK, CONTACT = 0, 1, 2
_RECIP = (0.0,) + tuple(1.0 / k for k in range(1, 24))  # 1 / k
_RFACT = tuple(1.0 / math.factorial(k) for k in range(20))  # 1 / k!
# event kinds; an event happens where g goes from <= 0 to > 0
EV_PLUS, EV_MINUS, EV_VSTOP, EV_YEXT, EV_REL_NEG, EV_REL_POS, EV_WALL_REL, EV_WEXT = range(8)
# regenerative cut: the tool leaves (in the cut) or re-enters (out of it) where the chip
# thickness h = S - W crosses zero; EV_HEXT = h' guards a graze of h = 0 inside a step
EV_CUT, EV_HEXT = 8, 9
N_EV = 10
# the segment's description ``seg``: see :func:`_g`
SEG_SIZE = 18
SEG_KRB = 11  # Kr b in the cut, 0 out of it (and for harmonic forcing)
SEG_S = 12  # S(tau) = seg[12] + seg[13] tau + seg[14] tau^2 + seg[15] tau^3, the surface
SEG_CDIR = 16  # +1 in the cut, -1 out of it, 0 harmonic forcing
SEG_ACC = 17  # fb / m, the ball's acceleration (one division per segment)
