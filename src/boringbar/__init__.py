"""boringbar: vibration and chatter of impact-damped boring bars.

Public names only (``import boringbar as bb``); docs/architecture.md shows the
layers behind them.

- Descriptions: :class:`SteppedBar`, :class:`ModalModel`, :class:`ImpactDamper`,
  :class:`Friction`, :class:`TunedMassDamper`, :class:`System` and
  :func:`make_system` (the two presets); your own bar: :func:`load_system`
  (system files) -> :class:`SystemSpec`, :func:`describe_modes`, :class:`ModalFit`
  (a fitted tip FRF); forcing: :class:`Harmonic`,
  :class:`Regenerative`.
- One run: :func:`simulate` -> :class:`Run`.
- Analyses: :func:`sweep`, :func:`lobes`, :func:`bifurcation`, :func:`basins`,
  :func:`sensitivity`, :func:`poincare_map`; design search: :func:`design`
  (:class:`DesignOptions`, :class:`Variable`, :class:`Uncertain`, :func:`load_design`).
- Closed-form references: :func:`tip_frf`, :func:`min_real_part`,
  :func:`sims_tuning`, :func:`den_hartog_parameters`.
- Study files: :func:`load_study`, :func:`run_study`.
"""

__version__ = "0.1.0"

import importlib  # noqa: E402

from boringbar._validate import ParameterError  # noqa: E402
from boringbar.analysis.basins import BasinOptions, basins  # noqa: E402
from boringbar.analysis.bifurcation import BifurcationOptions, bifurcation  # noqa: E402
from boringbar.analysis.continuation import ContinuationOptions, continuation  # noqa: E402
from boringbar.analysis.design_options import DesignOptions, Uncertain, Variable  # noqa: E402
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
from boringbar.model.modal_fit import ModalFit  # noqa: E402
from boringbar.model.system import (  # noqa: E402
    PRESETS,
    READINGS,
    System,
    describe_modes,
    make_system,
)
from boringbar.model.system_file import SystemSpec, load_system  # noqa: E402
from boringbar.reference.linear import min_real_part, tip_frf  # noqa: E402
from boringbar.simulate import Initial, Integration, IntegrationError, Run, State, simulate  # noqa: E402
from boringbar.studies.load import load_study  # noqa: E402
from boringbar.studies.runner import run_study  # noqa: E402

#: names loaded on first use, with the module that holds them: the design search imports
#: Optuna, the figures matplotlib, neither of which a simulation needs
_LAZY = {"design": "boringbar.analysis.design", "load_design": "boringbar.analysis.design_file",
         "plot": "boringbar.plot"}


def __getattr__(name: str):
    if name not in _LAZY:
        raise AttributeError(f"module 'boringbar' has no attribute {name!r}")
    module = importlib.import_module(_LAZY[name])
    value = module if name == "plot" else getattr(module, name)
    globals()[name] = value
    return value


__all__ = [
    "PRESETS",
    "READINGS",
    "BasinOptions",
    "BifurcationOptions",
    "Case",
    "ContinuationOptions",
    "Cuts",
    "DesignOptions",
    "Execution",
    "Friction",
    "Harmonic",
    "ImpactDamper",
    "Initial",
    "Integration",
    "IntegrationError",
    "LobesOptions",
    "ModalFit",
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
    "SystemSpec",
    "TunedMassDamper",
    "Uncertain",
    "Variable",
    "basins",
    "bifurcation",
    "continuation",
    "den_hartog_parameters",
    "describe_modes",
    "design",
    "load_design",
    "load_study",
    "load_system",
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
