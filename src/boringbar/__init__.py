"""boringbar: vibration and chatter of impact-damped boring bars.

Public names only (``import boringbar as bb``); docs/architecture.md shows the
layers behind them.

- Descriptions: :class:`SteppedBar`, :class:`ModalModel`, :class:`ImpactDamper`,
  :class:`Friction`, :class:`TunedMassDamper`, :class:`System` and
  :func:`make_system` (the two presets); forcing: :class:`Harmonic`,
  :class:`Regenerative`.
- One run: :func:`simulate` -> :class:`Run`.
- Analyses: :func:`sweep`, :func:`lobes`, :func:`bifurcation`, :func:`basins`,
  :func:`sensitivity`, :func:`poincare_map`.
- Closed-form references: :func:`tip_frf`, :func:`min_real_part`,
  :func:`sims_tuning`, :func:`den_hartog_parameters`.
- Study files: :func:`load_study`, :func:`run_study`.
"""

__version__ = "0.1.0"

from boringbar import plot  # noqa: E402, F401  (registers Run.plot)
from boringbar._validate import ParameterError  # noqa: E402
from boringbar.analysis.basins import BasinOptions, basins  # noqa: E402
from boringbar.analysis.bifurcation import BifurcationOptions, bifurcation  # noqa: E402
from boringbar.analysis.continuation import ContinuationOptions, continuation  # noqa: E402
from boringbar.analysis.lobes import LobesOptions, lobes  # noqa: E402
from boringbar.analysis.poincare import poincare_map  # noqa: E402
from boringbar.analysis.sensitivity import Cuts, SensitivityOptions, sensitivity  # noqa: E402
from boringbar.analysis.sweep import Case, SweepOptions, published_cases, sweep  # noqa: E402
from boringbar.execute import Execution  # noqa: E402
from boringbar.model.bar import ModalModel, Section, SteppedBar, published_bar  # noqa: E402
from boringbar.model.dampers import (  # noqa: E402
    Friction,
    ImpactDamper,
    TunedMassDamper,
    den_hartog_parameters,
    sims_tuning,
)
from boringbar.model.forcing import Harmonic, Regenerative  # noqa: E402
from boringbar.model.system import PRESETS, READINGS, System, make_system  # noqa: E402
from boringbar.reference.linear import min_real_part, tip_frf  # noqa: E402
from boringbar.simulate import Initial, Integration, IntegrationError, Run, State, simulate  # noqa: E402
from boringbar.studies.load import load_study  # noqa: E402
from boringbar.studies.runner import run_study  # noqa: E402

__all__ = [
    "PRESETS",
    "READINGS",
    "BasinOptions",
    "BifurcationOptions",
    "Case",
    "ContinuationOptions",
    "Cuts",
    "Execution",
    "Friction",
    "Harmonic",
    "ImpactDamper",
    "Initial",
    "Integration",
    "IntegrationError",
    "LobesOptions",
    "ModalModel",
    "ParameterError",
    "Regenerative",
    "Run",
    "Section",
    "SensitivityOptions",
    "State",
    "SteppedBar",
    "SweepOptions",
    "System",
    "TunedMassDamper",
    "basins",
    "bifurcation",
    "continuation",
    "den_hartog_parameters",
    "load_study",
    "lobes",
    "make_system",
    "min_real_part",
    "poincare_map",
    "published_bar",
    "published_cases",
    "run_study",
    "sensitivity",
    "simulate",
    "sims_tuning",
    "sweep",
    "tip_frf",
]
