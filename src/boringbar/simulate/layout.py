"""The packed parameter vector ``p`` and the metric vector ``met``: their slots, read from
the compiled core.

The core (``core/layout.hpp``) defines the layout once; this module gives its names to
Python as module constants (``L.CASE``, ``L.M_``, ``L.SUM_W2``, ...), so that there is no
second copy of the offsets.  It imports nothing from the layers above it.
"""

import numpy as np

from boringbar import core

_SLOTS = core.layout()
globals().update(_SLOTS)

#: largest number of retained bending modes the core supports
NMAX: int = _SLOTS["NMAX"]
P_SIZE: int = _SLOTS["P_SIZE"]
MET_SIZE: int = _SLOTS["MET_SIZE"]
#: the scalar slots of ``p`` in order (the per-mode blocks of NMAX entries follow them)
PARAM_NAMES: tuple = tuple(core.param_names())
#: the per-mode blocks of ``p``, in order
PARAM_BLOCKS: tuple = ("M_", "K_", "C_", "PSI_L", "PSI_D", "PSI_A", "PSI_F")
#: the slots of ``met``, in order
METRIC_NAMES: tuple = tuple(core.metric_names())
#: the core's case (slot CASE) of each bar, by System.kind
CASE_OF_KIND: dict = {"solid": _SLOTS["SOLID"], "ball": _SLOTS["BALL"], "tmd": _SLOTS["TMD"],
                      "locked": _SLOTS["LOCKED"]}


def empty_params() -> np.ndarray:
    """A zeroed parameter vector of the core's size."""
    return np.zeros(P_SIZE)
