"""Modal parameters from a measured tip FRF: a stabilisation diagram finds the modes,
sdypy-EMA estimates the poles (LSCE or LSCF) and the constants (LSFD).

The estimators are sdypy-EMA's; the reading of the stabilisation diagram, which a
person at the chart would otherwise do, is ours:

1. **Band.** The lines in ``band_hz`` (default: the whole measurement).
2. **Poles.** sdypy's poles at every model order from 1 to ``max_order``
   (default 20; order n holds n pole pairs): LSCE (least-squares complex
   exponential, in the time domain through the impulse response) when the band
   starts near 0 Hz (below 5 % of its top), else LSCF (least-squares complex
   frequency domain), which takes any band. LSCE first because LSCF, a linear
   least-squares estimator, is biased by noise in damping: 1.2-1.4 % on the test
   bar's second mode at 1 % noise, where LSCE stays within 0.3 %. Both need
   equally spaced lines; a non-uniform file is interpolated onto as many. Of each
   order's poles the diagram keeps the physical ones in the band: positive
   frequency and damping, frequency within the band.
3. **Stability.** A pole is *stable* when a pole of the order below has its
   frequency within 1 % and its damping within 5 % (relative to the pole below);
   each pole of the order below pairs with one pole at most, closest frequencies
   first. A pole whose frequency alone repeats is *stable in frequency*; any other
   is *new* (the classes of a stabilisation chart, e.g. Peeters et al. 2004).
4. **Columns.** A stable pole continues the column of its partner, so a column is
   one pole followed from order to order. Columns that break for an order and
   resume at the same frequency (within 1 %) are one column. A column is a
   **mode** when it is stable at a third of the model orders or more (7 of 20):
   a physical mode stays stable from the order that resolves it upward, while
   noise and the estimator's surplus poles repeat for a few orders at most
   (benchmarks/stabilisation_margins.py measures both; docs/frf.md). A mode's
   frequency and damping are the medians over its stable poles.
5. **Which modes.** Without ``n_modes`` every mode of the diagram (at most
   MAX_MODES, the most flexible); with it, the ``n_modes`` most flexible, the
   modes with the largest peak receptance 1/(2 k zeta): those that set chatter.
   No mode in the band, or fewer than asked, is an error.
6. **Constants.** LSFD modal constants with lower and upper residuals
   (sdypy's ``LSFD``) on the chosen poles.
7. **Our modal model.** A receptance mode reads
   A/(i w - lambda) + conj(A)/(i w - conj(lambda)), with lambda = -zeta w_n + i w_d.
   For a real (proportionally damped) mode of tip stiffness k that is
   w_n^2 / (k (w_n^2 - w^2 + 2 i zeta w_n w)), so A = -i w_n^2 / (2 k w_d) and
   k = w_n^2 / (2 w_d (-Im A)). The part of A that is not imaginary (a complex
   mode, or noise) is dropped, and its size goes into the quality figures
   (``complexity``) beside the fit's relative residual over the band.
8. **Plausibility.** A static tip stiffness 1 / sum(1/k_i) or a natural frequency
   that no boring bar has (model/frf_units.py: 1e5 to 1e9 N/m, 20 Hz to 20 kHz) is
   most often an FRF read in the wrong units: a warning, kept in the quality figures
   (``implausible``).

Peeters, B., Van der Auweraer, H., Guillaume, P., Leuridan, J. (2004), "The
PolyMAX frequency-domain method: a new standard for modal parameter estimation?",
Shock and Vibration 11, 395-409 (stabilisation charts and how they are read).
"""

from __future__ import annotations

import contextlib
import io
import math
import warnings
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np
from sdypy import EMA
from sdypy.EMA.EMA import LSFD

from boringbar._validate import ParameterError, check_int, check_range
from boringbar.model.frf_units import ImplausibleFrfWarning, plausibility_warning
from boringbar.model.measured_frf import MeasuredFrf
from boringbar.model.modal_fit import ModalFit

#: Highest model order tried by default, and the lowest allowed.
MAX_ORDER = 20
MIN_ORDER = 10
#: Most modes a fit takes.
MAX_MODES = 8
#: The pole estimator is LSCE (time domain, through the impulse response) when the
#: band starts below this fraction of its top, else LSCF (any band).
LSCE_START = 0.05
#: A fit whose relative residual over the band is above this is said to be poor.
POOR_FIT = 0.1
#: Stability from one model order to the next: relative frequency and damping change.
STABLE_FREQUENCY = 0.01
STABLE_DAMPING = 0.05
#: A column is a mode when it is stable at this share of the model orders or more.
STABLE_SHARE = 1 / 3
#: A pole's status in the diagram, and its name (indexed by the status).
NEW, FREQUENCY_STABLE, STABLE = 0, 1, 2
STATUS_NAMES = ("new", "stable in frequency", "stable in frequency and damping")


@dataclass(frozen=True)
class StableMode:
    """A column of the diagram that is a mode: its median frequency (Hz) and damping
    ratio over its stable poles, and at how many model orders it is stable."""

    frequency_hz: float
    damping_ratio: float
    stable_orders: int

    @property
    def pole(self) -> complex:
        """lambda = -zeta w_n + i w_n sqrt(1 - zeta^2) (rad/s)."""
        w = 2 * math.pi * self.frequency_hz
        z = self.damping_ratio
        return complex(-z * w, w * math.sqrt(1 - z * z))


@dataclass(frozen=True, eq=False)
class Stabilisation:
    """The stabilisation diagram of a measured FRF's band.

    Every kept pole has one entry in ``order``, ``frequency_hz``, ``damping_ratio``,
    ``status`` (NEW, FREQUENCY_STABLE, STABLE), ``column`` (the pole it continues
    shares its column) and ``mode`` (the index in ``modes`` of its column, -1 for
    none). ``modes`` are the columns that are modes, ascending frequency; ``frf`` is
    the band as measured, ``data`` the same on the estimators' uniform grid;
    ``method`` is "lsce" or "lscf"."""

    #: the name of each status, indexed by it (for a figure's legend)
    STATUS_NAMES: ClassVar[tuple[str, ...]] = STATUS_NAMES

    frf: MeasuredFrf
    data: MeasuredFrf
    method: str
    max_order: int
    order: np.ndarray
    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    status: np.ndarray
    column: np.ndarray
    mode: np.ndarray
    modes: tuple[StableMode, ...]

    @property
    def min_stable_orders(self) -> int:
        """Stable orders a column needs to be a mode."""
        return min_stable_orders(self.max_order)

    def summary(self) -> dict:
        """The diagram in a JSON-ready dict: its criteria and its modes."""
        return {"method": self.method.upper(), "max_order": self.max_order,
                "stable_frequency": STABLE_FREQUENCY, "stable_damping": STABLE_DAMPING,
                "min_stable_orders": self.min_stable_orders,
                "modes": [{"frequency_hz": m.frequency_hz, "damping_ratio": m.damping_ratio,
                           "stable_orders": m.stable_orders} for m in self.modes]}


def min_stable_orders(max_order: int) -> int:
    """Stable orders a column needs to be a mode when orders 1..max_order are tried."""
    return math.ceil(STABLE_SHARE * max_order)


def stabilisation(frf: MeasuredFrf, *, band_hz: tuple | None = None,
                  max_order: int = MAX_ORDER) -> Stabilisation:
    """The stabilisation diagram of the measured tip receptance ``frf`` in ``band_hz``
    (Hz, default the whole measurement), model orders 1 to ``max_order``."""
    check_int("max_order", max_order, MIN_ORDER, 200)
    band = _band(frf, band_hz)
    data = _uniform(band)  # what the estimators take; the fit is judged on the band's lines
    # the estimators' discrete-time models need several lines per coefficient
    lines = 4 * max_order + 2
    if len(data.frequency_hz) < lines:
        raise ParameterError(f"max_order = {max_order} needs at least {lines} lines in the "
                             f"band, which has {len(data.frequency_hz)}; lower --max-order "
                             "or widen --band-hz")
    f = data.frequency_hz
    method = "lsce" if f[0] <= LSCE_START * f[-1] else "lscf"
    per_order = [_physical(p, f[0], f[-1]) for p in _poles(data, method, max_order)]
    order, status, column = _track(per_order)
    fn = np.concatenate([p[0] for p in per_order])
    zeta = np.concatenate([p[1] for p in per_order])
    modes, mode = _modes(order, fn, zeta, status, column, min_stable_orders(max_order))
    return Stabilisation(band, data, method, int(max_order), order, fn, zeta, status,
                         column, mode, modes)


def fit_frf(frf: MeasuredFrf, n_modes: int | None = None, *, band_hz: tuple | None = None,
            max_order: int = MAX_ORDER) -> tuple[ModalFit, np.ndarray]:
    """Fit the modes of the stabilisation diagram of the measured tip receptance
    ``frf`` in ``band_hz`` (Hz, default the whole measurement); ``n_modes``, if
    given, the most flexible that many: (the :class:`ModalFit`, its receptance at
    the band's measured lines)."""
    return fit_modes(stabilisation(frf, band_hz=band_hz, max_order=max_order), n_modes)


def fit_modes(diagram: Stabilisation, n_modes: int | None = None
              ) -> tuple[ModalFit, np.ndarray]:
    """Fit the modes of ``diagram`` (all of them, at most MAX_MODES, or the
    ``n_modes`` most flexible): (the :class:`ModalFit`, its receptance at the band's
    measured lines). No mode, fewer modes than ``n_modes``, or a fitted mode of
    negative stiffness is a ParameterError. A static tip stiffness or a natural
    frequency that no boring bar has (:meth:`ModalFit.implausible`, most often an FRF
    read in the wrong units) is an :class:`ImplausibleFrfWarning`, kept in the fit's
    ``quality["implausible"]``."""
    where = diagram.frf.source.get("file", "FRF")
    found = len(diagram.modes)
    if found == 0:
        raise ParameterError(f"{where}: the stabilisation diagram finds no stable mode in "
                             f"the band (no pole column stable at {diagram.min_stable_orders}"
                             f" of {diagram.max_order} model orders): noise only, or a band "
                             "without a resonance; try --band-hz around a peak")
    n = min(found, MAX_MODES) if n_modes is None else check_int("n_modes", n_modes, 1,
                                                                MAX_MODES)
    if n > found:
        raise ParameterError(f"{where}: {found} stable mode(s) in the band, fewer than the "
                             f"{n} modes asked for")
    modes = list(diagram.modes)
    if n < found:
        flexibility = [1 / (2 * k * m.damping_ratio) for m, k in
                       zip(modes, _stiffness(modes, diagram.data)[0], strict=True)]
        modes = [modes[i] for i in sorted(np.argsort(flexibility)[::-1][:n])]
    k, complexity = _stiffness(modes, diagram.data)
    if np.any(k <= 0):
        raise ParameterError(f"{where}: a fitted mode has a non-physical constant "
                             "(negative stiffness); try --band-hz around the modes, or "
                             "fewer --modes")
    fit = ModalFit(tuple(m.frequency_hz for m in modes),
                   tuple(m.damping_ratio for m in modes), tuple(k))
    h_fit = fit.tip_frf(diagram.frf.frequency_hz)
    quality = _quality(diagram, h_fit, complexity)
    implausible = fit.implausible()
    if implausible:
        quality["implausible"] = plausibility_warning(where, implausible, diagram.frf.source)
        warnings.warn(quality["implausible"], ImplausibleFrfWarning, stacklevel=2)
    return replace(fit, source=_source(diagram), quality=quality), h_fit


def _stiffness(modes, data: MeasuredFrf) -> tuple[np.ndarray, np.ndarray]:
    """LSFD constants of ``modes``' poles on ``data``'s lines -> (tip stiffness k
    (N/m; <= 0 for a non-physical constant), complexity |Re A| / |A|)."""
    poles = np.array([m.pole for m in modes])
    f = data.frequency_hz
    first = int(f[0] == 0)  # the lower residual, -1/w^2, is singular at 0 Hz
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = LSFD(poles, data.receptance[None, :], f, True, True, first, len(f),
                 "receptance")[0][0]
    w_n = np.abs(poles)
    w_d = poles.imag
    with np.errstate(divide="ignore"):
        k = np.where(-a.imag > 0, w_n**2 / (2 * w_d * -a.imag), -np.inf)
    return k, np.abs(a.real) / np.abs(a)


def _quality(diagram: Stabilisation, h_fit: np.ndarray, complexity) -> dict:
    measured = diagram.frf.receptance
    residual = float(np.linalg.norm(h_fit - measured) / np.linalg.norm(measured))
    warning = ({"warning": f"relative residual {residual:.2g} > {POOR_FIT:g}: the modes "
                           "do not explain this FRF; try --band-hz or another --modes"}
               if residual > POOR_FIT else {})
    return {"relative_residual": residual, **warning,
            "complexity": np.asarray(complexity).tolist(),
            "stabilisation": diagram.summary()}


def _source(diagram: Stabilisation) -> dict:
    f = diagram.data.frequency_hz
    return {**diagram.frf.source,
            "method": f"sdypy-EMA {diagram.method.upper()} poles + LSFD constants",
            "max_order": diagram.max_order, "band_hz": [float(f[0]), float(f[-1])],
            "pole_selection": "the stable columns of the stabilisation diagram, most "
                              "flexible first"}


def _poles(data: MeasuredFrf, method: str, max_order: int) -> list[np.ndarray]:
    """sdypy's poles (rad/s, complex) of orders 1..max_order, one array per order."""
    f = data.frequency_hz
    model = EMA.Model(frf=data.receptance[None, :], freq=f,
                      lower=0.0 if method == "lsce" else float(f[0]), upper=float(f[-1]),
                      pol_order_high=int(max_order), frf_form="receptance")
    # sdypy warns on the poles it rejects itself and may draw a tqdm bar on stderr
    with warnings.catch_warnings(), contextlib.redirect_stderr(io.StringIO()):
        warnings.simplefilter("ignore")
        model.get_poles(method=method, show_progress=False)
    return [np.asarray(p, dtype=complex) for p in model.all_poles]


def _physical(poles: np.ndarray, lo_hz: float, hi_hz: float
              ) -> tuple[np.ndarray, np.ndarray]:
    """(frequency Hz, damping ratio) of the poles with positive frequency and
    damping whose frequency lies in [lo_hz, hi_hz], ascending frequency."""
    p = poles[np.isfinite(poles) & (poles.imag > 0) & (poles.real < 0)]
    fn = np.abs(p) / (2 * math.pi)
    zeta = -p.real / np.abs(p)
    keep = (fn >= lo_hz) & (fn <= hi_hz)
    order = np.argsort(fn[keep])
    return fn[keep][order], zeta[keep][order]


def _track(per_order) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each pole's order (1, 2, ...), status and column, over ``per_order`` (one
    (frequency, damping) pair of arrays per order)."""
    order, status, column = [], [], []
    prev_f, prev_z, prev_col = np.empty(0), np.empty(0), np.empty(0, dtype=int)
    n_columns = 0
    for o, (fn, zeta) in enumerate(per_order, start=1):
        st, partner = _link(fn, zeta, prev_f, prev_z)
        col = np.full(len(fn), -1)
        linked = partner >= 0
        col[linked] = prev_col[partner[linked]]
        col[~linked] = n_columns + np.arange(np.count_nonzero(~linked))
        n_columns += int(np.count_nonzero(~linked))
        order.append(np.full(len(fn), o))
        status.append(st)
        column.append(col)
        prev_f, prev_z, prev_col = fn, zeta, col
    return tuple(np.concatenate(x).astype(int) for x in (order, status, column))


def _link(fn, zeta, prev_f, prev_z) -> tuple[np.ndarray, np.ndarray]:
    """Each pole's status against the order below, and the index there of the pole
    it continues (-1: none). A pole below continues one pole at most, the closest
    in frequency first."""
    status = np.full(len(fn), NEW)
    partner = np.full(len(fn), -1)
    if len(fn) == 0 or len(prev_f) == 0:
        return status, partner
    df = np.abs(fn[:, None] / prev_f[None, :] - 1)
    dz = np.abs(zeta[:, None] / prev_z[None, :] - 1)
    status[df.min(axis=1) < STABLE_FREQUENCY] = FREQUENCY_STABLE
    i_ok, j_ok = np.nonzero((df < STABLE_FREQUENCY) & (dz < STABLE_DAMPING))
    taken = set()
    for k in np.argsort(df[i_ok, j_ok], kind="stable"):
        i, j = i_ok[k], j_ok[k]
        if partner[i] < 0 and j not in taken:
            partner[i] = j
            status[i] = STABLE
            taken.add(j)
    return status, partner


def _modes(order, fn, zeta, status, column, needed: int
           ) -> tuple[tuple[StableMode, ...], np.ndarray]:
    """The columns stable at ``needed`` orders or more (a column that breaks and
    resumes at the same frequency, at orders that do not overlap, is one column),
    ascending frequency, and each pole's mode (-1: none)."""
    stable = status == STABLE
    groups = []  # the indices of each column's stable poles
    for c in np.unique(column[stable]):
        idx = np.flatnonzero(stable & (column == c))
        f_c = np.median(fn[idx])
        same = next((g for g in groups if abs(f_c / np.median(fn[g]) - 1) < STABLE_FREQUENCY
                     and not set(order[g]) & set(order[idx])), None)
        if same is None:
            groups.append(list(idx))
        else:
            same.extend(idx)
    groups = sorted((g for g in groups if len(g) >= needed), key=lambda g: np.median(fn[g]))
    mode = np.full(len(fn), -1)
    for i, g in enumerate(groups):
        mode[np.isin(column, column[g])] = i
    return tuple(StableMode(float(np.median(fn[g])), float(np.median(zeta[g])), len(g))
                 for g in groups), mode


def _uniform(frf: MeasuredFrf) -> MeasuredFrf:
    """The FRF on a uniform grid (the estimators' discrete-time model): a non-uniform
    file is interpolated linearly onto as many equally spaced lines."""
    f = frf.frequency_hz
    steps = np.diff(f)
    if np.ptp(steps) <= 1e-6 * steps.mean():
        return frf
    grid = np.linspace(f[0], f[-1], len(f))
    h = np.interp(grid, f, frf.receptance.real) + 1j * np.interp(grid, f, frf.receptance.imag)
    return MeasuredFrf(grid, h, dict(frf.source, resampled_to_uniform_grid=True))


def _band(frf: MeasuredFrf, band_hz) -> MeasuredFrf:
    if band_hz is None:
        return frf
    lo, hi = band_hz
    check_range("band low", lo, 0, math.inf, hi_open=True, unit="Hz")
    check_range("band high", hi, lo, math.inf, lo_open=True, hi_open=True, unit="Hz")
    return frf.band(lo, hi)
