"""boringbar: vibration and chatter of impact-damped boring bars.

Public names only; see docs/architecture.md for the layers behind them.
"""

__version__ = "0.1.0"

from boringbar.model.bar import ModalModel, Section, SteppedBar, published_bar  # noqa: E402
from boringbar.model.dampers import (  # noqa: E402
    Friction,
    ImpactDamper,
    TunedMassDamper,
    den_hartog_parameters,
)
from boringbar.model.forcing import Harmonic  # noqa: E402
from boringbar.model.system import PRESETS, READINGS, System, make_system  # noqa: E402
from boringbar.simulate import Initial, Run, State, simulate  # noqa: E402

__all__ = [
    "PRESETS",
    "READINGS",
    "Friction",
    "Harmonic",
    "ImpactDamper",
    "Initial",
    "ModalModel",
    "Run",
    "Section",
    "State",
    "SteppedBar",
    "System",
    "TunedMassDamper",
    "den_hartog_parameters",
    "make_system",
    "published_bar",
    "simulate",
]
