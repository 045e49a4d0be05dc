"""The command line's options of two bending planes and the oriented cut
(docs/model.md, section 4.7): their arguments, their checks against the bars a command
runs, and make_system's keywords from them."""

from __future__ import annotations

from dataclasses import replace

from boringbar._validate import ParameterError
from boringbar.model.oriented import APPLIES_TO, CutGeometry, check_geometry

#: --planes and the oriented cut's options, by CutGeometry field
ORIENTATION_OPTIONS = {"force_ratio": "--force-ratio", "lead_angle_deg": "--lead-angle-deg",
                       "hole_angle_deg": "--hole-angle-deg",
                       "principal_angle_deg": "--principal-angle-deg",
                       "stiffness_ratio": "--stiffness-ratio"}


def add_orientation(p) -> None:
    """Two bending planes and the oriented cut (docs/model.md, section 4.7)."""
    g = p.add_argument_group("two bending planes and an oriented cut (docs/model.md, 4.7)")
    g.add_argument("--planes", type=int, choices=(1, 2),
                   help="bending planes: 1 (the published one direction) or 2 (default: the "
                        "system file's [orientation], else 1; 2 with any option below)")
    g.add_argument("--force-ratio", type=float, metavar="KT/KR",
                   help="tangential over edge-normal cutting coefficient, in [0, 100] "
                        "(default 0: the published radial force)")
    g.add_argument("--lead-angle-deg", type=float, metavar="DEG",
                   help="the edge normal's angle from the radial direction, in [0, 90) "
                        "(default 0: the published cut)")
    g.add_argument("--hole-angle-deg", type=float, metavar="DEG",
                   help="the ball cavity's axis in the section (a TMD's absorber moves "
                        "along it too), from the radial direction, in [-90, 90] (default 0)")
    g.add_argument("--principal-angle-deg", type=float, metavar="DEG",
                   help="the bar's first principal bending plane, in [-90, 90] (default 0)")
    g.add_argument("--stiffness-ratio", type=float, metavar="R",
                   help="EI of the second bending plane over the first's, in (0, 1000] "
                        "(default 1: a round bar)")


def check_orientation(args, bars: list[str]) -> None:
    """The oriented cut's options, each in its range (CutGeometry's) and used by one of
    ``bars`` at least (oriented.APPLIES_TO)."""
    for field, option in ORIENTATION_OPTIONS.items():
        value = getattr(args, field, None)
        if value is None:
            continue
        check_geometry(field, value, option)
        users = APPLIES_TO.get(field, bars)
        if not set(users) & set(bars):
            raise ParameterError(f"{option} = {value:g} applies to the {' and '.join(users)} "
                                 f"bars, and --bar is {','.join(bars)}")


def orientation_overrides(args) -> dict:
    """make_system's ``planes`` and ``cut_geometry`` from the options given (the system
    file's orientation for the rest); empty if none is given."""
    given = {k: getattr(args, k) for k in ORIENTATION_OPTIONS
             if getattr(args, k, None) is not None}
    planes = getattr(args, "planes", None)
    if not given:
        return {} if planes is None else {"planes": planes}
    if planes == 1:
        raise ParameterError(f"{ORIENTATION_OPTIONS[next(iter(given))]} applies to a bar of "
                             "two bending planes: give --planes 2 (or leave it out)")
    spec = getattr(args, "system_spec", None)
    base = spec.orientation if spec is not None else CutGeometry()
    return {"planes": 2, "cut_geometry": replace(base, **given)}
