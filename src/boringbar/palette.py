"""The colours of boringbar's figures, the report's and the design page's alike: the
Okabe-Ito palette (colour-blind safe) and the colour, line and label of each bar.  No
plotting library here, so the page (Bokeh) and the figures (matplotlib) share it."""

from __future__ import annotations

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
