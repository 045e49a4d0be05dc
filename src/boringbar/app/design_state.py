"""What the design page holds: one design, a system file's description (a dict in the
file's own units, mm, g, kg) with the run settings, each change checked exactly as
the command line checks it.

A control of the bar or its damper edits the description, which
:func:`~boringbar.model.system_file.parse_system` then reads as it reads a file, so a
value out of range gets the message ``boringbar modes --system FILE`` would print for
that file; a run setting goes through the command line's own checks of ``--force-n``,
``--ratio``, ``--rpm`` and ``--depth-mm``.  A design is immutable: every change makes
a new one, so a pinned design can never change under the user.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field, replace
from functools import cached_property

import tomli_w

from boringbar._validate import ParameterError, check_choice, check_range
from boringbar.model.forcing import Harmonic, Regenerative, check_depth, check_force, check_ratio
from boringbar.model.materials import MATERIALS
from boringbar.model.system import PRESETS, System, variants
from boringbar.model.system_file import FRICTION_FORMS, SystemSpec, cavity_moved, parse_system
from boringbar.simulate import INTEGRATOR_CHOICES
from boringbar.simulate.run_limits import check_delay

#: the run's step (s): the command line's default --dt-s
DT_S = 1e-6
#: how long a page run lasts (s): long enough for a steady pattern at the published
#: bar's 461-525 Hz (the last half is the steady part), short enough to redraw at once
RUN_S = 1.0
#: the description's keys a control edits: key -> (label, unit)
FIELDS = {
    "ball.gap_mm": ("gap", "mm"),
    "ball.material": ("ball material", ""),
    "ball.diameter_mm": ("ball diameter", "mm"),
    "ball.restitution": ("restitution", ""),
    "ball.friction": ("friction", ""),
    "cavity.position_mm": ("cavity position", "mm"),
    "tmd.mass_kg": ("TMD mass", "kg"),
    "tmd.tuning": ("TMD tuning", ""),
    "tmd.stiffness_n_m": ("TMD stiffness", "N/m"),
    "tmd.damping_n_s_m": ("TMD damping", "N s/m"),
}
TUNINGS = ("den-hartog", "sims", "given")
FORCINGS = ("harmonic", "cut")


@dataclass(frozen=True)
class Settings:
    """How the design is run: ``preset`` and ``integrator`` (as on the command line),
    ``forcing`` "harmonic" (``force_n`` N at ``ratio`` = Omega/omega_n) or "cut"
    (``rpm``, ``depth_mm``)."""

    preset: str = "physical"
    integrator: str = "auto"
    forcing: str = "harmonic"
    force_n: float = 20.0
    ratio: float = 1.0
    rpm: float = 1200.0
    depth_mm: float = 0.05

    def __post_init__(self):
        check_choice("--preset", self.preset, PRESETS)
        check_choice("--integrator", self.integrator, INTEGRATOR_CHOICES)
        check_choice("forcing", self.forcing, FORCINGS)
        check_force(self.force_n)
        check_ratio(self.ratio)
        check_delay(self.rpm, 3, DT_S, "--rpm")
        check_depth(self.depth_mm, "--depth-mm")


@dataclass(frozen=True, eq=False)
class Design:
    """A checked system description (``data``, the file's units; ``spec`` as read from
    it; ``name``) and its run ``settings``."""

    spec: SystemSpec
    settings: Settings = field(default_factory=Settings)

    @classmethod
    def of(cls, spec: SystemSpec, settings: Settings | None = None) -> Design:
        return cls(spec, settings or Settings())

    @property
    def data(self) -> dict:
        return self.spec.to_dict()

    @property
    def name(self) -> str:
        return self.spec.name

    def with_value(self, key: str, value) -> Design:
        """The design with the description's ``key`` (one of :data:`FIELDS`) set to
        ``value``; a ParameterError (the system file's message) if it cannot be."""
        return self.with_values({key: value})

    def with_values(self, changes: dict) -> Design:
        """The design with every ``key: value`` of ``changes`` set (:meth:`with_value`),
        checked together: the file is read once, after all of them."""
        data = self.data
        for key, value in changes.items():
            check_choice("control", key, tuple(FIELDS))
            data = edited(data, key, value)
        return replace(self, spec=parse_system(data, f"{self.name}.toml"))

    def with_settings(self, **changes) -> Design:
        """The design run another way; its bars are this one's unless the preset
        changes (they are built once: the views share them)."""
        new = replace(self, settings=replace(self.settings, **changes))
        if new.settings.preset == self.settings.preset and "systems" in self.__dict__:
            new.__dict__["systems"] = self.__dict__["systems"]  # cached_property's slot
        return new

    def value(self, key: str):
        """The description's value at ``key`` (None where the file has no such part)."""
        table, name = key.split(".")
        return self.data.get(table, {}).get(name)

    @cached_property
    def systems(self) -> dict[str, System]:
        """The bars this file describes under the preset: solid always, ball with a
        ball, tmd with an absorber (labels are the bar kinds); built once per design
        (the views share them)."""
        return variants(self.spec, self.settings.preset)

    def forcing(self) -> Harmonic | Regenerative:
        s = self.settings
        if s.forcing == "harmonic":
            return Harmonic(amplitude_n=s.force_n, ratio=s.ratio)
        return self.cut()

    def cut(self) -> Regenerative:
        """The design's cut (its lobes' too, whichever forcing the run takes)."""
        s = self.settings
        return Regenerative(depth_m=s.depth_mm * 1e-3, rpm=s.rpm)

    def toml(self) -> str:
        """The design as a system file (what Export writes)."""
        data = self.data
        data["description"] = data.get("description") or "exported from boringbar app"
        return tomli_w.dumps(_without_none(data))


def edited(data: dict, key: str, value) -> dict:
    """A copy of the description ``data`` with ``key`` set: a new ball material or
    diameter drops a given ``mass_g`` (the mass then follows from the density); a
    cavity moved merges the sections around it first (:func:`cavity_moved`); the
    friction is ``(form, value)`` with form one of FRICTION_FORMS."""
    data = copy.deepcopy(data)
    table, name = key.split(".")
    if table not in data:
        raise ParameterError(f"{key}: this system has no [{table}] to change")
    if key == "cavity.position_mm":
        return cavity_moved(data, _number(key, value))
    if key == "ball.friction":
        form, amount = value
        check_choice("friction", form, tuple(FRICTION_FORMS))
        kept = {k: v for k, v in data["ball"]["friction"].items() if k not in FRICTION_FORMS}
        data["ball"]["friction"] = {form: True if form == "none" else _number(key, amount),
                                    **kept}
        return data
    if name in ("material", "tuning"):
        check_choice(FIELDS[key][0], value, tuple(MATERIALS) if name == "material" else TUNINGS)
    else:
        value = _number(key, value)
    if name in ("material", "diameter_mm"):
        data["ball"].pop("mass_g", None)
    data[table][name] = value
    return data


def _number(key: str, value) -> float:
    """A control's number as the file would hold it (anything else: a clear error)."""
    return check_range(key, value, -math.inf, math.inf, lo_open=True, hi_open=True)


def _without_none(d):
    if isinstance(d, dict):
        return {k: _without_none(v) for k, v in d.items() if v is not None}
    if isinstance(d, list):
        return [_without_none(v) for v in d]
    return d
