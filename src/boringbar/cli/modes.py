"""``boringbar modes``: the modal model of a bar (a system file, the published bar, or
a fitted FRF), printed, saved as JSON and drawn over the bar's geometry."""

from __future__ import annotations

from pathlib import Path

from boringbar._validate import check_int
from boringbar.cli.options import OUT_HELP, Outcome, default_bars, resolve_files, wrote
from boringbar.cli.orientation import add_orientation, check_orientation, orientation_overrides
from boringbar.io import save_figure_atomic, write_json_atomic
from boringbar.model.system import BAR_KINDS, PRESETS, describe_modes, make_system
from boringbar.plot.bar import plot_modes

#: Most modes ``modes`` prints and draws.
MAX_MODES = 8


def add_modes(sub) -> None:
    p = sub.add_parser("modes", help="the modal model of a bar, and its mode shapes",
                       description="The bar's bending modes: frequency, modal mass and "
                                   "stiffness referred to the tip, and the mode shape at the "
                                   "tip, the ball and the absorber; the tip's static "
                                   "stiffness. Writes DIR/modes.json and DIR/modes.png (the "
                                   "shapes over the bar's geometry).")
    p.add_argument("--system", metavar="FILE.toml",
                   help="a system file (default: the published bar)")
    p.add_argument("--frf", metavar="FIT.json", help="a fitted tip FRF (boringbar fit-frf) "
                   "in place of the FE bar (no geometry figure)")
    p.add_argument("--frf-ball-ratio", type=float, metavar="R")
    p.add_argument("--frf-absorber-ratio", type=float, metavar="R")
    p.add_argument("--bar", choices=BAR_KINDS,
                   help="ball: with the cavity; solid or tmd: without it (default: ball if "
                        "the system has one, else tmd, else solid)")
    p.add_argument("--preset", choices=PRESETS, default="physical",
                   help="paper: calibrated to the published frequencies where the file "
                        "says so")
    p.add_argument("--modes", type=int, default=3, metavar="N",
                   help=f"modes to show, 1 to {MAX_MODES} (default: 3); with --planes 2, "
                        f"of each plane, 1 to {MAX_MODES // 2}")
    add_orientation(p)
    p.add_argument("--out", metavar="DIR", help=OUT_HELP)
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_modes)


def cmd_modes(args) -> Outcome:
    args.bar = args.bar or default_bars(args, many=False)[0]
    check_orientation(args, [args.bar])
    resolve_files(args, [args.bar])
    oriented = orientation_overrides(args)
    two = oriented.get("planes", 1 if args.system_spec is None else args.system_spec.planes) == 2
    n = check_int("--modes", args.modes, 1, MAX_MODES // 2 if two else MAX_MODES)
    kw = {"spec": args.system_spec, "modal": args.frf_modal, "n_modes": n, **oriented}
    if args.frf_modal is not None and args.frf_modal.n_modes < n:
        kw["n_modes"] = args.frf_modal.n_modes
    system = make_system(args.bar, args.preset, **kw)
    spec = system.spec
    table = describe_modes(system)
    retained = make_system(args.bar, args.preset, **{**kw, "n_modes": None}).bar.n_modes
    out = Path(args.out)
    files = {"json": out / "modes.json"}
    if args.frf_modal is None:
        files["png"] = out / "modes.png"
        plane = f", the plane at {table['built_plane_deg']:g} deg" if two else ""
        save_figure_atomic(plot_modes(spec, args.bar == "ball", n,
                                      f"{spec.name} ({args.bar} bar): mode shapes{plane}"),
                           files["png"])
    summary = {"system": spec.name if args.frf_modal is None else args.frf,
               "bar": args.bar, "preset": args.preset, **table, "runs_retain": retained,
               "system_file": spec.to_dict() if args.frf_modal is None else None,
               "files": {k: str(v) for k, v in files.items()}}
    write_json_atomic(summary, files["json"])

    def text(say) -> None:
        say(f"{summary['system']} ({args.bar} bar, {args.preset} preset): "
            f"{len(table['modes'])} modes, {table['source']}")
        say("  mode  " + ("plane (deg)  " if two else "") +
            "f (Hz)      m_tip (kg)  k_tip (N/m)  zeta    psi_ball  psi_absorber")
        for i, m in enumerate(table["modes"]):
            plane = f"{m['plane_deg']:<11.4g}  " if two else ""
            say(f"  {i + 1:<4}  {plane}{m['frequency_hz']:<10.2f}  {m['modal_mass_kg']:<10.4g}  "
                f"{m['modal_stiffness_n_m']:<11.4g}  {m['damping_ratio']:<6.3g}  "
                f"{_psi(m['psi_ball']):<8}  {_psi(m['psi_absorber'])}")
        say(f"  tip static stiffness {table['tip_static_stiffness_n_m']:.4g} N/m "
            f"({table['tip_static_stiffness_from']})")
        say(f"  the other commands retain {retained} of these modes by default (--modes "
            "changes it)")
        if two:
            say("  each mode in its own plane (degrees from the radial direction); the cut "
                "and the ball see it projected (docs/model.md, 4.7)")
        say("  " + wrote(summary["files"]))

    return Outcome(summary, text)


def _psi(value) -> str:
    return "-" if value is None else f"{value:.4g}"
