"""``boringbar simulate``: one run under harmonic forcing or a regenerative cut."""

from __future__ import annotations

import math
from pathlib import Path

from boringbar._validate import ParameterError, check_int
from boringbar.cli.options import (
    CUT_ONLY,
    Outcome,
    add_common,
    add_cutting,
    check_dt,
    check_gap,
    check_rpm,
    cut_options,
    gap_default_mm,
    initial_conditions,
    one_bar,
    system_overrides,
    wrote,
)
from boringbar.io import save_figure_atomic, write_json_atomic, write_netcdf_atomic
from boringbar.model.dampers import roll_words
from boringbar.model.forcing import Harmonic, Regenerative, check_depth, check_force, check_ratio
from boringbar.model.oriented import geometry_words
from boringbar.model.system import make_system
from boringbar.model.system_file import PUBLISHED_NAME
from boringbar.plot import plot_run
from boringbar.plot.style import system_label
from boringbar.simulate import HISTORY_ROWS, STEADY_FRACTION, fixed_run_step, simulate
from boringbar.simulate.run_limits import check_history, check_steady, check_steps


def add_simulate(sub) -> None:
    p = sub.add_parser("simulate", help="one time-domain run under harmonic forcing or a cut",
                       description="One run; writes DIR/run.nc, DIR/run.png, DIR/summary.json. "
                                   "Harmonic forcing (--force-n, --ratio) by default; "
                                   "--rpm with --depth-mm runs a regenerative cut instead.")
    groups = add_common(p, many=False)
    g = p.add_argument_group("regenerative cutting (instead of harmonic forcing)")
    g.add_argument("--rpm", type=float, metavar="RPM", help="spindle speed in rev/min")
    g.add_argument("--depth-mm", type=float, metavar="MM", help="depth of cut b in mm")
    add_cutting(g)
    g.add_argument("--stop-at-zero", action="store_true",
                   help="end the run when the cutting force first reaches zero (chatter)")
    groups["output"].add_argument("--record-every", type=int, metavar="N",
                   help=f"keep every N-th step in run.nc (default: about {HISTORY_ROWS} rows)")
    p.set_defaults(func=cmd_simulate)


def cmd_simulate(args) -> Outcome:
    bar, friction_on = one_bar(args, "simulate")
    gap = check_gap(gap_default_mm(args) if args.gap_mm is None else args.gap_mm, args)
    forcing = _simulate_forcing(args)
    dt = fixed_run_step(args.dt_s)
    n_steps = check_steps(args.duration_s, dt, ("--duration-s", "--dt-s"))
    record_every = None  # simulate's default: about HISTORY_ROWS rows
    if args.record_every is not None:  # every N-th step: N = 0 means nothing
        record_every = check_int("--record-every", args.record_every, 1, n_steps)
        check_history(n_steps, record_every, "--record-every")

    kw = system_overrides(args)
    if bar == "ball":
        kw.update(gap_m=gap, friction=friction_on)
    system = make_system(bar, args.preset, **kw)
    check_dt(args, [system], getattr(forcing, "ratio", 0.0))
    if isinstance(forcing, Harmonic):
        check_steady(args.duration_s, getattr(args, "steady_fraction", STEADY_FRACTION),
                     2 * math.pi / forcing.omega(system.reference_frequency_rad_s), "--duration-s")
    initial = initial_conditions(args, [gap] if bar == "ball" else [])
    run = simulate(system, forcing, duration_s=args.duration_s, dt_s=dt, initial=initial,
                   record_every=record_every, integrator=args.integrator,
                   stick_law=args.stick_law or "sgn")


    out = Path(args.out)
    files = {"netcdf": out / "run.nc", "png": out / "run.png", "summary": out / "summary.json"}
    ds = run.to_xarray()
    write_netcdf_atomic(ds, files["netcdf"])
    save_figure_atomic(plot_run(ds), files["png"])
    spec = run.system.spec
    summary = {**run.summary(), "system_name": spec.name if spec is not None else
               Path(args.frf).stem if getattr(args, "frf", None) else PUBLISHED_NAME,
               "files": {k: str(v) for k, v in files.items()}}
    write_json_atomic({**summary, "config": run.config()}, files["summary"])

    def text(say) -> None:
        say(_cut_text(summary, run) if "cutting" in summary else _simulate_text(summary, run))

    return Outcome(summary, text)


def _simulate_forcing(args):
    """Harmonic(F0, ratio), or Regenerative when --rpm and --depth-mm are given."""

    if args.rpm is not None:
        check_rpm(args.rpm, args)
    if args.depth_mm is not None:
        check_depth(args.depth_mm, "--depth-mm")
    if args.rpm is None and args.depth_mm is None:
        given = [o for o in CUT_ONLY if getattr(args, o) not in (None, False)]
        if given:
            raise ParameterError(f"--{given[0].replace('_', '-')} applies only to a cut "
                                 "(--rpm with --depth-mm)")
        force = 10.0 if args.force_n is None else args.force_n
        ratio = 1.0 if args.ratio is None else args.ratio
        return Harmonic(check_force(force), check_ratio(ratio))
    if args.rpm is None or args.depth_mm is None:
        have, need = ("--rpm", "--depth-mm") if args.depth_mm is None else ("--depth-mm",
                                                                            "--rpm")
        raise ParameterError(f"{have} needs {need}: a cut takes both")
    for name, value in (("--force-n", args.force_n), ("--ratio", args.ratio)):
        if value is not None:
            raise ParameterError(f"{name} = {value:g} is harmonic forcing and cannot be mixed "
                                 "with a cut (--rpm, --depth-mm): give one or the other")
    return Regenerative(depth_m=args.depth_mm * 1e-3, rpm=args.rpm,
                        stop_at_zero=args.stop_at_zero, **cut_options(args))


def _named(s: dict) -> str:
    """'ball bar of published bar', 'tmd bar of mybar': which bar of which file."""
    return f"{s['bar']} bar of {system_label(s['system_name'])}"


def _cut_text(s: dict, run) -> str:
    c = s["cutting"]
    cfg = "static start" if c["start"] == "static" else "from rest"
    lines = [
        f"{_named(s)}, {s['preset']} preset: cut at {c['rpm']:g} rpm "
        f"({s['forcing_frequency_hz']:.2f} Hz), depth {c['depth_m'] * 1e3:g} mm, {cfg}",
        f"  natural frequency  {s['natural_frequency_hz']:.2f} Hz",
    ]
    if c["chatter"]:
        lines.append(f"  verdict            CHATTER: the force first reaches zero at "
                     f"t = {c['first_zero_time_s']:.4g} s (the tool leaves the cut)")
    else:
        lines.append(f"  verdict            stable: the force never reaches zero in "
                     f"{s['duration_s']:g} s")
    lines += [
        f"  bounded chatter    {'yes' if c['bounded_chatter'] else 'no'} (steady amplitude "
        f"{c['amplitude_m'] * 1e3:.4g} mm, threshold {c['bounded_threshold_m'] * 1e3:.4g} mm)",
        f"  cutting law        {c['cutting_law']}"
        + (f", force noise {c['force_noise']:g}" if c["force_noise"] else ""),
        f"  cutting force      mean {c['mean_force_n']:.4g} N, max {c['max_force_n']:.4g} N "
        f"({c['steps_with_zero_force']} steps at zero)",
        f"  tip                static deflection {c['static_deflection_m'] * 1e3:.4g} mm, "
        f"max |W| {s['max_abs_tip_m'] * 1e3:.4g} mm",
        f"  delay interp.      {c['delay_interpolation']}",
        *_hardware_lines(run),
        *([contact_text(s["contact"])] if s.get("contact") else []),
        f"  integrator         {s['integrator']}",
        f"  elapsed            {s['elapsed_s']:.2f} s",
        "  " + wrote(s["files"]),
    ]
    return "\n".join(lines)


def contact_text(c: dict) -> str:
    """A Hertz contact's line of the summary: its impacts' durations and peak forces."""
    head = f"  Hertz contact      K = {c['stiffness_n_m1_5']:.3g} N/m^1.5"
    if not c["rows_kept"]:
        return head + f", largest force {c['max_force_whole_run_n']:.4g} N"
    if not c["n_impacts"]:
        return head + ", no impact in the steady part"
    return (head + f", {c['n_impacts']} impacts: {c['duration_median_s'] * 1e6:.3g} us "
            f"(max {c['duration_max_s'] * 1e6:.3g}), peak force {c['peak_force_median_n']:.4g} N "
            f"(max {c['peak_force_max_n']:.4g}), v_out/v_in {c['restitution_ratio']:.3g}")


def _hardware_lines(run) -> list[str]:
    """What the run's bar has beyond the published one: a rolling ball, two planes."""
    d, lines = run.system.damper, []
    if getattr(d, "motion", "slide") == "roll" and not d.locked:
        lines.append(f"  ball               rolling, {roll_words(d.mu_static, d.mu_kinetic)}")
    geometry = run.system.bar.info.get("cut_geometry")
    if geometry:
        lines.append(f"  two planes         {geometry_words(geometry, run.system.kind)}")
    return lines


def _simulate_text(s: dict, run) -> str:
    lines = [
        f"{_named(s)}, {s['preset']} preset: F0 = {s['force_n']:g} N, "
        f"Omega/omega_n = {s['ratio']:.4g} ({s['forcing_frequency_hz']:.2f} Hz)",
        f"  natural frequency  {s['natural_frequency_hz']:.2f} Hz",
        f"  tip RMS            {s['rms_tip_m'] * 1e3:.4g} mm (steady part)",
        f"  max |tip|          {s['max_abs_tip_m'] * 1e3:.4g} mm",
    ]
    if s["bar"] == "ball":
        lines.append(f"  pattern            {s['pattern']} "
                     f"({s['impacts_per_cycle']:.3g} impacts per cycle)")
        lines.append(f"  max |y|            {s['max_abs_rel_disp_m'] * 1e3:.4g} mm "
                     f"(walls at +-{run.system.damper.gap_m / 2 * 1e3:g} mm)")
    elif s["bar"] == "tmd":
        lines.append(f"  max stroke         {s['max_abs_rel_disp_m'] * 1e3:.4g} mm")
    lines += _hardware_lines(run)
    if s.get("contact"):
        lines.append(contact_text(s["contact"]))
    if s["readings"]:
        lines.append(f"  published readings {', '.join(s['readings'])}")
    lines.append(f"  integrator         {s['integrator']}")
    lines.append(f"  elapsed            {s['elapsed_s']:.2f} s")
    lines.append("  " + wrote(s["files"]))
    return "\n".join(lines)
