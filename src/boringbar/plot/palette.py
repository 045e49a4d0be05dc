"""What boringbar's figures, the report's and the design page's alike, share: the
Okabe-Ito palette (colour-blind safe), the colour, line and label of each bar, and a lobe
figure's axes.  No plotting library here, so the page (Bokeh) and the figures (matplotlib)
share it."""

from __future__ import annotations

import math

import numpy as np

#: Okabe-Ito's eight colours.
OKABE_ITO = {"black": "#000000", "orange": "#E69F00", "sky blue": "#56B4E9",
             "bluish green": "#009E73", "yellow": "#F0E442", "blue": "#0072B2",
             "vermillion": "#D55E00", "reddish purple": "#CC79A7"}
#: Neutral greys: behind the data (no impact, other attractors), and samples drawn over
#: a curve (the brute-force strobe samples over continued branches).
GREY = "#999999"
DARK_GREY = "#404040"

#: Colours of a series of things with no colour of their own (attractors, parameter
#: values, gaps, modes, cases), most distinct first.
CYCLE = tuple(OKABE_ITO[k] for k in ("blue", "orange", "bluish green", "vermillion",
                                     "sky blue", "reddish purple", "yellow", "black"))

#: Colour, line style and legend label of each bar; "locked" is the ball bar with its
#: ball held by friction.
BAR_STYLE = {
    "solid": {"color": OKABE_ITO["blue"], "ls": "-", "label": "solid bar"},
    "tmd": {"color": OKABE_ITO["bluish green"], "ls": "--", "label": "TMD bar"},
    "ball": {"color": OKABE_ITO["vermillion"], "ls": "-.", "label": "ball-damped bar"},
    "locked": {"color": OKABE_ITO["vermillion"], "ls": "-.", "label": "ball bar, ball locked"},
}

#: A lobe figure's depth axis ends at most this many times above its bars' smallest limit
#: (their pockets' depth): lobe 1's peak rises tens of times above the pockets, and on a
#: linear axis would press the depths a bar cuts at into the axis's foot ...
LOBE_CAP = 10.0
#: ... but never below this many times the largest of the bars' smallest limits, so every
#: bar's pockets and their rise stay in view (a tuned absorber's may be ten times another
#: bar's).
LOBE_FLOOR_ROOM = 2.0
#: Room above the deepest curve or point a lobe figure shows.
LOBE_HEADROOM = 1.15


def lobe_depth_top(shown, floors) -> tuple[float, float | None]:
    """Where a lobe figure's linear depth axis (from 0) ends, in the unit of ``shown``:
    :data:`LOBE_HEADROOM` times the largest finite value of ``shown`` (every curve and
    point drawn), but at most :data:`LOBE_CAP` times the smallest of ``floors`` (each
    bar's smallest limit) or :data:`LOBE_FLOOR_ROOM` times the largest, whichever is
    higher; and the largest value left above the axis (None when nothing is)."""
    values = np.concatenate([np.ravel(np.asarray(v, dtype=float)) for v in shown] or [[]])
    values = values[np.isfinite(values)]
    peak = float(values.max()) if values.size else 0.0
    top = LOBE_HEADROOM * peak if peak > 0 else 1.0
    low = np.asarray(floors, dtype=float)
    low = low[np.isfinite(low) & (low > 0)]
    if low.size:
        top = min(top, max(LOBE_CAP * float(low.min()), LOBE_FLOOR_ROOM * float(low.max())))
    return top, (peak if peak > top else None)


#: Speeds spanning more than this factor are drawn on a log axis, labelled at these
#: multiples of each decade.
LOG_SPAN = 3.0
LOG_TICKS = (1.0, 1.5, 2.0, 3.0, 5.0, 7.0)


def speed_axis(lo: float, hi: float) -> tuple[bool, np.ndarray | None, tuple[float, float]]:
    """A lobe figure's speed axis over ``lo`` to ``hi`` rpm: (log scale?, the labelled
    ticks (None: the plotting library's own), the axis's ends).  Speeds spanning more
    than :data:`LOG_SPAN` are on a log axis labelled at :data:`LOG_TICKS` of each decade,
    its ends at the ticks next beyond the speeds when near, so both ends are labelled: a
    lobe spans a fixed width in 1/rpm, and on a linear axis the slow lobes, where a long
    bar is cut, crowd into its left edge.  Others are linear, 4 % wider each side."""
    if hi <= LOG_SPAN * lo:
        pad = 0.04 * (hi - lo) if hi > lo else 0.05 * lo
        return False, None, (lo - pad, hi + pad)
    decades = 10.0 ** np.arange(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1)
    ticks = np.outer(decades, LOG_TICKS).ravel()
    left, right = ticks[ticks <= lo].max(), ticks[ticks >= hi].min()
    return True, ticks, (float(left) if 1.25 * left >= lo else lo / 1.03,
                         float(right) if right <= 1.25 * hi else hi * 1.03)
