"""A measured tip FRF (a tap test at the tool tip) and the files it comes in.

Two formats are read:

- **CSV**: three columns, frequency (Hz), real and imaginary part of the tip
  receptance W/F (m/N), one row per frequency.  Lines starting with ``#`` are
  comments; the first other line may be a header (names, not numbers).  Frequencies must
  increase strictly.
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
    says where it came from (file, format)."""

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
    rows, header = [], False
    with open(path, newline="") as f:
        for n, row in enumerate(csv.reader(f), start=1):
            if not row or row[0].lstrip().startswith("#"):
                continue
            try:
                values = [float(v) for v in row]
            except ValueError:
                if not rows and not header:
                    header = True  # the first line that is not a comment may name columns
                    continue
                raise FrfFileError(f"{path}: line {n} = {','.join(row)!r}: three numbers "
                                   "expected (frequency Hz, real, imaginary m/N)") from None
            if len(values) != 3:
                raise FrfFileError(f"{path}: line {n} has {len(values)} columns; three "
                                   "expected (frequency Hz, real, imaginary m/N)")
            rows.append(values)
    if not rows:
        raise FrfFileError(f"{path}: no data rows (frequency Hz, real, imaginary m/N)")
    a = np.array(rows)
    return MeasuredFrf(a[:, 0], a[:, 1] + 1j * a[:, 2], {"file": str(path), "format": "csv"})


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
    f = np.asarray(d["x"], dtype=float)
    h = np.asarray(d["data"], dtype=complex)
    power = UFF_ORDINATES[kind]
    if power:
        with np.errstate(divide="ignore", invalid="ignore"):
            h = h / (1j * 2.0 * math.pi * f) ** power
        keep = f > 0
        f, h = f[keep], h[keep]
    return MeasuredFrf(f, h, {"file": str(path), "format": "uff58",
                              "ordinate": {0: "receptance", 1: "mobility",
                                           2: "accelerance"}[power]})


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
