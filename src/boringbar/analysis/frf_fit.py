"""Modal parameters from a measured tip FRF, with sdypy-EMA (LSCE or LSCF poles, LSFD
constants).

The fit is sdypy-EMA's, not ours. We add only what a fit without a person at a
stabilisation chart needs, and the conversion to boringbar's modal model:

1. **Band.** The lines in ``band_hz`` (default: the whole measurement above
   its first line).
2. **Poles.** sdypy's poles for model orders up to ``max_order`` (default 20;
   ``Model.get_poles``): LSCE (least-squares complex exponential, in the time
   domain through the impulse response) when the band starts near 0 Hz (below
   5 % of its top), else LSCF (least-squares complex frequency domain), which
   takes any band. LSCE first because LSCF, a linear least-squares estimator, is
   biased by noise in damping: 1.2-1.4 % on the test bar's second mode at 1 %
   noise, where LSCE stays within 0.3 %. Both need equally spaced lines; a
   non-uniform file is interpolated onto as many.
3. **Which poles.** The stable poles of the stabilisation chart that sit closest
   to the ``n_modes`` most prominent peaks of |H|; "stable" means frequency
   within 0.1 % and damping within 5 % from one order to the next, sdypy's own
   criterion (``Model.select_closest_poles``). This rule stands in for the
   person at the chart. It finds lightly damped modes that stand out of the
   noise, and a fit it does not know is refused rather than guessed: fewer
   peaks than modes asked is an error.
4. **Constants.** LSFD modal constants with lower and upper residuals
   (``Model.get_constants``).
5. **Our modal model.** A receptance mode reads
   A/(i w - lambda) + conj(A)/(i w - conj(lambda)), with lambda = -zeta w_n + i w_d.
   For a real (proportionally damped) mode of tip stiffness k that is
   w_n^2 / (k (w_n^2 - w^2 + 2 i zeta w_n w)), so A = -i w_n^2 / (2 k w_d) and
   k = w_n^2 / (2 w_d (-Im A)). The part of A that is not imaginary (a complex
   mode, or noise) is dropped, and its size goes into the quality figures
   (``complexity``) beside the fit's relative residual over the band.
"""

from __future__ import annotations

import contextlib
import io
import math
import warnings
from dataclasses import replace

import numpy as np
import scipy.signal
from sdypy import EMA
from sdypy.EMA.EMA import LSFD

from boringbar._validate import ParameterError, check_int, check_range
from boringbar.model.measured_frf import MeasuredFrf
from boringbar.model.modal_fit import ModalFit

#: Highest model order tried by default.
MAX_ORDER = 20
#: The pole estimator is LSCE (time domain, through the impulse response) when the
#: band starts below this fraction of its top, else LSCF (any band).
LSCE_START = 0.05
#: How far a peak of |H| must stand above its surroundings to count as a mode.
PEAK_FACTOR = 2.0
#: A fit whose relative residual over the band is above this is said to be poor.
POOR_FIT = 0.1
#: sdypy's stability tolerances: relative frequency and damping change per order.
STABLE_FREQUENCY = 1e-3
STABLE_DAMPING = 5e-2


def fit_frf(frf: MeasuredFrf, n_modes: int = 1, *, band_hz: tuple | None = None,
            max_order: int = MAX_ORDER) -> tuple[ModalFit, np.ndarray]:
    """Fit ``n_modes`` modes to the measured tip receptance ``frf`` in ``band_hz``
    (Hz, default the whole measurement): (the :class:`ModalFit`, its receptance at
    the band's measured lines)."""
    n = check_int("n_modes", n_modes, 1, 8)
    check_int("max_order", max_order, 2 * n + 2, 200)
    band = _band(frf, band_hz)
    data = _uniform(band)  # what the estimators take; the fit is judged on the band's lines
    peaks = _peaks(data, n)
    f = data.frequency_hz
    method = "lsce" if f[0] <= LSCE_START * f[-1] else "lscf"
    model = EMA.Model(frf=data.receptance[None, :], freq=f,
                      lower=0.0 if method == "lsce" else float(f[0]), upper=float(f[-1]),
                      pol_order_high=int(max_order), frf_form="receptance")
    # sdypy's stabilisation chart always draws a tqdm bar on stderr: keep it off ours
    with warnings.catch_warnings(), contextlib.redirect_stderr(io.StringIO()):
        warnings.simplefilter("ignore")
        model.get_poles(method=method, show_progress=False)
        model.select_closest_poles(list(peaks), fn_temp=STABLE_FREQUENCY,
                                   xi_temp=STABLE_DAMPING)
        poles = np.array([model.all_poles[i][j] for i, j in np.asarray(model.pole_ind)])
        # LSFD on the measured lines themselves (the model's grid may start at 0 Hz,
        # where the lower residual term is singular)
        constants = LSFD(poles, data.receptance[None, :], f, True, True, 0, len(f),
                         "receptance")[0]
    f_n = np.asarray(model.nat_freq, dtype=float)
    zeta = np.asarray(model.nat_xi, dtype=float)
    order = np.argsort(f_n)
    f_n, zeta, a = f_n[order], zeta[order], np.asarray(constants)[0, order]
    w_n = 2 * math.pi * f_n
    w_d = w_n * np.sqrt(1 - zeta**2)
    if np.any(-a.imag <= 0) or np.any(zeta <= 0):
        raise ParameterError(f"{frf.source.get('file', 'FRF')}: a fitted mode has a "
                             "non-physical constant (negative stiffness or damping); try "
                             "--band-hz around the modes, or fewer --modes")
    k = w_n**2 / (2 * w_d * (-a.imag))
    fit = ModalFit(tuple(f_n), tuple(zeta), tuple(k))
    h_fit = fit.tip_frf(band.frequency_hz)
    residual = float(np.linalg.norm(h_fit - band.receptance) / np.linalg.norm(band.receptance))
    quality = {"relative_residual": residual,
               **({"warning": f"relative residual {residual:.2g} > {POOR_FIT:g}: the modes "
                              "do not explain this FRF; try --band-hz or another --modes"}
                  if residual > POOR_FIT else {}),
               "complexity": (np.abs(a.real) / np.abs(a)).tolist(),
               "peaks_hz": sorted(float(p) for p in peaks)}
    source = {**frf.source, "method": f"sdypy-EMA {method.upper()} poles + LSFD constants",
              "max_order": int(max_order), "band_hz": [float(data.frequency_hz[0]),
                                                       float(data.frequency_hz[-1])],
              "pole_selection": "stable poles closest to the most flexible clear peaks of |H|"}
    return replace(fit, source=source, quality=quality), h_fit


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


def clear_peaks(frf: MeasuredFrf) -> np.ndarray:
    """The frequencies (Hz) of the clear peaks of |H|, most flexible (highest |H|)
    first: a peak counts if it stands a factor PEAK_FACTOR above its surroundings on a
    log scale (a stiff higher mode as well as the first; noise of a few per cent does
    not)."""
    mag = np.abs(frf.receptance)
    idx, _ = scipy.signal.find_peaks(np.log(mag), prominence=math.log(PEAK_FACTOR))
    return frf.frequency_hz[idx[np.argsort(mag[idx])[::-1]]]


def _peaks(frf: MeasuredFrf, n: int) -> np.ndarray:
    """The ``n`` most flexible clear peaks (Hz, ascending): those that set chatter."""
    peaks = clear_peaks(frf)
    if len(peaks) < n:
        raise ParameterError(f"{frf.source.get('file', 'FRF')}: {len(peaks)} clear peak(s) "
                             f"in the band, fewer than the {n} modes asked for")
    return np.sort(peaks[:n])
