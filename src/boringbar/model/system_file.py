"""System files: any impact-damped or tuned-mass-damped boring bar, described in TOML.

A system file describes the bar (sections along it, each with an outer diameter
and an optional coolant bore; a named material or E and density; damping; the
clamp), the cavity and its ball (position, size, material or mass, gap,
restitution, friction) and a tuned mass damper (mass, position, tuning).  Every
key carries its unit in its name; docs/systems.md lists each key with its unit,
default and range.  The published bar is such a file, shipped with the package
(``published.toml`` beside this module), and the presets of
:func:`~boringbar.model.system.make_system` build from it.

:func:`load_system` reads and checks a file into a :class:`SystemSpec`; every
error is one line naming the file, the key, the value and what is allowed.
:meth:`SystemSpec.to_dict` is the resolved description (every default filled
in), which results carry in their attributes; :func:`parse_system` of it
rebuilds the same spec.
"""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path

from boringbar._validate import ParameterError, in_range, near, read_toml
from boringbar.model.bar import MAX_ELEMENTS, ModalModel, Section, SteppedBar
from boringbar.model.cavity_section import cavity_section_diameter
from boringbar.model.contact import CONTACT_LAWS, HERTZ_MIN_RESTITUTION
from boringbar.model.dampers import (
    BALL_MOTIONS,
    MAX_FRICTION_FORCE,
    MAX_GAP,
    MU_KINETIC,
    MU_MAX,
    MU_STATIC,
)
from boringbar.model.materials import MATERIALS
from boringbar.model.oriented import GEOMETRY_RANGES, CutGeometry

#: The file the presets build from.
PUBLISHED_FILE = "published.toml"
#: the name the published bar's file gives itself
PUBLISHED_NAME = "published"
TUNINGS = ("den-hartog", "sims", "given")
#: The forms a ball's friction may take (one per file): key -> Friction kind.
FRICTION_FORMS = {"published_number": "published-number", "rolling_mm": "rolling",
                  "coulomb": "coulomb", "force_n": "force", "none": "none"}
REACTIONS = ("reciprocal", "printed")
_TOP_KEYS = ("name", "description", "bar", "clamp", "cavity", "ball", "tmd", "paper",
             "orientation")


class SystemFileError(ParameterError):
    """A system file that cannot describe a bar; the message is one line:
    ``FILE: key 'a.b' = VALUE: what is allowed``."""


@dataclass(frozen=True)
class CavitySpec:
    """The ball's cavity: its centre ``position_m`` (from the clamp), its
    ``length_m`` along the bar, the ``section_diameter_m`` of the solid round
    section with the bar's stiffness through it (its ``section_bore_m`` kept from
    the host section), and its ``depth_m`` in the direction the ball travels."""

    position_m: float
    length_m: float
    section_diameter_m: float
    section_bore_m: float
    depth_m: float


@dataclass(frozen=True)
class BallSpec:
    """The ball (``material``, ``diameter_m``, ``mass_kg`` or None: from the
    density) and its behaviour: ``gap_m``, ``restitution``, friction
    (``friction_kind`` one of FRICTION_FORMS's values, ``friction_value`` in
    its unit, ``friction_reaction`` or None: the preset's, ``static_ratio``) and how it
    meets the plugs: ``contact`` ("impact" or "hertz"), ``contact_stiffness_n_m1_5``
    (N/m^1.5, or None: Hertz's from the materials) and ``plug_material``; how it moves:
    ``motion`` ("slide" or "roll") with ``mu_static`` and ``mu_kinetic``."""

    material: str
    diameter_m: float
    mass_kg: float | None
    gap_m: float
    restitution: float
    friction_kind: str
    friction_value: float
    friction_reaction: str | None
    static_ratio: float
    contact: str = "impact"
    contact_stiffness_n_m1_5: float | None = None
    plug_material: str = "steel"
    motion: str = "slide"
    mu_static: float = MU_STATIC
    mu_kinetic: float = MU_KINETIC


@dataclass(frozen=True)
class TmdSpec:
    """A tuned mass damper: ``mass_kg`` at ``position_m`` (from the clamp),
    ``tuning`` (den-hartog, sims, given) and the given ``stiffness_n_m`` and
    ``damping_n_s_m``, or None; ``label`` names the given design in results."""

    mass_kg: float
    position_m: float
    tuning: str
    stiffness_n_m: float | None
    damping_n_s_m: float | None
    label: str


@dataclass(frozen=True, eq=False)
class SystemSpec:
    """A resolved system file (SI units).  ``bar`` is the host bar without the
    cavity (the solid and TMD bars); ``cavity``, ``ball``, ``tmd`` may be None;
    ``damping_ratio`` one ratio per mode (a 1-tuple applies to all); ``n_modes`` None:
    the preset's; ``calibration``: f1 (Hz) by bar ("ball", "solid") that the
    paper preset calibrates to; ``name``: the bar's name; ``data``: the resolved description
    (:meth:`to_dict`); ``source``: the file; ``planes``: 1, or 2 for the bar's modes in both
    bending planes under the oriented cut ``orientation`` (a CutGeometry; the file's
    ``[orientation]``)."""

    bar: SteppedBar
    damping_ratio: tuple[float, ...]
    n_modes: int | None
    cavity: CavitySpec | None
    ball: BallSpec | None
    tmd: TmdSpec | None
    calibration: dict
    name: str
    data: dict = field(repr=False)
    source: str = "<dict>"
    #: the bending planes (1: the published one direction; 2: docs/model.md, section
    #: 4.7) and the oriented cut's geometry
    planes: int = 1
    orientation: CutGeometry = field(default_factory=CutGeometry)

    @property
    def ball_position_m(self) -> float:
        """z_d (m): the cavity's centre (the bar's tip if there is no cavity)."""
        return self.cavity.position_m if self.cavity else self.bar.length_m

    @property
    def absorber_position_m(self) -> float:
        """z_a (m): the absorber's position (the bar's tip if there is none)."""
        return self.tmd.position_m if self.tmd else self.bar.length_m

    def stepped_bar(self, cavity: bool, across: bool = False) -> SteppedBar:
        """The FE bar: with the cavity's section (``cavity``) or without; ``across``: bent
        in the second plane (the cavity's section across the ball's direction, and the
        sections' second moments of the second plane where they give their own)."""
        bar = self.bar.in_plane(1) if across and self.bar.plane_moments else self.bar
        if not cavity or self.cavity is None:
            return bar
        return _with_cavity(bar, self.cavity, across)

    def modal(self, cavity: bool, n_modes: int,
              z_absorber_m: float | None = None, across: bool = False) -> ModalModel:
        """The modal model of :meth:`stepped_bar`, ``n_modes`` retained, psi at the
        ball and at the absorber (``z_absorber_m`` m, default the file's); ``across``:
        bending across the ball's direction."""
        za = self.absorber_position_m if z_absorber_m is None else z_absorber_m
        model = self.stepped_bar(cavity, across).modal_model(n_modes, self.ball_position_m,
                                                             za)
        if len(self.damping_ratio) == 1:
            return model
        ratios = [self.damping_ratio[min(i, len(self.damping_ratio) - 1)] for i in range(n_modes)]
        return replace(model, damping_ratio=ratios)

    def mode_shapes(self, cavity: bool, n_modes: int):
        """(z m of the FE nodes, deflection shapes (nodes, n) divided by their tip
        value, frequencies Hz) of :meth:`stepped_bar`."""
        omegas, nodes, shapes = self.stepped_bar(cavity).modes(
            n_modes, (self.ball_position_m, self.absorber_position_m))
        return nodes, shapes / shapes[-1, :], omegas / (2 * math.pi)

    def max_gap(self) -> float:
        """The largest gap (m) the cavity allows: its depth less the ball's
        diameter, and at most the model's MAX_GAP."""
        if self.cavity is None or self.ball is None:
            return MAX_GAP
        return min(MAX_GAP, self.cavity.depth_m - self.ball.diameter_m)

    def to_dict(self) -> dict:
        """The resolved description (JSON-able; every default filled in)."""
        return json.loads(json.dumps(self.data))


def load_system(path) -> SystemSpec:
    """Read and check the TOML system file ``path``."""
    return parse_system(read_toml(path, SystemFileError, "system file"), str(path))


def loads_system(text: str, source: str) -> SystemSpec:
    """A system file's text (``source`` names it in messages), checked as
    :func:`load_system` checks the file."""
    try:
        d = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SystemFileError(f"{source}: not valid TOML: {exc}") from None
    return parse_system(d, source)


def merged_sections(sections: list[dict]) -> list[dict]:
    """A description's sections (dicts with end_mm, diameter_mm, bore_mm and maybe
    second_moments_mm4, area_mm2) with neighbours of one shape merged: the spans a
    cavity may move along."""
    def shape(s: dict) -> tuple:
        return (s["diameter_mm"], s.get("bore_mm", 0.0), s.get("second_moments_mm4"),
                s.get("area_mm2"))

    merged = []
    for s in sections:
        if merged and shape(merged[-1]) == shape(s):
            merged[-1] = dict(merged[-1], end_mm=s["end_mm"])
        else:
            merged.append(dict(s))
    return merged


def cavity_moved(data: dict, position_mm: float) -> dict:
    """The system description ``data`` (changed in place and returned) with the cavity
    at ``position_mm``; its sections merged first (:func:`merged_sections`), so the
    cavity may move along a span of one diameter."""
    data["bar"]["sections"] = merged_sections(data["bar"]["sections"])
    data["cavity"]["position_mm"] = position_mm
    return data


def published_system() -> SystemSpec:
    """The published bar, from the file shipped with the package."""
    return parse_system(tomllib.loads(published_file_text()), PUBLISHED_FILE)


def published_file_text() -> str:
    """The shipped published system file, as text."""
    return resources.files("boringbar.model").joinpath(PUBLISHED_FILE).read_text()


# --- reading -------------------------------------------------------------------------

class _Reader:
    """Checks keys of one file, failing with one line: file, key, value, allowed."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, key: str, value, allowed: str):
        shown = repr(value) if isinstance(value, str) else json.dumps(value, default=str)
        raise SystemFileError(f"{self.source}: key '{key}' = {shown}: {allowed}")

    def table(self, value, key: str, allowed: tuple) -> dict:
        """``value`` (the table at ``key``), its keys checked against ``allowed``."""
        if not isinstance(value, dict):
            self.fail(key, value, "must be a table")
        for k in value:
            if k not in allowed:
                self.fail(f"{key}.{k}", value[k], "unknown key; allowed: " + ", ".join(allowed))
        return value

    def number(self, d: dict, key: str, lo: float, hi: float = math.inf, *, default=None,
               lo_open: bool = False, hi_open: bool = False, unit: str = "") -> float | None:
        name = key.rsplit(".", 1)[-1]
        if name not in d:
            return default
        value = d[name]
        ok = isinstance(value, int | float) and not isinstance(value, bool)
        if ok:
            v = float(value)
            ok = math.isfinite(v) and in_range(v, lo, hi, lo_open, hi_open)
        if not ok:
            left, right = "(" if lo_open else "[", ")" if hi_open or hi == math.inf else "]"
            self.fail(key, value, f"must be a number in {left}{lo:g}, {hi:g}{right}"
                                  + (f" {unit}" if unit else ""))
        return float(value)

    def required(self, d: dict, key: str, *args, **kw) -> float:
        if key.rsplit(".", 1)[-1] not in d:
            self.fail(key, None, "is required")
        return self.number(d, key, *args, **kw)

    def choice(self, d: dict, key: str, choices, default=None):
        name = key.rsplit(".", 1)[-1]
        if name not in d:
            return default
        value = d[name]
        # true == 1 and 2.0 == 2 in Python, but neither is the whole number a key asks for
        if not any(value == c and type(value) is type(c) for c in choices):
            self.fail(key, value, "must be one of " + ", ".join(map(repr, choices)))
        return value

    def text(self, d: dict, key: str, default: str) -> str:
        name = key.rsplit(".", 1)[-1]
        value = d.get(name, default)
        if not isinstance(value, str):
            self.fail(key, value, "must be a string")
        return value


def parse_system(d: dict, source: str = "<dict>") -> SystemSpec:
    """Check the system description ``d`` (a system file's tables as a dict: docs/
    systems.md) into a SystemSpec; ``source`` names it in messages."""
    r = _Reader(source)
    if not isinstance(d, dict):
        raise SystemFileError(f"{source}: a system file is a table, not {type(d).__name__}")
    for k in d:
        if k not in _TOP_KEYS:
            r.fail(k, d[k], "unknown key; allowed: " + ", ".join(_TOP_KEYS))
    if "bar" not in d:
        r.fail("bar", None, "is required: the bar's sections and material")
    bar, damping, n_modes, bar_data = _bar(r, d)
    cavity, cav_data = _cavity(r, d, bar)
    ball, ball_data = _ball(r, d, bar, cavity)
    tmd, tmd_data = _tmd(r, d, bar)
    calibration = _paper(r, d)
    planes, orientation, orient_data = _orientation(r, d)
    if bar.plane_moments and orientation.stiffness_ratio != 1.0:
        r.fail("orientation.stiffness_ratio", orientation.stiffness_ratio, "the sections give "
               "each plane's second moments (second_moments_mm4): leave stiffness_ratio out")
    name = r.text(d, "name", Path(source).stem if source not in ("<dict>", "") else "system")
    data = {"name": name, "description": r.text(d, "description", ""), **bar_data,
            **cav_data, **ball_data, **tmd_data, **orient_data}
    if calibration:
        data["paper"] = {f"first_frequency_hz_{k}": v for k, v in calibration.items()}
    return SystemSpec(bar, damping, n_modes, cavity, ball, tmd, calibration, name, data,
                      source, planes, orientation)


_ORIENTATION_KEYS = ("planes", "force_ratio", "lead_angle_deg", "hole_angle_deg",
                     "principal_angle_deg", "stiffness_ratio")


def _orientation(r: _Reader, d: dict):
    """[orientation]: the bending planes and the oriented cut (model/oriented.py)."""
    if "orientation" not in d:
        return 1, CutGeometry(), {}
    t = r.table(d["orientation"], "orientation", _ORIENTATION_KEYS)
    planes = r.choice(t, "orientation.planes", (1, 2), default=2)
    defaults = CutGeometry()
    values = {}
    for key, (lo, hi, lo_open, hi_open, unit, why) in GEOMETRY_RANGES.items():
        values[key] = r.number(t, f"orientation.{key}", lo, hi, lo_open=lo_open,
                               hi_open=hi_open, default=getattr(defaults, key),
                               unit=f"{unit} ({why})" if why else unit)
    given = [k for k in GEOMETRY_RANGES if k in t]
    if planes == 1 and given:
        r.fail("orientation.planes", 1, f"an oriented cut ({', '.join(given)}) acts on two "
               "bending planes: give planes = 2 (or leave it out)")
    geometry = CutGeometry(**values)
    return planes, geometry, {"orientation": {"planes": planes, **geometry.to_dict()}}


_BAR_KEYS = ("material", "youngs_modulus_gpa", "density_kg_m3", "damping_ratio", "modes",
             "element_length_mm", "sections")
_SECTION_KEYS = ("end_mm", "diameter_mm", "bore_mm", "second_moments_mm4", "area_mm2")
_CLAMP_KEYS = ("translational_stiffness_n_m", "rotational_stiffness_n_m_per_rad")


def _material(r: _Reader, t: dict) -> tuple[float, float, str | None]:
    name = r.choice(t, "bar.material", tuple(MATERIALS))
    e, rho = t.get("youngs_modulus_gpa"), t.get("density_kg_m3")
    if name is not None and (e is not None or rho is not None):
        r.fail("bar.material", name, "give a material name or youngs_modulus_gpa and "
                                     "density_kg_m3, not both")
    if name is not None:
        m = MATERIALS[name]
        return m.youngs_modulus, m.density, name
    if e is None or rho is None:
        r.fail("bar.material", None, "give a material (" + ", ".join(MATERIALS)
               + ") or both youngs_modulus_gpa and density_kg_m3")
    return (r.number(t, "bar.youngs_modulus_gpa", 0, 2000, lo_open=True, unit="GPa") * 1e9,
            r.number(t, "bar.density_kg_m3", 0, 30_000, lo_open=True, unit="kg/m^3"), None)


def _sections(r: _Reader, t: dict) -> tuple[Section, ...]:
    rows = t.get("sections")
    if not isinstance(rows, list) or not rows:
        r.fail("bar.sections", rows, "is required: a list of tables [[bar.sections]] with "
                                     "end_mm, diameter_mm and optional bore_mm")
    sections, start, data = [], 0.0, []
    for i, row in enumerate(rows):
        key = f"bar.sections[{i}]"
        if not isinstance(row, dict):
            r.fail(key, row, "must be a table with end_mm, diameter_mm, bore_mm")
        r.table(row, key, _SECTION_KEYS)
        end = r.required(row, f"{key}.end_mm", start * 1e3, 10_000, lo_open=True, unit="mm")
        dia = r.required(row, f"{key}.diameter_mm", 0, 1000, lo_open=True, unit="mm")
        bore = r.number(row, f"{key}.bore_mm", 0, dia, default=0.0, hi_open=True, unit="mm")
        round_section = Section(start, end / 1000, dia / 1000, bore / 1000)
        moments, area = _section_shape(r, row, key, round_section)
        sections.append(replace(
            round_section,
            given_moments_m4=None if moments is None else tuple(m * 1e-12 for m in moments),
            given_area_m2=None if area is None else area * 1e-6))
        data.append({"end_mm": end, "diameter_mm": dia, "bore_mm": bore}
                    | ({"second_moments_mm4": list(moments)} if moments else {})
                    | ({"area_mm2": area} if area is not None else {}))
        start = end / 1000
    return tuple(sections), data


def _section_shape(r: _Reader, row: dict, key: str, round_section: Section):
    """A section's own second moments a plane (mm^4) and area (mm^2), as the file gives
    them, each None where the row leaves them to its round shape: at most the round
    section's (flats and an off-centre bore only take material away)."""
    moments = row.get("second_moments_mm4")
    top = round_section.round_moment_m4 * 1e12
    if moments is not None:
        if not isinstance(moments, list) or len(moments) != 2:
            r.fail(f"{key}.second_moments_mm4", moments, "must be two second moments of "
                   "area (mm^4): [first plane, second plane]")
        moments = tuple(r.number({f"second_moments_mm4[{k}]": m},
                                 f"{key}.second_moments_mm4[{k}]", 0, top, lo_open=True,
                                 unit="mm^4 (at most the round section's)")
                        for k, m in enumerate(moments))
    area = r.number(row, f"{key}.area_mm2", 0, round_section.round_area_m2 * 1e6, lo_open=True,
                    unit="mm^2 (at most the round section's)")
    return moments, area


def _bar(r: _Reader, d: dict):
    t = r.table(d["bar"], "bar", _BAR_KEYS)
    e, rho, material = _material(r, t)
    sections, section_data = _sections(r, t)
    damping = t.get("damping_ratio", 0.01)
    ratios = damping if isinstance(damping, list) else [damping]
    if not ratios:
        r.fail("bar.damping_ratio", damping, "one ratio in [0, 1), or a list per mode")
    for i, z in enumerate(ratios):
        r.number({"damping_ratio": z}, "bar.damping_ratio" + (f"[{i}]" if len(ratios) > 1
                                                              else ""), 0, 1, hi_open=True)
    modes = t.get("modes")
    if modes is not None and (isinstance(modes, bool) or not isinstance(modes, int)
                              or not 1 <= modes <= 8):
        r.fail("bar.modes", modes, "must be a whole number in [1, 8]")
    h = r.number(t, "bar.element_length_mm", 0, 1000, default=5.0, lo_open=True, unit="mm")
    c = r.table(d.get("clamp", {}), "clamp", _CLAMP_KEYS)
    kt = r.number(c, "clamp.translational_stiffness_n_m", 0, 1e14, default=math.inf,
                  lo_open=True, unit="N/m")
    kr = r.number(c, "clamp.rotational_stiffness_n_m_per_rad", 0, 1e14, default=math.inf,
                  lo_open=True, unit="N m/rad")
    length_mm = sections[-1].end_m * 1000
    if h < length_mm / MAX_ELEMENTS:
        r.fail("bar.element_length_mm", h, f"must be at least {length_mm / MAX_ELEMENTS:.3g} "
               f"mm: the {length_mm:g} mm bar in at most {MAX_ELEMENTS} elements")
    bar = SteppedBar(sections, e, rho, float(ratios[0]), h / 1000, kt, kr)
    data = {"bar": {"material": material, "youngs_modulus_gpa": e / 1e9,
                    "density_kg_m3": rho, "damping_ratio": [float(z) for z in ratios],
                    "modes": modes, "element_length_mm": h,
                    "sections": section_data},
            "clamp": {k: v for k, v in (("translational_stiffness_n_m", kt),
                                        ("rotational_stiffness_n_m_per_rad", kr))
                      if v != math.inf}}
    if material is None:
        del data["bar"]["material"]
    else:
        del data["bar"]["youngs_modulus_gpa"], data["bar"]["density_kg_m3"]
    if modes is None:
        del data["bar"]["modes"]
    return bar, tuple(float(z) for z in ratios), modes, data


_CAVITY_KEYS = ("position_mm", "length_mm", "section_diameter_mm", "depth_mm")
def _within(lo: float, hi: float, start: float, end: float, length: float) -> bool:
    """Whether [lo, hi] lies in [start, end] (m, on a bar ``length`` long; the ends
    computed from mm are equal up to round-off: :func:`~boringbar._validate.in_range`)."""
    return (in_range(lo, start, end, scale=length)
            and in_range(hi, start, end, scale=length))


def _host_section(r: _Reader, bar: SteppedBar, lo: float, hi: float, z: float) -> Section:
    """The one section holding [lo, hi] (m), or a one-line error."""
    if not _within(lo, hi, 0.0, bar.length_m, bar.length_m):
        r.fail("cavity.position_mm", z * 1e3,
               f"the cavity spans [{lo * 1e3:g}, {hi * 1e3:g}] mm, outside the bar "
               f"[0, {bar.length_m * 1e3:g}] mm")
    for s in bar.sections:
        if _within(lo, hi, s.start_m, s.end_m, bar.length_m):
            if s.given_moments_m4 is not None or s.given_area_m2 is not None:
                r.fail("cavity.position_mm", z * 1e3, "the cavity lies in a section that "
                       "gives its own second_moments_mm4 or area_mm2, and the cavity's "
                       "section is computed from a round host: give the cavity's span a "
                       "round section of its own")
            return s
    edge = next(s.end_m for s in bar.sections if lo < s.end_m < hi)
    r.fail("cavity.position_mm", z * 1e3,
           f"the cavity [{lo * 1e3:g}, {hi * 1e3:g}] mm crosses the section boundary at "
           f"{edge * 1e3:g} mm; a cavity must lie within one section (split the sections "
           "at the cavity's ends)")


def _cavity(r: _Reader, d: dict, bar: SteppedBar):
    if "cavity" not in d:
        return None, {}
    t = r.table(d["cavity"], "cavity", _CAVITY_KEYS)
    z_mm = r.required(t, "cavity.position_mm", 0, bar.length_m * 1e3, lo_open=True,
                      hi_open=True, unit="mm")
    length_mm = r.required(t, "cavity.length_mm", 0, bar.length_m * 1e3, lo_open=True,
                           unit="mm")
    z, length = z_mm / 1000, length_mm / 1000
    host = _host_section(r, bar, z - length / 2, z + length / 2, z)
    depth = r.number(t, "cavity.depth_mm", 0, host.diameter_m * 1e3, default=host.diameter_m * 1e3,
                     lo_open=True, unit="mm (at most the host section's outer diameter)")
    dia_mm = r.number(t, "cavity.section_diameter_mm", host.inner_diameter_m * 1e3,
                      host.diameter_m * 1e3, lo_open=True, unit="mm (above the host "
                      "section's bore, at most its outer diameter)")
    if dia_mm is None:
        try:
            dia_mm = 1e3 * cavity_section_diameter(host.diameter_m, host.inner_diameter_m,
                                                   length, depth / 1000)
        except ParameterError:
            r.fail("cavity.length_mm", length_mm, f"without section_diameter_mm, must be "
                   f"less than the host section's diameter {host.diameter_m * 1e3:g} mm (a "
                   "round cavity this long cuts the section in two); give "
                   "section_diameter_mm")
    dia = dia_mm / 1000
    cavity = CavitySpec(z, length, dia, host.inner_diameter_m, depth / 1000)
    return cavity, {"cavity": {"position_mm": z_mm, "length_mm": length_mm,
                               "section_diameter_mm": dia_mm, "depth_mm": depth}}


_BALL_KEYS = ("material", "diameter_mm", "mass_g", "gap_mm", "restitution", "friction",
              "contact", "contact_stiffness_n_m1_5", "plug_material", "motion", "mu_static",
              "mu_kinetic")
_FRICTION_KEYS = tuple(FRICTION_FORMS) + ("reaction", "static_ratio")


def _friction(r: _Reader, t: dict) -> tuple[str, float, str | None, float]:
    f = t.get("friction", {"published_number": 0.6})
    if not isinstance(f, dict):
        r.fail("ball.friction", f, "must be a table, e.g. { rolling_mm = 0.6 }")
    r.table(f, "ball.friction", _FRICTION_KEYS)
    forms = [k for k in FRICTION_FORMS if k in f]
    if len(forms) != 1:
        r.fail("ball.friction", f, "give exactly one of " + ", ".join(FRICTION_FORMS))
    form = forms[0]
    if form == "none":
        if f["none"] is not True:
            r.fail("ball.friction.none", f["none"], "must be true")
        value = 0.0
    else:
        hi = MAX_FRICTION_FORCE if form == "force_n" else 100.0
        value = r.number(f, f"ball.friction.{form}", 0, hi)
    reaction = r.choice(f, "ball.friction.reaction", REACTIONS)
    ratio = r.number(f, "ball.friction.static_ratio", 1, 1e6, default=1.0)
    return FRICTION_FORMS[form], value, reaction, ratio


def _ball(r: _Reader, d: dict, bar: SteppedBar, cavity: CavitySpec | None):
    if "ball" not in d:
        return None, {}
    if cavity is None:
        r.fail("ball", d["ball"], "a ball needs a [cavity] (its position and size)")
    t = r.table(d["ball"], "ball", _BALL_KEYS)
    material = r.choice(t, "ball.material", tuple(MATERIALS), default="carbide")
    dia = r.number(t, "ball.diameter_mm", 0, cavity.length_m * 1e3, default=15.0,
                   lo_open=True, unit=f"mm (the cavity is {cavity.length_m * 1e3:g} mm long)")
    if dia / 1000 >= cavity.depth_m:
        r.fail("ball.diameter_mm", dia, f"must be less than the cavity's depth "
                                        f"{cavity.depth_m * 1e3:g} mm")
    mass = r.number(t, "ball.mass_g", 0, 100_000, lo_open=True, unit="g")
    room = min(MAX_GAP, cavity.depth_m - dia / 1000) * 1e3
    gap = r.number(t, "ball.gap_mm", 0, room, default=min(0.5, room), lo_open=True,
                   unit=f"mm (cavity depth {cavity.depth_m * 1e3:g} mm less the ball, at most "
                        f"{MAX_GAP * 1e3:g} mm)")
    e = r.number(t, "ball.restitution", 0, 1, default=0.7)
    kind, value, reaction, ratio = _friction(r, t)
    contact = r.choice(t, "ball.contact", CONTACT_LAWS, default="impact")
    stiffness = r.number(t, "ball.contact_stiffness_n_m1_5", 0, math.inf, lo_open=True,
                         unit="N/m^1.5")
    plug = r.choice(t, "ball.plug_material", tuple(MATERIALS), default="steel")
    if contact == "hertz" and e < HERTZ_MIN_RESTITUTION:
        r.fail("ball.restitution", e, f"must be in [{HERTZ_MIN_RESTITUTION}, 1] with contact = "
                                      "'hertz' (Hunt-Crossley's damping grows without bound "
                                      "as e -> 0)")
    motion = r.choice(t, "ball.motion", BALL_MOTIONS, default="slide")
    mus = r.number(t, "ball.mu_static", 0, MU_MAX, default=MU_STATIC)
    muk = r.number(t, "ball.mu_kinetic", 0, MU_MAX, default=MU_KINETIC)
    if mus < muk:
        r.fail("ball.mu_static", mus, f"must be at least mu_kinetic = {muk:g}")
    ball = BallSpec(material, dia / 1000, None if mass is None else mass / 1000, gap / 1000,
                    e, kind, value, reaction, ratio, contact, stiffness, plug, motion, mus, muk)
    form = next(k for k, v in FRICTION_FORMS.items() if v == kind)
    friction = {form: True if form == "none" else value, "static_ratio": ratio}
    if reaction is not None:
        friction["reaction"] = reaction
    data = {"material": material, "diameter_mm": dia, "gap_mm": gap, "restitution": e,
            "friction": friction}
    if mass is not None:
        data["mass_g"] = mass
    if motion != "slide":
        data.update(motion=motion, mu_static=mus, mu_kinetic=muk)
    if contact != "impact":
        data.update(contact=contact, plug_material=plug)
        if stiffness is not None:
            data["contact_stiffness_n_m1_5"] = stiffness
    return ball, {"ball": data}


_TMD_KEYS = ("mass_kg", "position_mm", "tuning", "stiffness_n_m", "damping_n_s_m", "label")


def _tmd(r: _Reader, d: dict, bar: SteppedBar):
    if "tmd" not in d:
        return None, {}
    t = r.table(d["tmd"], "tmd", _TMD_KEYS)
    mass = r.required(t, "tmd.mass_kg", 0, 1000, lo_open=True, unit="kg")
    z_mm = r.required(t, "tmd.position_mm", 0, bar.length_m * 1e3, lo_open=True, unit="mm")
    z = z_mm / 1000
    tuning = r.choice(t, "tmd.tuning", TUNINGS, default="den-hartog")
    k = r.number(t, "tmd.stiffness_n_m", 0, 1e12, lo_open=True, unit="N/m")
    c = r.number(t, "tmd.damping_n_s_m", 0, 1e9, unit="N s/m")
    if tuning == "given" and (k is None or c is None):
        r.fail("tmd.tuning", tuning, "'given' needs stiffness_n_m and damping_n_s_m")
    label = r.text(t, "tmd.label", "given")
    data = {"mass_kg": mass, "position_mm": z_mm, "tuning": tuning, "label": label}
    if k is not None and c is not None:
        data.update(stiffness_n_m=k, damping_n_s_m=c)
    elif k is not None or c is not None:
        r.fail("tmd.stiffness_n_m" if k is None else "tmd.damping_n_s_m", None,
               "give both stiffness_n_m and damping_n_s_m, or neither")
    return TmdSpec(mass, z, tuning, k, c, label), {"tmd": data}


def _paper(r: _Reader, d: dict) -> dict:
    t = r.table(d.get("paper", {}), "paper",
                ("first_frequency_hz_ball", "first_frequency_hz_solid"))
    out = {}
    for kind in ("ball", "solid"):
        f = r.number(t, f"paper.first_frequency_hz_{kind}", 0, 1e6, lo_open=True, unit="Hz")
        if f is not None:
            out[kind] = f
    return out


def _cavity_section(cavity: CavitySpec, host: Section, start: float, end: float,
                    across: bool) -> Section:
    """The cavity's equivalent section in ``host``; ``across``: with the along section's
    mass and the stiffness of bending across the ball's direction, the computed across
    stiffness over the computed along one's times the along section's (so a given along
    section keeps their ratio), at most the host's."""
    dia, bore = cavity.section_diameter_m, cavity.section_bore_m
    if not across:
        return Section(start, end, dia, bore)
    outer = host.diameter_m
    try:
        along, other = (cavity_section_diameter(outer, bore, cavity.length_m, cavity.depth_m,
                                                across=a) for a in (False, True))
    except ParameterError:
        raise ParameterError("the cavity's section across the ball's direction cannot be "
                             "computed (give a cavity shorter than the section's diameter): "
                             "a bar of two planes needs it") from None
    scale = min((other**4 - bore**4) / (along**4 - bore**4),
                (outer**4 - bore**4) / (dia**4 - bore**4))
    return Section(start, end, dia, bore, scale)


def _with_cavity(bar: SteppedBar, cavity: CavitySpec, across: bool = False) -> SteppedBar:
    """``bar`` with the cavity's span given the cavity's equivalent section; the
    host section is split at the cavity's ends unless they sit on its own."""
    lo, hi = cavity.position_m - cavity.length_m / 2, cavity.position_m + cavity.length_m / 2
    out = []
    for s in bar.sections:
        if not _within(lo, hi, s.start_m, s.end_m, bar.length_m):
            out.append(s)
            continue
        a = s.start_m if near(lo, s.start_m, bar.length_m) else lo
        b = s.end_m if near(hi, s.end_m, bar.length_m) else hi
        if a > s.start_m:
            out.append(replace(s, end_m=a))
        out.append(_cavity_section(cavity, s, a, b, across))
        if b < s.end_m:
            out.append(replace(s, start_m=b))
    return SteppedBar(tuple(out), bar.youngs_modulus_pa, bar.density_kg_m3, bar.damping_ratio,
                      bar.max_element_length_m, bar.clamp_translational_stiffness_n_m,
                      bar.clamp_rotational_stiffness_n_m_per_rad)
