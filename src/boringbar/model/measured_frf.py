"""A measured tip FRF (a tap test at the tool tip) and the files it comes in.

Two formats are read:

- **CSV**: three columns, one row per frequency: the frequency, and the real and
  imaginary parts (or the magnitude and phase) of the tip receptance, mobility or
  accelerance.  Lines starting with ``#`` are comments.  The first other line, if it
  holds names rather than numbers, is a header that names each column and its unit
  (the grammar: :mod:`boringbar.model.frf_units`; docs/frf.md); a header whose units
  cannot be read is refused.  A file without a header is read as frequency (Hz), real
  and imaginary part of the receptance (m/N), and its ``source`` says so.
  Frequencies must increase strictly.
- **UFF dataset 58** (``.uff``, ``.unv``), read with pyuff: a frequency
  response function (function type 4) of displacement, velocity or
  acceleration over force (receptance, mobility or accelerance; the latter two
  are turned into receptance by dividing by i omega or -omega^2).  The first
  FRF in the file is read.

Every error is one line naming the file, the line or field, and what is allowed.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pyuff

from boringbar._validate import ParameterError
from boringbar.model.frf_units import (
    NO_HEADER,
    ORDINATES,
    CsvUnits,
    read_header,
    to_receptance,
)

#: Fewest frequency lines a measured FRF may have.
MIN_LINES = 20
CSV_SUFFIXES = (".csv", ".txt")
UFF_SUFFIXES = (".uff", ".unv")
#: UFF58 ordinate types (numerator over force) -> the power of i omega that turns it
#: into receptance: displacement 0, velocity 1, acceleration 2.
UFF_ORDINATES = {8: 0, 11: 1, 12: 2}


class FrfFileError(ParameterError):
    """A measured-FRF file that cannot be read; the message is one line."""


@dataclass(frozen=True, eq=False)
class MeasuredFrf:
    """A tip receptance H(f) (m/N) at ``frequency_hz`` (increasing); ``source``
    says where it came from (file, format) and, for a CSV file, the units it was read
    in (``units``) and what was done to turn them into Hz and m/N (``conversion``)."""

    frequency_hz: np.ndarray
    receptance: np.ndarray
    source: dict = field(default_factory=dict)

    def __post_init__(self):
        f = np.asarray(self.frequency_hz, dtype=float)
        h = np.asarray(self.receptance, dtype=complex)
        where = self.source.get("file", "measured FRF")
        if f.ndim != 1 or h.shape != f.shape:
            raise FrfFileError(f"{where}: frequency_hz and receptance must be two arrays of "
                               f"one length (got {f.shape} and {h.shape})")
        if len(f) < MIN_LINES:
            raise FrfFileError(f"{where}: {len(f)} frequency lines; at least {MIN_LINES} "
                               "are needed")
        if not (np.all(np.isfinite(f)) and np.all(np.isfinite(h))):
            raise FrfFileError(f"{where}: frequencies and FRF values must be finite")
        if f[0] < 0 or np.any(np.diff(f) <= 0):
            raise FrfFileError(f"{where}: frequencies must be >= 0 and strictly increasing")
        object.__setattr__(self, "frequency_hz", f)
        object.__setattr__(self, "receptance", h)

    @property
    def omega(self) -> np.ndarray:
        return 2.0 * math.pi * self.frequency_hz

    def band(self, lo_hz: float, hi_hz: float) -> MeasuredFrf:
        """The lines within [lo_hz, hi_hz]."""
        keep = (self.frequency_hz >= lo_hz) & (self.frequency_hz <= hi_hz)
        return MeasuredFrf(self.frequency_hz[keep], self.receptance[keep],
                           dict(self.source, band_hz=[lo_hz, hi_hz]))


def read_frf(path) -> MeasuredFrf:
    """Read a measured tip FRF from ``path`` (CSV or UFF58, by its suffix)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in CSV_SUFFIXES + UFF_SUFFIXES:
        raise FrfFileError(f"{path}: unknown FRF file type {suffix or '(none)'!r}; allowed: "
                           + ", ".join(CSV_SUFFIXES + UFF_SUFFIXES))
    if not path.is_file():
        raise FrfFileError(f"{path}: no such file")
    return _read_csv(path) if suffix in CSV_SUFFIXES else _read_uff(path)


def _read_csv(path: Path) -> MeasuredFrf:
    units, rows = None, []
    for n, row in enumerate(csv.reader(_csv_text(path).splitlines()), start=1):
        if not any(cell.strip() for cell in row) or row[0].lstrip().startswith("#"):
            continue  # blank (a spreadsheet writes ",," for an empty row), or a comment
        values = _numbers(row)
        if values is None and units is None and not rows:
            units = _header(path, n, row)  # the first line that is not a comment
            continue
        expected = (units or NO_HEADER).columns_text()
        if values is None:
            raise FrfFileError(f"{path}: line {n} = {','.join(row)!r}: three numbers "
                               f"expected ({expected})")
        if len(values) != 3:
            raise FrfFileError(f"{path}: line {n} has {len(values)} columns; three "
                               f"expected ({expected})")
        rows.append(values)
    units = units or NO_HEADER
    if not rows:
        raise FrfFileError(f"{path}: no data rows ({units.columns_text()})")
    try:
        f, h, how = units.receptance(np.array(rows))
    except ParameterError as exc:
        raise FrfFileError(f"{path}: {exc}") from None
    return MeasuredFrf(f, h, {"file": str(path), "format": "csv", **how})


def _csv_text(path: Path) -> str:
    """The file's text: UTF-8 (a spreadsheet's byte-order mark dropped), else Latin-1,
    in which an older export writes "µm/N"."""
    try:
        return path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        return path.read_text(encoding="latin-1")


def _numbers(row: list[str]) -> list[float] | None:
    """The row's numbers, or None if it holds a cell that is not one."""
    try:
        return [float(v) for v in row]
    except ValueError:
        return None


def _header(path: Path, n: int, row: list[str]) -> CsvUnits:
    try:
        return read_header(row)
    except ParameterError as exc:
        raise FrfFileError(f"{path}: line {n} (header): {exc}") from None


def _read_uff(path: Path) -> MeasuredFrf:
    try:
        uff = pyuff.UFF(str(path))
        types = list(uff.get_set_types())
    except Exception as exc:  # pyuff raises bare Exceptions on malformed files
        raise FrfFileError(f"{path}: not a readable UFF file ({exc})") from None
    if 58 not in types:
        raise FrfFileError(f"{path}: no dataset 58 (function at nodal DOF); datasets found: "
                           f"{sorted(set(int(t) for t in types))}")
    d = uff.read_sets(types.index(58))
    if int(d.get("func_type", 0)) != 4:
        raise FrfFileError(f"{path}: dataset 58 has function type {d.get('func_type')}; a "
                           "frequency response function (4) is needed")
    kind = int(d.get("ordinate_spec_data_type", 8))
    if kind not in UFF_ORDINATES:
        raise FrfFileError(f"{path}: dataset 58 ordinate type {kind}; allowed: 8 "
                           "(displacement), 11 (velocity), 12 (acceleration) over force")
    power = UFF_ORDINATES[kind]
    f, h, _ = to_receptance(np.asarray(d["x"], dtype=float),
                            np.asarray(d["data"], dtype=complex), power)
    return MeasuredFrf(f, h, {"file": str(path), "format": "uff58",
                              "ordinate": ORDINATES[power]})


def frf_csv_text(frf: MeasuredFrf, header: str = "") -> str:
    """The CSV text of ``frf`` (full precision), with ``header`` as # comments."""
    lines = [f"# {h}" for h in header.splitlines()]
    lines.append("frequency_hz,real_m_per_n,imag_m_per_n")
    lines += [f"{float(f)!r},{float(h.real)!r},{float(h.imag)!r}"
              for f, h in zip(frf.frequency_hz, frf.receptance, strict=True)]
    return "\n".join(lines) + "\n"


def uff58_dict(frf: MeasuredFrf, name: str = "tip receptance") -> dict:
    """``frf`` as a pyuff dataset-58 dict (receptance, m/N, complex double)."""
    return pyuff.prepare_58(func_type=4, ordinate_spec_data_type=8,
                            orddenom_spec_data_type=13, abscissa_spec_data_type=18,
                            data=frf.receptance, x=frf.frequency_hz, rsp_node=1, rsp_dir=1,
                            ref_node=1, ref_dir=1, id1=name, binary=0, ord_data_type=6,
                            abscissa_spacing=0)
