"""The units of a measured FRF: read from a CSV file's header, turned into Hz and m/N,
and checked against what a boring bar can have.

A CSV header names each of its three columns with a unit (docs/frf.md):

- ``NAME [UNIT]``, ``NAME (UNIT)``, ``NAME/UNIT`` or ``NAME UNIT``: ``f [kHz]``,
  ``Re (um/N)``, ``phase [deg]``, ``f/Hz``;
- ``NAME_UNIT``, the unit as a name suffix with ``per`` for ``/``: ``frequency_hz``,
  ``real_m_per_n``, ``accelerance_imag_m_s2_per_n``.

NAME says which column it is: frequency (``frequency``, ``freq``, ``f``, ``omega``,
``w``), real part (``real``, ``re``), imaginary part (``imag``, ``imaginary``,
``im``), magnitude (``magnitude``, ``mag``, ``abs``, ``amplitude``, ``|H|``) or phase
(``phase``, ``arg``, ``angle``, ``phi``); other words (``H``, ``tip``, ``part``) are
allowed. The three columns are a frequency and either real and imaginary parts or
magnitude and phase, in any order. UNIT is, case aside:

- frequency: Hz, kHz or rad/s;
- response over force: receptance in m/N, mm/N, um/N (``µm/N``, ``micron/N``) or
  nm/N; mobility in (m/s)/N (also ``m/s/N``, ``m/(N s)``); accelerance in
  (m/s^2)/N (also ``m/s2/N``, ``m/(N s^2)``) or g/N. Real and imaginary parts share
  one unit. Mobility and accelerance are divided by i omega or -omega^2 into
  receptance; a line at 0 Hz, where that is undefined, is dropped;
- phase: deg or rad.

A header whose units cannot be read is refused: it names the column and what is
allowed. NAME may also carry the kind (``receptance``, ``compliance``, ``mobility``,
``accelerance``, ``inertance``); one that contradicts UNIT is refused rather than
guessed.

A file in the wrong units (or one without a header, read as Hz and m/N) shows in what
it describes: a static tip stiffness or natural frequencies that no boring bar has
(PLAUSIBLE_STIFFNESS_N_M, PLAUSIBLE_FREQUENCY_HZ). :func:`implausible_modes` (for a
fit) and :func:`implausible_frf` (for a measured FRF as it is) say what is out of range;
the callers warn with :class:`ImplausibleFrfWarning`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from boringbar._validate import ParameterError

#: m/s^2 in one g (standard gravity), for accelerance in g/N.
STANDARD_GRAVITY_M_S2 = 9.80665
#: frequency units (normalised spelling) -> (as shown, factor to Hz)
FREQUENCY_UNITS = {"hz": ("Hz", 1.0), "khz": ("kHz", 1e3),
                   "rad/s": ("rad/s", 1 / (2 * math.pi))}
#: phase units (normalised spelling) -> (as shown, factor to rad)
PHASE_UNITS = {**dict.fromkeys(("deg", "degree", "degrees", "°"), ("deg", math.pi / 180)),
               **dict.fromkeys(("rad", "radian", "radians"), ("rad", 1.0))}
#: lengths of a response (normalised spelling) -> m
LENGTHS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "nm": 1e-9}
#: the power of i omega that turns an FRF into receptance -> the FRF's name
ORDINATES = {0: "receptance", 1: "mobility", 2: "accelerance"}
#: words of a column's name that say the FRF's kind -> its power of i omega
KIND_WORDS = {"receptance": 0, "compliance": 0, "mobility": 1, "accelerance": 2,
              "inertance": 2}
#: words of a column's name -> the column it is
ROLE_WORDS = {"frequency": {"frequency", "freq", "f", "omega", "w"},
              "real": {"real", "re"}, "imag": {"imag", "imaginary", "im"},
              "magnitude": {"magnitude", "mag", "abs", "amplitude", "amp", "modulus"},
              "phase": {"phase", "arg", "angle", "phi"}}
RESPONSE_ROLES = ("real", "imag", "magnitude")
ALLOWED = {"frequency": "Hz, kHz, rad/s",
           "response": "m/N, mm/N, um/N (or µm/N, micron/N), nm/N; mobility (m/s)/N; "
                       "accelerance (m/s^2)/N or g/N (any of those lengths for m)",
           "phase": "deg, rad"}
GRAMMAR = ("name each column with its unit: 'f [kHz]', 'Re (um/N)', 'phase [deg]' or "
           "'frequency_hz', 'real_m_per_n' (docs/frf.md)")
#: spellings of micrometre, and the symbols of micro (micro sign, Greek mu)
MICRO = re.compile(r"micro(?:metres?|meters?|ns?)|[µμ]m")

#: Tip static stiffness a boring bar can have (N/m): a 10 mm steel bar at 14 diameters'
#: overhang at the soft end, a 60 mm carbide bar at 3 at the stiff end (docs/frf.md).
PLAUSIBLE_STIFFNESS_N_M = (1e5, 1e9)
#: Natural frequencies a tap test of a boring bar finds (Hz): a long heavy bar's first
#: mode at the low end, what a hammer and an accelerometer reach at the high end.
PLAUSIBLE_FREQUENCY_HZ = (20.0, 20e3)
#: Least damping ratio of a bar (a solid steel bar's own): a measured FRF's least
#: dynamic stiffness 1/max|H|, 2 k zeta at a lone mode, is at least this times 2 k.
LEAST_DAMPING_RATIO = 0.002


class ImplausibleFrfWarning(UserWarning):
    """A measured FRF or its fit with a stiffness or natural frequencies no boring bar
    has: most often a file read in the wrong units."""


def _response_units() -> dict[str, tuple[str, int, float]]:
    """Response units (normalised spelling) -> (as shown, power of i omega, factor to
    m/N, (m/s)/N or (m/s^2)/N)."""
    units = {"g/n": ("g/N", 2, STANDARD_GRAVITY_M_S2)}
    for length, factor in LENGTHS.items():
        units[f"{length}/n"] = (f"{length}/N", 0, factor)
        for power, per in ((1, "s"), (2, "s2")):
            shown = f"({length}/s)/N" if power == 1 else f"({length}/s^2)/N"
            for spelling in (f"{length}/{per}/n", f"({length}/{per})/n", f"{length}/n/{per}",
                             f"{length}/(n{per})", f"{length}/({per}n)"):
                units[spelling] = (shown, power, factor)
    return units


RESPONSE_UNITS = _response_units()
ANY_UNIT = set(FREQUENCY_UNITS) | set(PHASE_UNITS) | set(RESPONSE_UNITS)


@dataclass(frozen=True)
class Column:
    """One column of a CSV header: its index (0-based), its text, which column it is
    (``role``), its unit as shown, the factor to SI (Hz, rad, m/N...) and, for a
    response, the power of i omega that turns it into receptance."""

    index: int
    text: str
    role: str
    unit: str
    factor: float
    power: int = 0


@dataclass(frozen=True)
class CsvUnits:
    """How a CSV file's three columns are read: the frequency, and real and imaginary
    parts or magnitude and phase; ``header`` whether a header said so."""

    frequency: Column
    first: Column
    second: Column
    header: bool = True

    @property
    def polar(self) -> bool:
        return self.first.role == "magnitude"

    @property
    def ordinate(self) -> str:
        return ORDINATES[self.first.power]

    def columns_text(self) -> str:
        """The columns in file order, for an error about a data line."""
        cols = sorted((self.frequency, self.first, self.second), key=lambda c: c.index)
        return ", ".join(f"{c.role} {c.unit}" for c in cols)

    def receptance(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict]:
        """(frequency Hz, receptance m/N, how they were read) of the data ``rows``."""
        f = rows[:, self.frequency.index] * self.frequency.factor
        a = rows[:, self.first.index] * self.first.factor
        b = rows[:, self.second.index] * self.second.factor
        if self.polar and np.any(a < 0):
            raise ParameterError(f"column {self.first.index + 1} {self.first.text!r} holds "
                                 f"a negative magnitude ({a[a < 0][0]:g}); a magnitude is >= 0")
        f, h, dropped = to_receptance(f, a * np.exp(1j * b) if self.polar else a + 1j * b,
                                      self.first.power)
        return f, h, self.source(dropped)

    def source(self, dropped: int = 0) -> dict:
        """The units read and the conversion applied, for a MeasuredFrf's ``source``."""
        units = (f"frequency {self.frequency.unit}, {self.first.role} {self.first.unit}, "
                 f"{self.second.role} {self.second.unit} "
                 + ("(from the header)" if self.header else "assumed (no header)"))
        return {"units": units, "ordinate": self.ordinate,
                "conversion": "; ".join(self._conversions(dropped)) or "none"}

    def _conversions(self, dropped: int) -> list[str]:
        steps = []
        if self.frequency.factor != 1.0:
            steps.append(f"frequency x {self.frequency.factor:.10g} "
                         f"({self.frequency.unit} to Hz)")
        if self.polar:
            steps.append("H = magnitude exp(i phase)" + (
                f", phase x {self.second.factor:.10g} (deg to rad)"
                if self.second.factor != 1.0 else ""))
        if self.first.factor != 1.0:
            si = ("m/N", "(m/s)/N", "(m/s^2)/N")[self.first.power]
            steps.append(f"{self.ordinate} x {self.first.factor:.10g} ({self.first.unit} to "
                         f"{si})")
        if self.first.power:
            steps.append(f"receptance = {self.ordinate} / "
                         + ("(i omega)" if self.first.power == 1 else "-omega^2")
                         + (f" ({dropped} line(s) at 0 Hz dropped)" if dropped else ""))
        return steps


#: A file without a header: frequency (Hz), real and imaginary part (m/N).
NO_HEADER = CsvUnits(Column(0, "", "frequency", "Hz", 1.0), Column(1, "", "real", "m/N", 1.0),
                     Column(2, "", "imag", "m/N", 1.0), header=False)


def to_receptance(frequency_hz: np.ndarray, h: np.ndarray, power: int
                  ) -> tuple[np.ndarray, np.ndarray, int]:
    """Receptance from an FRF whose response is the ``power``-th derivative of
    displacement (0 receptance, 1 mobility, 2 accelerance): H / (i omega)^power. The
    lines at 0 Hz, where that is undefined, are dropped: (frequency, H, lines dropped)."""
    if power == 0:
        return frequency_hz, h, 0
    keep = frequency_hz != 0
    f = frequency_hz[keep]
    return f, h[keep] / (1j * 2.0 * math.pi * f) ** power, int(np.count_nonzero(~keep))


def read_header(cells: list[str]) -> CsvUnits:
    """The units of a CSV header's ``cells``; a ParameterError names the column that
    cannot be read and what is allowed."""
    if len(cells) != 3:
        raise ParameterError(f"the header has {len(cells)} column(s); three are expected: "
                             "frequency, and real and imaginary parts or magnitude and "
                             "phase; " + GRAMMAR)
    columns = {}
    for i, text in enumerate(cells):
        column = read_column(i, text)
        if column.role in columns:
            raise ParameterError(f"columns {columns[column.role].index + 1} and {i + 1} "
                                 f"({columns[column.role].text!r}, {text!r}) are both "
                                 f"{column.role}")
        columns[column.role] = column
    return _pair(columns)


def _pair(columns: dict[str, Column]) -> CsvUnits:
    pair = ("real", "imag") if "real" in columns or "imag" in columns else (
        "magnitude", "phase")
    missing = [role for role in ("frequency", *pair) if role not in columns]
    if missing:
        names = ", ".join(f"{c.index + 1} {c.text!r} ({c.role})" for c in columns.values())
        raise ParameterError(f"the header's columns {names} lack {' and '.join(missing)}: "
                             "three columns are frequency, and real and imaginary parts or "
                             "magnitude and phase")
    first, second = columns[pair[0]], columns[pair[1]]
    if pair[0] == "real" and first.unit != second.unit:
        raise ParameterError(f"columns {first.index + 1} {first.text!r} and "
                             f"{second.index + 1} {second.text!r} have two units "
                             f"({first.unit}, {second.unit}); real and imaginary parts "
                             "share one")
    return CsvUnits(columns["frequency"], first, second)


def read_column(index: int, text: str) -> Column:
    """Column ``index`` (0-based) of a header, from its ``text``."""
    where = f"column {index + 1} {text.strip()!r}"
    name, unit_text, space = split_unit(text)
    role = _role(where, name)
    table = (FREQUENCY_UNITS if role == "frequency" else PHASE_UNITS if role == "phase"
             else RESPONSE_UNITS)
    allowed = ALLOWED[role if role in ("frequency", "phase") else "response"]
    if unit_text is None:
        raise ParameterError(f"{where} states no unit (allowed: {allowed}); {GRAMMAR}")
    unit = table.get(normal_unit(unit_text, space))
    if unit is None:
        raise ParameterError(f"{where}: unit {unit_text.strip()!r} is not one of the "
                             f"{role} units this reader knows: {allowed}")
    if role in RESPONSE_ROLES:
        _check_kind(where, name, unit)
        return Column(index, text.strip(), role, unit[0], unit[2], unit[1])
    return Column(index, text.strip(), role, unit[0], unit[1])


def _role(where: str, name: str) -> str:
    words = set(re.findall(r"[a-z]+", name.lower()))
    roles = [role for role, names in ROLE_WORDS.items() if names & words]
    if name.count("|") >= 2 and "magnitude" not in roles:
        roles.append("magnitude")  # |H|
    if len(roles) != 1:
        found = f"names {' and '.join(roles)}" if roles else "names no column"
        raise ParameterError(f"{where} {found}: one of frequency (f, freq), real (re), "
                             "imag (im), magnitude (mag, |H|), phase is expected")
    return roles[0]


def _check_kind(where: str, name: str, unit: tuple[str, int, float]) -> None:
    """A kind named in the column's name (accelerance...) must be the unit's."""
    for word in set(re.findall(r"[a-z]+", name.lower())) & set(KIND_WORDS):
        if KIND_WORDS[word] != unit[1]:
            raise ParameterError(f"{where}: the name says {word}, the unit {unit[0]} is "
                                 f"a {ORDINATES[unit[1]]} unit; which is it? (allowed: "
                                 f"{ALLOWED['response']})")


def split_unit(text: str) -> tuple[str, str | None, str]:
    """(name, unit or None, what a space in the unit means: "" a product, "/" a
    quotient as in a name suffix) of a header cell."""
    cell = text.strip()
    if cell.endswith("]") and "[" in cell:
        i = cell.rindex("[")
        return cell[:i], cell[i + 1:-1], ""
    if cell.endswith(")"):
        i = _opening(cell)
        if i > 0:
            return cell[:i], cell[i + 1:-1], ""
    tokens = re.split(r"[\s_]+", cell)
    for i in range(1, len(tokens)):
        if normal_unit(" ".join(tokens[i:]), "/") in ANY_UNIT:
            return " ".join(tokens[:i]), " ".join(tokens[i:]), "/"
    if "/" in cell:  # f/Hz, Re/(m/N): a quantity over its unit
        name, unit = cell.split("/", 1)
        if unit.startswith("(") and _opening(unit) == 0:
            unit = unit[1:-1]
        return name, unit, ""
    return cell, None, ""


def _opening(text: str) -> int:
    """The index of the "(" that the final ")" of ``text`` closes (-1: none)."""
    depth = 0
    for i in range(len(text) - 1, -1, -1):
        depth += {")": 1, "(": -1}.get(text[i], 0)
        if depth == 0:
            return i
    return -1


def normal_unit(text: str, space: str = "") -> str:
    """A unit's spelling as the tables hold it: lower case, u for micro, no ^ or
    multiplication signs, "per" as "/", and a space as ``space``."""
    s = MICRO.sub("um", text.strip().lower())
    s = s.replace("²", "2").replace("^", "")
    s = re.sub(r"[*·⋅]", " ", s)
    s = re.sub(r"\s*\bper\b\s*", "/", s)
    s = re.sub(r"\s*/\s*", "/", s.strip())
    return re.sub(r"\s+", space, s)


def implausible_modes(static_stiffness_n_m: float, frequency_hz) -> list[str]:
    """What in a fit's static tip stiffness and natural frequencies no boring bar has
    (empty: nothing)."""
    found = []
    lo, hi = PLAUSIBLE_STIFFNESS_N_M
    if not lo <= static_stiffness_n_m <= hi:
        found.append(f"static tip stiffness {static_stiffness_n_m:.3g} N/m is outside "
                     f"{_power_of_ten(lo)} to {_power_of_ten(hi)} N/m, a boring bar's")
    found += _outside_frequencies("natural frequency", frequency_hz)
    return found


def implausible_frf(frequency_hz: np.ndarray, receptance: np.ndarray) -> list[str]:
    """What in a measured receptance no boring bar has (empty: nothing): its highest
    peak's frequency, and its least dynamic stiffness 1/max|H| (2 k zeta at a lone
    mode, so within 2 LEAST_DAMPING_RATIO times the least stiffness up to the most)."""
    peak = int(np.argmax(np.abs(receptance)))
    most = float(np.abs(receptance[peak]))
    least = 1.0 / most if most > 0 else math.inf
    lo, hi = 2 * LEAST_DAMPING_RATIO * PLAUSIBLE_STIFFNESS_N_M[0], PLAUSIBLE_STIFFNESS_N_M[1]
    found = []
    if not lo <= least <= hi:
        found.append(f"least dynamic stiffness 1/max|H| {least:.3g} N/m is outside {lo:g} "
                     f"to {_power_of_ten(hi)} N/m, a boring bar's")
    return found + _outside_frequencies("highest peak", [frequency_hz[peak]])


def _outside_frequencies(what: str, frequency_hz) -> list[str]:
    lo, hi = PLAUSIBLE_FREQUENCY_HZ
    out = [f for f in map(float, frequency_hz) if not lo <= f <= hi]
    if not out:
        return []
    return [f"{what} {', '.join(f'{f:.4g}' for f in out)} Hz outside {lo:g} to {hi:g} Hz, "
            "a boring bar's"]


def _power_of_ten(x: float) -> str:
    """1e5 for 100000.0."""
    return f"1e{round(math.log10(x))}"


def plausibility_warning(where: str, found: list[str], source: dict) -> str:
    """One line saying what ``found`` is implausible and how the file was read."""
    read = f" It was read as {source['units']}." if "units" in source else ""
    return f"{where}: {'; '.join(found)}: are the FRF's units right?{read} See docs/frf.md"
