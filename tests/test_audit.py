"""The reproduction audit: every check on small synthetic step summaries, one per
verdict it can give; the claims file; ``boringbar audit`` and the report's table on a
real (quick) paper output."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
import xarray as xr
from cli_output import assert_one_line_error

from boringbar.cli.main import main
from boringbar.model.system import make_system
from boringbar.report.audit import load_claims
from boringbar.report.audit_checks import CHECKS, basin_threshold, code
from boringbar.report.audit_data import Verdict

R = [0.96, 0.98, 1.0, 1.02, 1.04]
SHAPE = [0.3, 0.5, 1.0, 0.5, 0.3]  # a resonance peaking at r = 1


class Fake:
    """Step summaries by key, as a paper output would hold them (one preset)."""

    def __init__(self, steps: dict):
        self.steps = steps

    def summary(self, preset, key):
        return self.steps.get(key)

    def figure(self, preset, key, which=None):
        return f"{key}.png" if key in self.steps else None


def case(bar, force, rms_mm, patterns=None, gap=None, friction="n/a", f1=456.0) -> dict:
    return {"case": bar, "bar": bar, "gap_m": None if gap is None else gap * 1e-3,
            "friction": friction, "force_n": force, "natural_frequency_hz": f1, "ratio": R,
            "rms_tip_m": [v * 1e-3 for v in rms_mm], "pattern": list(patterns or [""] * 5)}


def scaled(k: float, shape=SHAPE) -> list:
    return [k * v for v in shape]


def sweep(tmp_path=None, **ball) -> dict:
    """A sweep like the published one: solid (peak 1 mm at r = 1 at 10 N), TMD (flat,
    88.5 % below), four ball cases per force, each given as
    ball[(gap, friction, force)] = (rms list, patterns) or NI at the solid's level."""
    cases = [case("solid", 10.0, scaled(1.0)), case("solid", 20.0, scaled(2.0)),
             case("tmd", 10.0, [0.110, 0.113, 0.115, 0.113, 0.110]),
             case("tmd", 20.0, [0.220, 0.226, 0.230, 0.226, 0.220])]
    for gap in (0.5, 0.1):
        for fr in ("off", "on"):
            for force in (10.0, 20.0):
                rms, pats = ball.get(f"g{str(gap).replace('.', '_')}_{fr}_{force:g}",
                                     (scaled(force / 10), ["no impact"] * 5))
                cases.append(case("ball", force, rms, pats, gap, fr, f1=461.0))
    s = {"cases": cases, "files": {"png": ["sweep_F10N.png"]}}
    if tmp_path is not None:
        s["files"]["netcdf"] = str(tmp_path / "sweep.nc")
    return s


def write_systems(tmp_path, ball_mass=None) -> None:
    d = make_system("ball", "paper").to_dict()
    if ball_mass is not None:
        d["damper"]["mass_kg"] = ball_mass
    ds = xr.Dataset(attrs={"systems": json.dumps({"ball gap=0.5mm friction=on": d})})
    ds.to_netcdf(tmp_path / "sweep.nc")


NU, NI = "non-uniform", "no impact"


def judge(claim: str, steps: dict) -> Verdict:
    return CHECKS[claim](Fake(steps), "paper")


# --- harmonic claims: (claim, steps builder, expected verdict) ---------------------------
def harmonic_cases(tmp_path):
    right = scaled(1.0, [0.3, 0.4, 0.6, 1.0, 0.5])  # peak at r = 1.02
    left = scaled(1.0, [0.4, 1.0, 0.6, 0.4, 0.3])  # peak at r = 0.98
    solid_f = {"cases": None}
    yield "H1", {"sweep": sweep()}, "reproduced"
    s = sweep()
    for c in s["cases"]:
        c["natural_frequency_hz"] *= 517 / 456
    yield "H1", {"sweep": s}, "partly"
    s = sweep()
    s["cases"][0]["rms_tip_m"] = [v * 1e-3 for v in scaled(1.0, [0.3, 1.0, 0.6, 0.5, 0.3])]
    yield "H1", {"sweep": s}, "not reproduced"
    yield "H2", {"sweep": sweep()}, "reproduced"
    s = sweep()
    s["cases"][2]["rms_tip_m"] = [v * 0.5 for v in s["cases"][2]["rms_tip_m"]]
    yield "H2", {"sweep": s}, "partly"
    s = sweep()
    s["cases"][2]["rms_tip_m"] = [0.6e-3] * 5
    yield "H2", {"sweep": s}, "not reproduced"
    a2 = [0.3, 0.5, 0.057, 0.5, 0.3]
    s = sweep(g0_5_off_10=(a2, [NI, NI, NU, NI, NI]))
    s["cases"][0]["rms_tip_m"] = [v * 1e-3 for v in scaled(0.285)]  # A2 is 80 % below
    yield "H3", {"sweep": s}, "reproduced"
    yield "H3", {"sweep": sweep(g0_5_off_10=([0.3, 0.5, 0.1, 0.5, 0.3],
                                             [NI, NI, NU, NI, NI]))}, "partly"
    yield "H3", {"sweep": sweep()}, "not reproduced"
    write_systems(tmp_path)
    pats = [NI, NI, NU, NI, NI]
    yield "H4", {"sweep": sweep(tmp_path, g0_5_on_10=(right, pats))}, "reproduced"
    yield "H4", {"sweep": sweep(tmp_path, g0_5_on_10=(left, pats))}, "not reproduced"
    heavy = tmp_path / "heavy"
    heavy.mkdir()
    write_systems(heavy, ball_mass=0.5)  # a 500 g ball lowers f1 to 328 Hz, not 452
    yield "H4", {"sweep": sweep(heavy, g0_5_on_10=(right, pats))}, "partly"
    a5 = [0.2, 0.35, 0.11, 0.08, 0.05]  # A5: 0.11 mm at r = 1, 63 % below the solid
    five = [NU, "2 asymmetric", "4 symmetric", "3 asymmetric", "6 symmetric"]
    for rms, pats, want in ((a5, five, "reproduced"), ([0.2, 0.35, 0.2, 0.1, 0.05], five,
                                                        "partly"), (a5, [NU] * 5,
                                                                    "not reproduced")):
        s = sweep(g0_1_off_10=(rms, pats))
        s["cases"][0]["rms_tip_m"] = [v * 1e-3 for v in scaled(0.297)]
        yield "H5", {"sweep": s}, want
    three = [NI, "2 symmetric", "sticking", NI, NI]
    yield "H6", {"sweep": sweep(g0_1_on_10=(right, three))}, "reproduced"
    yield "H6", {"sweep": sweep(g0_1_on_10=(left, three))}, "partly"
    yield "H6", {"sweep": sweep(g0_1_on_10=(right, [NU] * 5))}, "not reproduced"
    yield "H7", {"sweep": sweep()}, "reproduced"
    s = sweep()
    s["cases"][1]["rms_tip_m"] = [v * 1.02 for v in s["cases"][1]["rms_tip_m"]]
    yield "H7", {"sweep": s}, "partly"
    s["cases"][1]["rms_tip_m"] = [v * 1.5 for v in s["cases"][1]["rms_tip_m"]]
    yield "H7", {"sweep": s}, "not reproduced"
    shifted = {f"g{str(g).replace('.', '_')}_{f}_20":
               (scaled(2, [0.4, 1.0, 0.6, 0.4, 0.3]) if f == "off"
                else scaled(2, [0.3, 0.4, 0.6, 1.0, 0.5]), [NU] * 5)
               for g in (0.5, 0.1) for f in ("off", "on")}
    yield "H8", {"sweep": sweep(**shifted)}, "reproduced"
    yield "H8", {"sweep": sweep(**{k: v for k, v in shifted.items() if "off" in k})}, "partly"
    yield "H8", {"sweep": sweep()}, "not reproduced"
    four = ["2 asymmetric", "3 asymmetric", "2 symmetric", NU, NU]
    yield "H9", {"sweep": sweep(g0_5_off_20=(scaled(2, [0.3, 0.5, 0.15, 0.4, 0.3]), four))}, \
        "reproduced"
    yield "H9", {"sweep": sweep(g0_5_off_20=(scaled(2, [0.3, 0.5, 0.5, 0.4, 0.3]), four))}, \
        "partly"
    yield "H9", {"sweep": sweep(g0_5_off_20=(scaled(2), [NU] * 5))}, "not reproduced"
    below = scaled(2, [0.2, 0.3, 0.6, 0.3, 0.2])
    yield "H10", {"sweep": sweep(g0_5_on_20=(below, [NI, NI, NU, NI, NI]))}, "reproduced"
    yield "H10", {"sweep": sweep(g0_5_on_20=(scaled(2), [NI, NI, NU, NI, NI]))}, "partly"
    yield "H10", {"sweep": sweep(g0_5_on_20=(below, [NI] * 5))}, "not reproduced"
    six = [NU, "6 symmetric", "7 asymmetric", "8 symmetric", "10 symmetric"]
    s = sweep(g0_1_off_20=(scaled(2), six))
    s["cases"][-3]["ratio"] = R + [1.06]
    s["cases"][-3]["rms_tip_m"] += [1e-4]
    s["cases"][-3]["pattern"] += ["2 symmetric"]
    yield "H11", {"sweep": s}, "reproduced"
    yield "H11", {"sweep": sweep(g0_1_off_20=(scaled(2), six))}, "not reproduced"
    yield "H12", {"sweep": sweep(g0_1_on_20=(scaled(2), [NI, "sticking", "2 symmetric",
                                                         "4 symmetric", NI]))}, "reproduced"
    yield "H12", {"sweep": sweep(g0_1_on_20=(scaled(2), [NI, "sticking", "2 symmetric",
                                                         NI, NI]))}, "not reproduced"
    del solid_f


def test_every_harmonic_check_gives_each_of_its_verdicts(tmp_path):
    seen = {}
    for claim, steps, want in harmonic_cases(tmp_path):
        got = judge(claim, steps)
        assert got.verdict == want, (claim, want, got)
        assert got.reason and "\n" not in got.reason
        seen.setdefault(claim, set()).add(want)
    assert set(seen) == {f"H{i}" for i in range(1, 13)}
    three = {"reproduced", "partly", "not reproduced"}
    # H11 and H12 publish no number: they can only hold or fail
    assert all(seen[c] == three for c in seen if c not in ("H11", "H12"))


def test_a_missing_step_is_not_available():
    for claim in CHECKS:
        v = judge(claim, {})
        assert v.verdict == "not available" and "no" in v.reason, claim


# --- stability claims ----------------------------------------------------------------------
PUBLISHED_MM = {"solid": 0.021, "ball gap=0.5mm friction=off": 0.13,
                "ball gap=0.5mm friction=on": 0.03, "tmd": 0.26,
                "ball gap=0.1mm friction=off": 0.29, "ball gap=0.1mm friction=on": 0.11}


def lobes(**depths_mm) -> dict:
    d = {**PUBLISHED_MM, **{k.replace("_", " ").replace("g0 5", "gap=0.5mm")
                           .replace("g0 1", "gap=0.1mm").replace(" off", " friction=off")
                           .replace(" on", " friction=on"): v for k, v in depths_mm.items()}}
    return {"cases": [{"case": k, "min_chatter_free_depth_m": v * 1e-3} for k, v in d.items()],
            "files": {"png": "lobes.png"}}


@pytest.mark.parametrize(("claim", "depths", "want"), [
    ("S1", {}, "reproduced"), ("S1", {"solid": 0.04}, "partly"),
    ("S2", {}, "reproduced"), ("S2", {"ball_g0_5_off": 0.06}, "partly"),
    ("S2", {"ball_g0_5_off": 0.02}, "not reproduced"),
    ("S3", {}, "reproduced"), ("S3", {"ball_g0_5_on": 0.05}, "partly"),
    ("S4", {}, "reproduced"), ("S4", {"tmd": 0.7}, "partly"),
    ("S4", {"tmd": 0.021}, "not reproduced"),
    ("S5", {}, "reproduced"), ("S5", {"ball_g0_1_off": 0.1}, "partly"),
    ("S5", {"ball_g0_1_off": 0.021}, "not reproduced"),
    ("S6", {}, "reproduced"), ("S6", {"ball_g0_1_on": 0.05}, "partly"),
    ("S6", {"ball_g0_1_on": 0.02}, "not reproduced"),
    ("S7", {}, "reproduced"), ("S7", {"ball_g0_5_on": 0.2}, "partly"),
    ("S7", {"ball_g0_5_on": 0.2, "ball_g0_1_on": 0.4}, "not reproduced"),
])
def test_stability_checks(claim, depths, want):
    solid = depths.pop("solid", None)
    steps = {"lobes": lobes(**depths)}
    if solid is not None:
        steps["lobes"]["cases"][0]["min_chatter_free_depth_m"] = solid * 1e-3
    assert judge(claim, steps).verdict == want


# --- discussion claims -----------------------------------------------------------------------
def attractor(pattern, fraction=0.5, periodic=True):
    return {"pattern": pattern, "fraction": fraction, "periodic": periodic}


def basins(a, b, c) -> dict:
    return {"basins-10N-r1.01-off": {"attractors": a}, "basins-10N-r1.01-on": {"attractors": b},
            "basins-20N-r1.00-off": {"attractors": c}}


def bif(periods, strobe_mm, ranges=None) -> dict:
    forces = [5.0 * (i + 1) for i in range(len(periods))]
    return {"values": forces, "period": {"forward": periods},
            "forward": [[v * 1e-3] * 3 for v in strobe_mm], "hysteresis_ranges": ranges or []}


def sens(values, patterns, rms=None, chatter=None) -> dict:
    h = [{"value": v, "ratio": [0.95, 1.0, 1.05], "pattern": p,
          "rms_tip_m": (rms or {}).get(v, [1e-4, 2e-4, 1e-4])} for v, p in zip(values, patterns,
                                                                               strict=True)]
    s = {"harmonic": h}
    if chatter is not None:
        s["cuts"] = {"depth_m": [5e-5, 6e-5, 7e-5, 8e-5, 9e-5, 1e-4],
                     "results": [{"value": v, "chatter": chatter[v]} for v in values]}
    return s


def first_chatter(k):
    return [i >= k for i in range(6)]


def discussion_cases():
    chaos, nu2 = attractor(NU, periodic=False), attractor(NU, periodic=False)
    yield "D1", basins([chaos], [attractor(NI), nu2], [attractor("2 symmetric", 0.9)]), \
        "reproduced"
    yield "D1", basins([chaos], [attractor(NI, 1.0)], [attractor(NU, 0.9)]), "partly"
    yield "D1", basins([attractor(NI)], [attractor(NI, 1.0)], [attractor(NU, 0.9)]), \
        "not reproduced"
    p = [NI, NU, NI]
    yield "D2", {"sensitivity-initial": sens([0, 1], [p, [NU, NU, NI]])}, "reproduced"
    yield "D2", {"sensitivity-initial": sens([0, 1, 2], [p, [NU, NU, NI], [NI, NI, NI]])}, \
        "partly"
    yield "D2", {"sensitivity-initial": sens([0, 1], [[NU, NU, NI], [NI, NI, NI]])}, \
        "not reproduced"
    periods = [1] * 10
    strobe = [-0.04, -0.08, -0.13, -0.18, -0.23, -0.28, -0.3, -0.3, -0.3, -0.3]
    key = "bifurcation-gap0.1-frictionoff"
    yield "D3a", {key: bif(periods, strobe)}, "reproduced"
    yield "D3a", {key: bif(periods, [2 * v for v in strobe])}, "partly"
    yield "D3a", {key: bif([0] * 10, strobe)}, "not reproduced"
    key = "bifurcation-gap0.5-frictionoff"
    b = [-0.05, -0.06, -0.1, -0.11, -0.15, -0.21, -0.25, -0.3, -0.3, -0.3]
    yield "D3b", {key: bif([1, 0] + [1] * 8, b)}, "reproduced"
    yield "D3b", {key: bif([1, 0] + [1] * 8, [3 * v for v in b])}, "partly"
    yield "D3b", {key: bif([1] * 10, b)}, "not reproduced"
    key = "bifurcation-gap0.1-frictionon"
    yield "D3c", {key: bif(periods, strobe, [[19.0, 20.0]])}, "reproduced"
    yield "D3c", {key: bif(periods, strobe, [[40.0, 45.0]])}, "partly"
    yield "D3c", {key: bif(periods, strobe)}, "not reproduced"
    key = "bifurcation-gap0.5-frictionon"
    yield "D3d", {key: bif([1, 1, 1, 0, 0, 1, 1, 1, 1, 1], strobe)}, "reproduced"
    yield "D3d", {key: bif([1, 1, 1, 0, 1, 1, 1, 1, 1, 1], strobe)}, "partly"
    yield "D3d", {key: bif([1] * 10, strobe)}, "not reproduced"
    balls = ["carbide", "steel"]
    pp = [[NI] * 3, [NI] * 3]
    yield "D4", {"sensitivity-ball": sens(balls, pp, {"carbide": [1e-4] * 3,
                                                     "steel": [1.1e-4] * 3},
                                          {"carbide": first_chatter(5),
                                           "steel": first_chatter(4)})}, "reproduced"
    yield "D4", {"sensitivity-ball": sens(balls, pp, {"carbide": [1e-4] * 3,
                                                     "steel": [1.1e-4] * 3},
                                          {"carbide": first_chatter(5),
                                           "steel": first_chatter(1)})}, "partly"
    yield "D4", {"sensitivity-ball": sens(balls, pp, {"carbide": [1e-4] * 3,
                                                     "steel": [0.9e-4] * 3},
                                          {"carbide": first_chatter(3),
                                           "steel": first_chatter(5)})}, "not reproduced"
    yield "D4", {"sensitivity-ball": sens(balls, pp, {"carbide": [1e-4] * 3,
                                                     "steel": [1.1e-4] * 3},
                                          {"carbide": first_chatter(0),
                                           "steel": first_chatter(0)})}, "partly"
    carb = {"ball_g0_5_off": 0.10, "ball_g0_5_on": 0.10, "ball_g0_1_off": 0.10,
            "ball_g0_1_on": 0.10}
    rms = {"carbide": [1e-4] * 3, "steel": [1.1e-4] * 3}
    for steel_mm, r, want in ((0.09, rms, "reproduced"), (0.05, rms, "partly"),
                              (0.10, rms, "partly"),  # no drop a 0.01 mm step can show
                              (0.12, {"carbide": [1e-4] * 3, "steel": [0.9e-4] * 3},
                               "not reproduced")):
        steel = lobes(**{k: steel_mm for k in carb})
        steel["cases"] = [c for c in steel["cases"] if c["case"].startswith("ball")]
        yield "D4", {"lobes": lobes(**carb), "lobes-steel": steel,
                     "sensitivity-ball": sens(balls, pp, r)}, want
    mu = [0.2, 0.4, 0.6, 0.8]
    pm = [[NI] * 3] * 4
    yield "D5", {"sensitivity-friction_number": sens(mu, pm, chatter={
        0.2: first_chatter(1), 0.4: first_chatter(2), 0.6: first_chatter(3),
        0.8: first_chatter(5)})}, "reproduced"
    yield "D5", {"sensitivity-friction_number": sens(mu, pm, chatter={
        0.2: first_chatter(1), 0.4: first_chatter(2), 0.6: first_chatter(4),
        0.8: first_chatter(3)})}, "partly"
    yield "D5", {"sensitivity-friction_number": sens(mu, pm, chatter={
        v: first_chatter(3) for v in mu})}, "not reproduced"
    e = [0.6, 0.7, 0.8]
    yield "D6", {"sensitivity-restitution": sens(e, [[NI, NU, NI]] * 3)}, "reproduced"
    yield "D6", {"sensitivity-restitution": sens(e, [[NI, NU, NI]] * 3, {
        0.6: [1e-4, 3e-4, 1e-4], 0.7: [1e-4, 2e-4, 1e-4], 0.8: [1e-4, 2e-4, 1e-4]})}, "partly"
    yield "D6", {"sensitivity-restitution": sens(e, [[NI, NU, NI], [NI, NU, NI],
                                                     [NI, NI, NI]])}, "not reproduced"
    small = (scaled(0.5), [NU] * 5)
    yield "K1", {"lobes": lobes(), "sweep": sweep(g0_1_off_10=small, g0_1_on_10=small)}, \
        "reproduced"
    yield "K1", {"lobes": lobes(), "sweep": sweep()}, "partly"
    yield "K1", {"lobes": lobes(ball_g0_1_off=0.1, ball_g0_1_on=0.02),
                 "sweep": sweep(g0_1_off_10=(scaled(2), [NU] * 5))}, "not reproduced"


def test_d4_on_the_cuts_words_a_depth_that_cannot_be_compared():
    """Carbide chatters from the shallowest cut, steel does not: no 'nan %' in the reason."""
    sens = next(steps for claim, steps, _ in discussion_cases() if claim == "D4")[
        "sensitivity-ball"]
    cuts = {r["value"]: r for r in sens["cuts"]["results"]}
    n = len(cuts["carbide"]["chatter"])
    cuts["carbide"]["chatter"] = [True] * n
    cuts["steel"]["chatter"] = [False] * 3 + [True] * (n - 3)
    got = judge("D4", {"sensitivity-ball": sens})
    assert got.verdict == "partly" and "nan" not in got.reason
    assert "carbide ball chatters from the shallowest cut" in got.reason


def test_d4_on_the_cuts_words_a_drop_below_the_shallowest_cut():
    """Steel chatters from the shallowest cut, carbide does not: a lower depth that the
    cuts cannot size, not a -100 % change; the direction holds, so partly."""
    sens = next(steps for claim, steps, _ in discussion_cases() if claim == "D4")[
        "sensitivity-ball"]
    cuts = {r["value"]: r for r in sens["cuts"]["results"]}
    n = len(cuts["carbide"]["chatter"])
    cuts["carbide"]["chatter"] = [False] + [True] * (n - 1)
    cuts["steel"]["chatter"] = [True] * n
    got = judge("D4", {"sensitivity-ball": sens})
    assert got.verdict == "partly" and "-100" not in got.reason
    assert "below the shallowest cut tried" in got.reason
    assert got.measured["depth change %"] is None


def test_d4_compares_the_rms_beyond_its_spread_over_starts():
    """With the runs from several starts (the step's --starts), the steel ball's RMS at
    r = 1 is higher only where the means lie apart beyond twice the standard error of
    their difference: the own runs' 1.1e-4 against 1e-4 m, which alone read as higher,
    are inside a spread of +-3e-5 m, so the claim's direction is not shown; with the
    starts close together it is."""
    sens = next(steps for claim, steps, want in discussion_cases()
                if claim == "D4" and want == "reproduced")["sensitivity-ball"]
    for entry in sens["harmonic"]:
        own = entry["rms_tip_m"]
        entry["starts"] = {"ball_position_m": [-1e-4, 0.0, 1e-4],
                           "rms_tip_m": [[v + d for v in own] for d in (-3e-5, 0.0, 3e-5)],
                           "pattern": [entry["pattern"]] * 3}
    got = judge("D4", {"sensitivity-ball": sens})
    assert got.verdict == "partly" and "not higher" in got.reason
    assert "over 4 starts" in got.reason
    for entry in sens["harmonic"]:
        entry["starts"]["rms_tip_m"] = [[v + d for v in entry["rms_tip_m"]]
                                        for d in (-1e-7, 0.0, 1e-7)]
    got = judge("D4", {"sensitivity-ball": sens})
    assert got.verdict == "reproduced"


def test_every_discussion_check_gives_each_of_its_verdicts():
    seen = {}
    for claim, steps, want in discussion_cases():
        got = judge(claim, copy.deepcopy(steps))
        assert got.verdict == want, (claim, want, got)
        seen.setdefault(claim, set()).add(want)
    assert set(seen) == {"D1", "D2", "D3a", "D3b", "D3c", "D3d", "D4", "D5", "D6", "K1"}
    assert all(v == {"reproduced", "partly", "not reproduced"} for v in seen.values())


def test_pattern_codes():
    assert [code(p) for p in ("no impact", "no impact with sticking", "non-uniform",
                              "2 symmetric", "3 asymmetric (period 2)", "sticking")] == \
        ["NI", "NI", "NU", "2S", "3A", "sticking"]


def test_the_claims_file_lists_every_claim_with_a_check():
    claims = load_claims()
    ids = [c["id"] for c in claims]
    assert len(ids) == 29 and set(ids) == set(CHECKS)
    for c in claims:
        assert c["statement"] and c["source"] and c["conditions"] and c["published"]


def test_audit_of_what_is_not_a_paper_output(tmp_path, capsys):
    out = tmp_path / "nothing"
    assert_one_line_error(main, ["audit", str(tmp_path)], out, "no boringbar paper output",
                          capsys)
    assert_one_line_error(main, ["audit", str(out)], out, "is not a directory", capsys)


def test_the_two_attractor_threshold_of_d1(tmp_path):
    """D1(b): the smallest |x0| (v0 = 0 row) where the basin changes attractor."""
    x = np.linspace(-1.5e-3, 1.5e-3, 31)
    v = np.linspace(-1.5, 1.5, 31)
    for edge_mm, want in ((1.0, "reproduced"), (0.3, "partly")):
        a = np.where(np.abs(x)[:, None] < edge_mm * 1e-3 - 1e-9, 0, 1) * np.ones((1, 31), int)
        path = tmp_path / f"basins{edge_mm}.nc"
        xr.Dataset({"attractor": (("displacement_m", "velocity_m_s"), a)},
                   coords={"displacement_m": x, "velocity_m_s": v}).to_netcdf(path)
        assert basin_threshold(path) == pytest.approx(edge_mm, abs=1e-9)
        steps = basins([attractor(NU, periodic=False)],
                       [attractor(NI), attractor(NU, periodic=False)],
                       [attractor("2 symmetric", 0.9)])
        steps["basins-10N-r1.01-on"]["files"] = {"netcdf": str(path)}
        assert judge("D1", steps).verdict == want
    one = tmp_path / "one.nc"
    xr.Dataset({"attractor": (("displacement_m", "velocity_m_s"), np.zeros((31, 31), int))},
               coords={"displacement_m": x, "velocity_m_s": v}).to_netcdf(one)
    assert basin_threshold(one) is None
