"""Measured FRFs on the command line: ``boringbar fit-frf`` (modal parameters of a
measured tip FRF, with sdypy-EMA) and ``boringbar lobes --analytic`` (the classical
frequency-domain lobes, from a measured FRF as it is, or from a bar's model)."""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np

from boringbar._validate import ParameterError, check_int, check_positive
from boringbar.analysis.cases import parse_range
from boringbar.analysis.frf_fit import (
    MAX_MODES,
    MAX_ORDER,
    MIN_ORDER,
    fit_modes,
    stabilisation,
)
from boringbar.analysis.speeds import default_speeds, lobe_speeds
from boringbar.cli.options import (
    OUT_HELP,
    Outcome,
    many_cases,
    resolve_files,
    system_spec,
    warn_line,
    with_speed,
    wrote,
)
from boringbar.cli.orientation import orientation_overrides
from boringbar.io import save_figure_atomic, write_json_atomic
from boringbar.model.cutting import CuttingLaw
from boringbar.model.forcing import MIN_LOBE_RPM, check_lobe_speed
from boringbar.model.frf_units import (
    ImplausibleFrfWarning,
    implausible_frf,
    plausibility_warning,
)
from boringbar.model.measured_frf import read_frf
from boringbar.plot.bar import plot_frf_fit, plot_stabilisation
from boringbar.plot.lobes import plot_analytic_lobes
from boringbar.plot.style import system_label
from boringbar.reference.stability import (
    GRID_SPAN,
    TWO_PI,
    limit_at_speeds,
    linear_host,
    lobes_of_receptance,
    min_limit,
    natural_frequencies,
    sampled_limits,
    system_receptance,
)

#: Speeds at which the figure's lower envelope is evaluated.
ENVELOPE_SPEEDS = 1000


def add_fit_frf(sub) -> None:
    p = sub.add_parser("fit-frf", help="fit modes to a measured tip FRF (tap test)",
                       description="Find the modes of a measured tip receptance with a "
                                   "stabilisation diagram and fit their modal parameters "
                                   "(frequency, damping ratio, tip stiffness) with "
                                   "sdypy-EMA (LSCE or LSCF poles, LSFD constants; "
                                   "docs/frf.md). FILE: CSV (frequency, and real "
                                   "and imaginary parts or magnitude and phase, each "
                                   "column's unit in the header: 'f [kHz]', "
                                   "'Re [um/N]'...; without a header Hz and m/N) or "
                                   "UFF dataset 58. Writes "
                                   "DIR/modal_fit.json (what --frf reads), DIR/fit.png "
                                   "(measured against fitted) and DIR/stabilisation.png "
                                   "(the diagram).")
    p.add_argument("file", metavar="FILE", help="the measured FRF (.csv, .txt, .uff, .unv)")
    p.add_argument("--modes", type=int, metavar="N",
                   help=f"modes to fit, 1 to {MAX_MODES} (default: every mode of the "
                        f"stabilisation diagram, at most {MAX_MODES}); fewer than the "
                        "diagram finds take the most flexible")
    p.add_argument("--band-hz", metavar="LO:HI", help="fit within this band (default: all)")
    p.add_argument("--max-order", type=int, default=MAX_ORDER, metavar="N",
                   help=f"highest model order of the stabilisation diagram, {MIN_ORDER} "
                        f"to 200 (default: {MAX_ORDER})")
    p.add_argument("--out", metavar="DIR", help=OUT_HELP)
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_fit_frf)


def cmd_fit_frf(args) -> Outcome:
    band = None if args.band_hz is None else _band(args.band_hz)
    n = None if args.modes is None else check_int("--modes", args.modes, 1, MAX_MODES)
    max_order = check_int("--max-order", args.max_order, MIN_ORDER, 200)
    diagram = stabilisation(read_frf(args.file), band_hz=band, max_order=max_order)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ImplausibleFrfWarning)  # said in one line below
        fit, fitted = fit_modes(diagram, n)
    if "implausible" in fit.quality:
        warn_line(fit.quality["implausible"])
    out = Path(args.out)
    files = {"json": out / "modal_fit.json", "png": out / "fit.png",
             "stabilisation": out / "stabilisation.png"}
    write_json_atomic(fit.to_dict(), files["json"])
    data = diagram.frf
    save_figure_atomic(plot_frf_fit(data.frequency_hz, data.receptance, fitted, fit),
                       files["png"])
    save_figure_atomic(plot_stabilisation(diagram, fit.frequency_hz), files["stabilisation"])
    summary = {**fit.to_dict(), "files": {k: str(v) for k, v in files.items()}}

    def text(say) -> None:
        found = len(diagram.modes)
        say(f"{args.file}: {fit.n_modes} mode(s) fitted by {fit.source['method']}; the "
            f"stabilisation diagram finds {found} in the band"
            + ("" if fit.n_modes == found else " (the most flexible taken)"))
        if "units" in fit.source:
            say(f"  read as {fit.source['units']}; conversion: {fit.source['conversion']}")
        say("  mode  f (Hz)      zeta       k_tip (N/m)")
        for i, m in enumerate(summary["modes"]):
            say(f"  {i + 1:<4}  {m['frequency_hz']:<10.2f}  {m['damping_ratio']:<9.4g}  "
                f"{m['modal_stiffness_n_m']:.4g}")
        say(f"  relative residual {fit.quality['relative_residual']:.3g} over the band"
            + (f" -- warning: {fit.quality['warning']}" if "warning" in fit.quality else ""))
        say("  " + wrote(summary["files"]))

    return Outcome(summary, text)


def _band(text: str) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in text.split(":"))
    except ValueError:
        raise ParameterError(f"--band-hz = {text!r} must be LO:HI in Hz") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo < hi):
        raise ParameterError(f"--band-hz = {text!r} must be LO:HI with 0 <= LO < HI")
    return lo, hi


def analytic_lobes_outcome(args, law: CuttingLaw, feed_m: float) -> Outcome:
    """``lobes --analytic``: the classical lobes of each case's tip FRF, or of the
    measured FRF of --frf as it is, with the slope of the cutting ``law`` at the feed
    ``feed_m`` (m) for Kr; no time-domain cut is simulated.  With --at-rpm, that speed
    is among the speeds (and the figure's), each case's depth there read out."""
    kr = law.linear_coefficient_pa(feed_m)
    check_positive("--kr-mpa", kr * 1e-6, "MPa")
    at = None if args.at_rpm is None else check_lobe_speed("--at-rpm", args.at_rpm)
    resolve_files(args, [])
    if (getattr(args, "frf_measured", None) is not None
            and orientation_overrides(args).get("planes", 1) == 2):
        raise ParameterError("--planes and the oriented cut's options apply to a bar's "
                             "modes; a measured FRF is used as it is: measure it oriented "
                             "(tap along the cutting force, read the response along the "
                             "chip's thickness), or fit its modes (boringbar fit-frf)")
    rpm = parse_range(args.rpm, "--rpm") if args.rpm else analytic_speeds(args)
    for r in rpm:
        check_lobe_speed("--rpm", r)
    rpm = np.asarray(with_speed(rpm, at), dtype=float)
    lo, hi = ((rpm.min(), rpm.max()) if len(rpm) > 1
              else (max(0.8 * rpm[0], MIN_LOBE_RPM), 1.2 * rpm[0]))
    # evenly in log rpm, as the figure's speed axis (linear over a narrow range, where
    # the two hardly differ): every part of the axis drawn as finely
    dense = np.asarray(with_speed(np.geomspace(lo, hi, ENVELOPE_SPEEDS), at), dtype=float)
    j = None if at is None else int(np.flatnonzero(rpm == at)[0])
    rows, curves = [], []
    for names, w, g, limits in _distinct(_sources(args, kr, rpm, dense)):
        row = {"case": names[1], "min_limit_m": limits["min_limit"],
               "frequency_hz": limits["frequency_hz"],
               "speeds": [{"rpm": float(r), "limit_m": float(b)}
                          for r, b in zip(rpm, limits["limit"], strict=True)]}
        curves.append({"label": names[1], "name": names[0], "kind": names[2],
                       "lobes": lobes_of_receptance(w, g, kr), "rpm": dense,
                       "limit_m": limits["envelope"]})
        if j is not None:
            row["depth_at_rpm_m"] = curves[-1]["depth_at_rpm_m"] = float(limits["limit"][j])
        rows.append(row)
    out = Path(args.out)
    files = {"json": out / "lobes_analytic.json", "png": out / "lobes_analytic.png"}
    summary = {"method": "analytic", "kr_pa": kr, "cutting_law": law.describe(),
               **({"at_rpm": at} if at is not None else {}), "cases": rows,
               "files": {k: str(v) for k, v in files.items()}}
    measured, spec = getattr(args, "frf_measured", None), system_spec(args)
    if measured is not None:
        summary["measured_frf"] = _plausible_source(measured)
    name = (f"measured FRF {Path(args.frf).name}" if measured is not None
            else f"modal fit {Path(args.frf).name}" if getattr(args, "frf", None)
            else system_label(spec.name) if spec is not None else "published bar")
    save_figure_atomic(plot_analytic_lobes(curves, (float(lo), float(hi)), name=name,
                                           at_rpm=at), files["png"])
    write_json_atomic(summary, files["json"])

    def text(say) -> None:
        for row in rows:
            mine = ("" if at is None else
                    f"; at your speed {at:g} rpm: {row['depth_at_rpm_m'] * 1e3:.4g} mm")
            say(f"{row['case']}: speed-independent limit {row['min_limit_m'] * 1e3:.4g} mm "
                f"(chatter at {row['frequency_hz']:.1f} Hz){mine}")
            for s in row["speeds"][:12]:
                say(f"  {s['rpm']:8g} rpm  {s['limit_m'] * 1e3:.4g} mm")
            if len(row["speeds"]) > 12:
                say(f"  ... {len(row['speeds'])} speeds in {files['json']}")
        say(wrote(summary["files"]))

    return Outcome(summary, text)


def _plausible_source(measured) -> dict:
    """The measured FRF's ``source``, with (and said on stderr) what in it no boring bar
    has, if anything."""
    found = implausible_frf(measured.frequency_hz, measured.receptance)
    if not found:
        return dict(measured.source)
    message = plausibility_warning(measured.source.get("file", "FRF"), found, measured.source)
    warn_line(message)
    return {**measured.source, "implausible": message}


def analytic_speeds(args) -> tuple[float, ...]:
    """``lobes --analytic``'s speeds without --rpm: the first lobes of each case's bar
    (:func:`~boringbar.analysis.lobes.default_speeds`, as the simulated lobes take
    them), or of a measured FRF's most flexible mode (its peak |G|)."""
    measured = getattr(args, "frf_measured", None)
    if measured is not None:
        peak = int(np.argmax(np.abs(measured.receptance)))
        return lobe_speeds([measured.omega[peak] / (2 * math.pi)])
    return default_speeds(many_cases(args)[0], getattr(args, "workpiece", None))


def _sources(args, kr, rpm, dense):
    """(label, bar kind or None, w rad/s, tip receptance, limits) of the measured FRF or
    of each case."""
    measured = getattr(args, "frf_measured", None)
    if measured is not None:
        w, g = measured.omega, measured.receptance
        limits = sampled_limits(w, g, rpm, kr)
        limits["envelope"] = sampled_limits(w, g, dense, kr)["limit"]
        yield f"measured FRF {Path(args.frf).name}", None, w, g, limits
        return
    cases, _, _ = many_cases(args)
    for case in cases:
        wn = natural_frequencies(*linear_host(case.system))
        w = np.geomspace(GRID_SPAN[0] * wn.min(), GRID_SPAN[1] * wn.max(), 20000)
        g = system_receptance(case.system, w)
        low = min_limit(case.system, kr)
        at = np.argmin(g.real)
        limits = {"min_limit": low, "frequency_hz": float(w[at] / TWO_PI),
                  "limit": limit_at_speeds(case.system, rpm, kr),
                  "envelope": sampled_limits(w, g, dense, kr)["limit"]}
        yield case.label, case.system.kind, w, g, limits


def _distinct(sources):
    """The sources with distinct FRFs, each as ((its first label, the labels joined, its
    bar kind), w, g, limits): the free-ball cases share one (in the linear limit the
    ball does not touch the bar)."""
    out, labels = [], []
    for label, kind, w, g, limits in sources:
        same = next((i for i, o in enumerate(out) if o[2].shape == g.shape
                     and np.array_equal(o[2], g)), None)
        if same is None:
            out.append((kind, w, g, limits))
            labels.append([label])
        else:
            labels[same].append(label)
    return [((names[0], names[0] + (f" (and {len(names) - 1} more with the same FRF)"
                                    if len(names) > 1 else ""), kind), *rest)
            for names, (kind, *rest) in zip(labels, out, strict=True)]
