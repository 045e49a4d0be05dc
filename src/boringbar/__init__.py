"""boringbar: vibration and chatter of impact-damped boring bars.

Public names only (``import boringbar as bb``); docs/architecture.md shows the
layers behind them.

- Descriptions: :class:`SteppedBar`, :class:`ModalModel`, :class:`ImpactDamper`,
  :class:`Friction`, :class:`TunedMassDamper`, :class:`System` and
  :func:`make_system` (the two presets), :func:`variants` (the solid, ball and TMD
  bars of one system file, side by side); your own bar: :func:`load_system`
  (system files; :func:`loads_system` their text, :func:`parse_system` a dict of the
  same keys) -> :class:`SystemSpec`, :func:`describe_modes`, :class:`ModalFit`
  (a fitted tip FRF); forcing: :class:`Harmonic`,
  :class:`Regenerative` and its :class:`CuttingLaw`.
- One run: :func:`simulate` -> :class:`Run`.
- Analyses: :func:`sweep`, :func:`lobes` (a boring job's speeds:
  :func:`boring_speeds`; the chance of chatter: :class:`Uncertainty`),
  :func:`chatter_map` (the settled vibration at every speed and depth,
  :class:`ChatterMapOptions`), :func:`bifurcation`, :func:`basins`, :func:`sensitivity`,
  :func:`poincare_map`; design search: :func:`design` (:class:`DesignOptions`,
  :class:`Variable`, :class:`Uncertain`, :func:`load_design`).
- Closed-form references: :func:`tip_frf`, :func:`min_real_part`,
  :func:`sims_tuning`, :func:`den_hartog_parameters`.
- Study files: :func:`load_study`, :func:`run_study`.
- The design page in a notebook: :func:`app` (``pip install 'boringbar[app]'``).
"""

import importlib

from boringbar._validate import ParameterError

# eager, since the module of the same name would otherwise shadow the function once
# anything imported it
from boringbar.simulate import (
    Initial,
    Integration,
    IntegrationError,
    Run,
    State,
    simulate,
)
from boringbar.version import __version__  # noqa: F401 (the package's version)

#: every public name with the module that holds it, imported on first use: a command
#: or a script then loads only what it needs (a simulation no optimiser, study runner
#: or figure library)
_HOMES = {
    "boringbar.analysis.basins": ("BasinOptions", "basins"),
    "boringbar.analysis.bifurcation": ("BifurcationOptions", "bifurcation"),
    "boringbar.analysis.chatter_probability": ("Uncertainty",),
    "boringbar.analysis.chatter_map": ("ChatterMapOptions", "chatter_map"),
    "boringbar.analysis.cases": ("Case", "published_cases"),
    "boringbar.analysis.continuation": ("ContinuationOptions", "continuation"),
    "boringbar.analysis.cut_continuation": ("CutContinuationOptions", "cut_continuation"),
    "boringbar.analysis.design": ("design",),
    "boringbar.analysis.design_file": ("load_design",),
    "boringbar.analysis.design_options": ("DesignOptions", "Uncertain", "Variable"),
    "boringbar.analysis.lobes": ("LobesOptions", "lobes"),
    "boringbar.analysis.speeds": ("boring_speeds",),
    "boringbar.analysis.poincare": ("poincare_map",),
    "boringbar.analysis.sensitivity": ("Cuts", "SensitivityOptions", "sensitivity"),
    "boringbar.analysis.sweep": ("SweepOptions", "sweep"),
    "boringbar.execute": ("Execution",),
    "boringbar.model.bar": ("ModalModel", "Section", "SteppedBar", "published_bar"),
    "boringbar.model.dampers": ("Friction", "ImpactDamper", "TunedMassDamper",
                                "den_hartog_parameters", "sims_tuning"),
    "boringbar.model.cutting": ("CuttingLaw",),
    "boringbar.model.forcing": ("Harmonic", "Regenerative"),
    "boringbar.model.modal_fit": ("ModalFit",),
    "boringbar.model.oriented": ("CutGeometry",),
    "boringbar.model.system": ("PRESETS", "READINGS", "System", "describe_modes",
                               "make_system", "variants"),
    "boringbar.model.system_file": ("SystemSpec", "load_system", "loads_system",
                                    "parse_system"),
    "boringbar.reference.linear": ("min_real_part", "tip_frf"),
    "boringbar.studies.load": ("load_study",),
    "boringbar.studies.runner": ("run_study",),
    "boringbar.app.server": ("design_page", "serve"),
}
_LAZY = {name: module for module, names in _HOMES.items() for name in names}


def __getattr__(name: str):
    if name == "plot":
        value = importlib.import_module("boringbar.plot")
    elif name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
    else:
        raise AttributeError(f"module 'boringbar' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY, "plot"])


__all__ = [
    "PRESETS",
    "READINGS",
    "BasinOptions",
    "BifurcationOptions",
    "Case",
    "ChatterMapOptions",
    "ContinuationOptions",
    "CutContinuationOptions",
    "CutGeometry",
    "CuttingLaw",
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
    "Uncertainty",
    "Variable",
    "basins",
    "bifurcation",
    "boring_speeds",
    "chatter_map",
    "continuation",
    "cut_continuation",
    "den_hartog_parameters",
    "describe_modes",
    "design",
    "design_page",
    "load_design",
    "load_study",
    "load_system",
    "loads_system",
    "lobes",
    "make_system",
    "min_real_part",
    "parse_system",
    "poincare_map",
    "published_bar",
    "published_cases",
    "run_study",
    "sensitivity",
    "serve",
    "simulate",
    "sims_tuning",
    "sweep",
    "tip_frf",
    "variants",
]
