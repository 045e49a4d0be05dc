"""One check per published claim (report/claims.toml), each computed from the step
summaries of a ``boringbar paper`` output (docs/audit.md states every tolerance).

Each check is ``check(evidence, preset) -> Verdict``. Its verdict comes from two
judgements: the *qualitative* part of the claim (a pattern set, the side of a
shift, which bar is better) and its *numbers*, each within :data:`TOLERANCE`
(15 %). Both hold: reproduced. Only the qualitative part: partly. Otherwise:
not reproduced. The reason is worded from the measured numbers.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import xarray as xr

from boringbar.analysis.sensitivity import above_spread, rms_at_ratio
from boringbar.model.system import System
from boringbar.reference.stability import natural_frequencies
from boringbar.report.audit_data import TOLERANCE, Evidence, Verdict

#: A peak moves "left" or "right" when it sits at least this far (in r) from the
#: solid bar's peak; less is "none".
SHIFT = 0.005
#: How far below the solid bar (fraction of its RMS) a point must lie to be "below".
BELOW = 0.05


# --- reading the sweep --------------------------------------------------------------
def _case(s: dict, bar: str, force: float, gap_mm: float | None = None,
          friction: str | None = None) -> dict:
    for c in s["cases"]:
        if c["bar"] != bar or c["force_n"] != force:
            continue
        if gap_mm is not None and not math.isclose(c["gap_m"] * 1e3, gap_mm):
            continue
        if friction is not None and c["friction"] != friction:
            continue
        return c
    raise KeyError(f"no sweep case {bar} {force} N gap {gap_mm} friction {friction}")


def _rms(c: dict) -> np.ndarray:
    return np.array([math.nan if v is None else v for v in c["rms_tip_m"]])


def _at(c: dict, r: float) -> int:
    return int(np.argmin(np.abs(np.asarray(c["ratio"]) - r)))


def _peak_r(c: dict) -> float:
    return float(c["ratio"][int(np.nanargmax(_rms(c)))])


def code(pattern: str) -> str:
    """A pattern's published abbreviation: no impact NI (a ball stuck without impacts
    too), non-uniform NU, 'n symmetric' nS, 'n asymmetric' nA, sticking."""
    p = str(pattern)
    if p in ("no impact", "no impact with sticking"):
        return "NI"
    if p == "non-uniform":
        return "NU"
    if p == "sticking":
        return "sticking"
    m = re.match(r"(\d+) (symmetric|asymmetric)", p)
    return f"{m.group(1)}{'S' if m.group(2) == 'symmetric' else 'A'}" if m else p


def _codes(c: dict) -> set[str]:
    return {code(p) for p in c["pattern"] if p}


def _shift(ball: dict, solid: dict) -> str:
    d = _peak_r(ball) - _peak_r(solid)
    return "right" if d > SHIFT else "left" if d < -SHIFT else "none"


def _near(value: float, published: float) -> bool:
    return abs(value / published - 1) <= TOLERANCE


def _pct(value: float, published: float) -> str:
    return f"{(value / published - 1) * 100:+.0f} %"


def _judge(qualitative: bool, numbers: bool, measured: dict, why_not: str, why_partly: str,
           figure) -> Verdict:
    if not qualitative:
        return Verdict("not reproduced", measured, why_not, figure)
    if not numbers:
        return Verdict("partly", measured, why_partly, figure)
    return Verdict("reproduced", measured, "holds within the stated tolerance", figure)


def _missing(what: str) -> Verdict:
    return Verdict("not available", {}, f"this output has no {what} step")


def _sweep(ev: Evidence, preset: str):
    s = ev.summary(preset, "sweep")
    return s, ev.figure(preset, "sweep", "F10N")


def _pair(ev: Evidence, preset: str, force: float, gap: float, friction: str):
    """(the ball case, the solid bar) of the sweep at ``force``; None without a sweep."""
    s = ev.summary(preset, "sweep")
    if s is None:
        return None
    return _case(s, "ball", force, gap, friction), _case(s, "solid", force)


def _pattern_check(ball: dict, published: set, exact: bool = True,
                   more: int = 0) -> tuple[bool, dict, str]:
    found = _codes(ball)
    ok = found == published if exact else (published <= found and
                                          len(found) >= len(published) + more)
    words = (f"patterns {', '.join(sorted(found)) or 'none'} where the paper has "
             f"{', '.join(sorted(published))}{' and more' if more else ''}")
    return ok, {"patterns": sorted(found)}, words


def _reduction(c: dict, solid: dict, r: float = 1.0) -> float:
    return float(1 - _rms(c)[_at(c, r)] / _rms(solid)[_at(solid, r)]) * 100


# --- harmonic forcing -------------------------------------------------------------------
def check_h1(ev: Evidence, preset: str) -> Verdict:
    s, fig = _sweep(ev, preset)
    if s is None:
        return _missing("sweep")
    solid = _case(s, "solid", 10.0)
    ball = next(c for c in s["cases"] if c["bar"] == "ball")
    f_solid, f_ball = solid["natural_frequency_hz"], ball["natural_frequency_hz"]
    m = {"solid peak at r": _peak_r(solid), "solid f1 Hz": round(f_solid, 1),
         "cavity f1 Hz": round(f_ball, 1)}
    peak_ok = abs(_peak_r(solid) - 1.0) <= _step(solid) / 2 + 1e-9
    freq_ok = abs(f_solid / 456 - 1) < 0.01 and abs(f_ball / 461 - 1) < 0.01
    return _judge(peak_ok, freq_ok, m,
                  f"the solid bar peaks at r = {_peak_r(solid):g}, not 1",
                  f"the peak is at r = 1 but f1 = {f_solid:.0f} Hz (solid) and {f_ball:.0f} Hz "
                  f"(cavity), {_pct(f_solid, 456)} and {_pct(f_ball, 461)} off the published "
                  "456 and 461 Hz: the finite-element bar is stiffer than the published "
                  "frequencies; only the paper preset calibrates to them", fig)


def _step(c: dict) -> float:
    r = np.asarray(c["ratio"])
    return float(np.min(np.diff(r))) if len(r) > 1 else 0.0


def check_h2(ev: Evidence, preset: str) -> Verdict:
    s, fig = _sweep(ev, preset)
    if s is None:
        return _missing("sweep")
    solid, tmd = _case(s, "solid", 10.0), _case(s, "tmd", 10.0)
    cut = _reduction(tmd, solid)
    ratio = float(np.nanmax(_rms(solid)) / np.nanmax(_rms(tmd)))
    m = {"reduction at r = 1 %": round(cut, 1), "solid peak / TMD largest": round(ratio, 2)}
    return _judge(cut >= 50, abs(cut - 88) <= 5 and _near(ratio, 8.7), m,
                  f"the TMD cuts the RMS at r = 1 by only {cut:.0f} %",
                  f"the TMD cuts the RMS by {cut:.0f} % (published 88 %) and the solid peak "
                  f"is {ratio:.1f}x the TMD's largest (published 8.7x)", fig)


def _ball_numbers(ev, preset, ball: dict, published_set, numbers, exact=True,
                  more=0) -> Verdict:
    """A pattern-set claim on the ``ball`` case with published numbers: ``numbers`` is
    a list of (name, measured, published) checked within the tolerance."""
    fig = ev.figure(preset, "sweep", "F10N")
    ok, m, words = _pattern_check(ball, published_set, exact, more)
    off = [(n, v, p) for n, v, p in numbers if not _near(v, p)]
    m.update({n: round(v, 4) for n, v, _ in numbers})
    return _judge(ok, not off, m, words,
                  "the patterns match but " + "; ".join(f"{n} = {v:.3g} ({_pct(v, p)} off "
                                                        f"{p:g})" for n, v, p in off), fig)


def check_h3(ev: Evidence, preset: str) -> Verdict:
    pair = _pair(ev, preset, 10.0, 0.5, "off")
    if pair is None:
        return _missing("sweep")
    ball, solid = pair
    nu = [i for i, p in enumerate(ball["pattern"]) if code(p) == "NU"]
    if not nu:
        v = _ball_numbers(ev, preset, ball, {"NI", "NU"}, [])
        return Verdict("not reproduced", v.measured, v.reason + "; no non-uniform case at "
                       "all: the ball never reaches a wall at 10 N", v.figure)
    i = min(nu, key=lambda k: abs(ball["ratio"][k] - 1))
    rms = _rms(ball)[i] * 1e3
    cut = float(1 - _rms(ball)[i] / _rms(solid)[_at(solid, ball["ratio"][i])]) * 100
    return _ball_numbers(ev, preset, ball, {"NI", "NU"},
                         [("NU RMS mm", rms, 0.057), ("reduction %", cut, 80.0)])


def _stuck_f1(ev: Evidence, preset: str) -> float:
    """f1 (Hz) of the cavity bar with the ball fixed to it (an added mass)."""
    s = ev.summary(preset, "sweep")
    with xr.open_dataset(s["files"]["netcdf"]) as ds:
        systems = json.loads(ds.attrs["systems"])
    d = next(v for k, v in systems.items() if k.startswith("ball"))
    system = System.from_dict(d)
    return float(natural_frequencies(system.bar, None, system.damper.mass_kg)[0] / (2 * math.pi))


def check_h4(ev: Evidence, preset: str) -> Verdict:
    pair = _pair(ev, preset, 10.0, 0.5, "on")
    if pair is None:
        return _missing("sweep")
    ball, solid = pair
    fig = ev.figure(preset, "sweep", "F10N")
    ok, m, words = _pattern_check(ball, {"NI", "NU"})
    shift = _shift(ball, solid)
    stuck = _stuck_f1(ev, preset)
    m.update({"shift": shift, "stuck-ball f1 Hz": round(stuck, 1)})
    qualitative = shift == "right" and ok
    why = words if not ok else f"the peak does not move right (shift: {shift})"
    return _judge(qualitative, _near(stuck, 452), m, why,
                  f"the shift and patterns hold; the stuck ball gives f1 = {stuck:.0f} Hz "
                  f"({_pct(stuck, 452)} off 452)", fig)


def check_h5(ev: Evidence, preset: str) -> Verdict:
    pair = _pair(ev, preset, 10.0, 0.1, "off")
    if pair is None:
        return _missing("sweep")
    ball, solid = pair
    v = _ball_numbers(ev, preset, ball, {"NU", "2A", "3A", "4S", "6S"},
                      [("RMS at r = 1 mm", _rms(ball)[_at(ball, 1)] * 1e3, 0.11),
                       ("reduction %", _reduction(ball, solid), 63.0)])
    return _with_shift(v, ball, solid, "left")


def _with_shift(v: Verdict, ball: dict, solid: dict, side: str) -> Verdict:
    """Add the shift to a pattern verdict: the wrong side makes a reproduced or
    partly verdict partly, with the reason."""
    shift = _shift(ball, solid)
    v.measured["shift"] = shift
    if shift != side and v.verdict == "reproduced":
        return Verdict("partly", v.measured, f"the patterns and numbers hold but the peak "
                       f"moves {shift}, not {side}", v.figure)
    if shift != side and v.verdict == "partly":
        v.reason += f"; the peak moves {shift}, not {side}"
    return v


def check_h6(ev: Evidence, preset: str) -> Verdict:
    pair = _pair(ev, preset, 10.0, 0.1, "on")
    if pair is None:
        return _missing("sweep")
    ball, solid = pair
    v = _ball_numbers(ev, preset, ball, {"NI", "2S", "sticking"}, [])
    return _with_shift(v, ball, solid, "right")


def check_h7(ev: Evidence, preset: str) -> Verdict:
    s, fig = _sweep(ev, preset)
    if s is None:
        return _missing("sweep")
    ratios = []
    for bar in ("solid", "tmd"):
        ratios += list(_rms(_case(s, bar, 20.0)) / _rms(_case(s, bar, 10.0)))
    worst = float(np.max(np.abs(np.asarray(ratios) - 2)))
    m = {"RMS(20 N) / RMS(10 N), farthest from 2": round(2 + worst, 6)}
    return _judge(worst < 0.2, worst < 0.01, m, f"the ratio departs from 2 by {worst:.2g}",
                  f"the ratio departs from 2 by {worst:.2g}", fig)


def check_h8(ev: Evidence, preset: str) -> Verdict:
    s, fig = _sweep(ev, preset)
    if s is None:
        return _missing("sweep")
    solid = _case(s, "solid", 20.0)
    shifts = {(g, f): _shift(_case(s, "ball", 20.0, g, f), solid)
              for g in (0.5, 0.1) for f in ("off", "on")}
    want = {(g, f): "left" if f == "off" else "right" for g, f in shifts}
    hits = sum(shifts[k] == want[k] for k in shifts)
    m = {f"shift gap {g} friction {f}": v for (g, f), v in shifts.items()}
    words = ", ".join(f"gap {g} friction {f}: {v}" for (g, f), v in shifts.items())
    if hits == 4:
        return Verdict("reproduced", m, "all four shifts as published", fig)
    return Verdict("partly" if hits >= 2 else "not reproduced", m,
                   f"{hits} of 4 shifts as published ({words})", fig)


def check_h9(ev: Evidence, preset: str) -> Verdict:
    pair = _pair(ev, preset, 20.0, 0.5, "off")
    if pair is None:
        return _missing("sweep")
    ball, solid = pair
    return _ball_numbers(ev, preset, ball, {"2S", "2A", "3A", "NU"},
                         [("reduction at r = 1 %", _reduction(ball, solid), 85.0)])


def check_h10(ev: Evidence, preset: str) -> Verdict:
    pair = _pair(ev, preset, 20.0, 0.5, "on")
    if pair is None:
        return _missing("sweep")
    ball, solid = pair
    v = _ball_numbers(ev, preset, ball, {"NI", "NU"}, [])
    ni = [i for i, p in enumerate(ball["pattern"]) if code(p) == "NI"]
    below = all(_rms(ball)[i] < (1 - BELOW) * _rms(solid)[_at(solid, ball["ratio"][i])]
                for i in ni)
    v.measured["NI points below the solid bar"] = bool(ni) and below
    if v.verdict == "reproduced" and not (ni and below):
        return Verdict("partly", v.measured, "the patterns match but the no-impact points "
                       "are not below the solid bar (a ball that does not strike adds only "
                       "its mass)", v.figure)
    return v


def _pattern_claim(ev: Evidence, preset: str, friction: str, published: set) -> Verdict:
    """H11, H12: the 0.1 mm ball at 20 N shows the published patterns and one more."""
    pair = _pair(ev, preset, 20.0, 0.1, friction)
    if pair is None:
        return _missing("sweep")
    return _ball_numbers(ev, preset, pair[0], published, [], exact=False, more=1)


def check_h11(ev: Evidence, preset: str) -> Verdict:
    return _pattern_claim(ev, preset, "off", {"NU", "6S", "7A", "8S", "10S"})


def check_h12(ev: Evidence, preset: str) -> Verdict:
    return _pattern_claim(ev, preset, "on", {"NI", "sticking", "2S"})


# --- machining stability ---------------------------------------------------------------------
LOBE_CASES = {"S1": "solid", "S2": "ball gap=0.5mm friction=off",
              "S3": "ball gap=0.5mm friction=on", "S4": "tmd",
              "S5": "ball gap=0.1mm friction=off", "S6": "ball gap=0.1mm friction=on"}
PUBLISHED_DEPTH_MM = {"S1": 0.021, "S2": 0.13, "S3": 0.03, "S4": 0.26, "S5": 0.29, "S6": 0.11}


def _depths(ev: Evidence, preset: str) -> dict | None:
    return _depths_of(ev, preset, "lobes")


def _depth_check(claim: str):
    def check(ev: Evidence, preset: str) -> Verdict:
        d = _depths(ev, preset)
        if d is None:
            return _missing("lobes")
        fig = ev.figure(preset, "lobes")
        got, want = d[LOBE_CASES[claim]], PUBLISHED_DEPTH_MM[claim]
        m = {"min chatter-free depth mm": round(got, 4)}
        if claim == "S1":
            return _judge(True, _near(got, want), m, "",
                          f"{got:.3g} mm, {_pct(got, want)} off the published {want:g} mm", fig)
        solid = d["solid"]
        gain, want_gain = got / solid - 1, want / PUBLISHED_DEPTH_MM["S1"] - 1
        m["gain on solid %"] = round(gain * 100, 0)
        better = gain > 0.1 if want_gain > 0.5 else True
        return _judge(better, _near(got, want), m,
                      f"{got:.3g} mm against the solid bar's {solid:.3g} mm: no gain (the "
                      f"paper: {want_gain * 100:+.0f} %)",
                      f"{got:.3g} mm, {_pct(got, want)} off the published {want:g} mm "
                      f"({gain * 100:+.0f} % on the solid bar, published "
                      f"{want_gain * 100:+.0f} %)", fig)
    return check


def check_s7(ev: Evidence, preset: str) -> Verdict:
    d = _depths(ev, preset)
    if d is None:
        return _missing("lobes")
    pairs = {g: (d[f"ball gap={g}mm friction=off"], d[f"ball gap={g}mm friction=on"])
             for g in ("0.5", "0.1")}
    lower = {g: on < off for g, (off, on) in pairs.items()}
    m = {f"gap {g}: off / on mm": [round(a, 4), round(b, 4)] for g, (a, b) in pairs.items()}
    hits = sum(lower.values())
    verdict = "reproduced" if hits == 2 else "partly" if hits == 1 else "not reproduced"
    why = "; ".join(f"gap {g} mm: {off:.3g} mm without friction, {on:.3g} mm with"
                    for g, (off, on) in pairs.items())
    return Verdict(verdict, m, why, ev.figure(preset, "lobes"))


# --- discussion ------------------------------------------------------------------------
def basin_threshold(path) -> float | None:
    """D1(b)'s threshold (mm): along the initial velocity nearest 0, the smallest
    |initial displacement| whose attractor differs from the one nearest the
    origin; None where that row holds one attractor."""
    with xr.open_dataset(path) as ds:
        a, x = ds["attractor"].values, ds["displacement_m"].values
        j = int(np.argmin(np.abs(ds["velocity_m_s"].values)))
    row = a[:, j]
    centre = row[int(np.argmin(np.abs(x)))]
    other = np.abs(x[row != centre])
    return float(other.min()) * 1e3 if other.size else None


def check_d1(ev: Evidence, preset: str) -> Verdict:
    keys = ("basins-10N-r1.01-off", "basins-10N-r1.01-on", "basins-20N-r1.00-off")
    s = [ev.summary(preset, k) for k in keys]
    if any(x is None for x in s):
        return _missing("basins")
    a_chaos = any(not a["periodic"] for a in s[0]["attractors"])
    b_two = len(s[1]["attractors"]) >= 2
    c = max(s[2]["attractors"], key=lambda a: a["fraction"])
    c_2s = c["periodic"] and code(c["pattern"]) == "2S"
    nc = s[1].get("files", {}).get("netcdf")
    threshold = basin_threshold(nc) if nc else None
    m = {"(a) non-periodic attractor": a_chaos, "(b) attractors": len(s[1]["attractors"]),
         "(b) threshold mm": None if threshold is None else round(threshold, 3),
         "(c) largest basin": f"{c['pattern']} ({c['fraction']:.0%})"}
    hits = a_chaos + b_two + c_2s
    words = (f"{hits} of 3 parts hold: (a) {'a' if a_chaos else 'no'} non-periodic "
             f"attractor, (b) {len(s[1]['attractors'])} attractor(s) with friction"
             + ("" if threshold is None else f", the other from |x0| = {threshold:.2g} mm")
             + f", (c) the largest basin at 20 N is {c['pattern']}")
    fig = ev.figure(preset, keys[1])
    if hits == 3 and threshold is not None and not _near(threshold, 1.0):
        return Verdict("partly", m, words + f"; the threshold is {_pct(threshold, 1.0)} off "
                       "the published 1 mm", fig)
    verdict = "reproduced" if hits == 3 else "partly" if hits else "not reproduced"
    return Verdict(verdict, m, words, fig)


def check_d2(ev: Evidence, preset: str) -> Verdict:
    s = ev.summary(preset, "sensitivity-initial")
    if s is None:
        return _missing("sensitivity-initial")
    runs = s["harmonic"]
    base = [code(p) for p in runs[0]["pattern"]]
    changes, other = 0, []
    for run in runs[1:]:
        for a, b in zip(base, (code(p) for p in run["pattern"]), strict=True):
            if a != b:
                changes += 1
                if not (a == "NI" and b == "NU"):
                    other.append(f"{a}->{b}")
    m = {"pattern changes": changes, "changes other than NI -> NU": len(other)}
    if not other:
        return Verdict("reproduced", m, "no pattern changes" if not changes else
                       f"{changes} pattern change(s), all NI -> NU",
                       ev.figure(preset, "sensitivity-initial"))
    return Verdict("partly" if len(other) <= changes / 2 else "not reproduced", m,
                   f"{changes} pattern change{'s' if changes > 1 else ''}, {len(other)} "
                   "of them not NI -> NU "
                   f"({', '.join(sorted(set(other)))})", ev.figure(preset, "sensitivity-initial"))


def _strobe(s: dict, force: float) -> float:
    """The mean forward strobe sample (mm) at ``force``."""
    i = int(np.argmin(np.abs(np.asarray(s["values"]) - force)))
    return float(np.mean(s["forward"][i])) * 1e3


def _periodic(s: dict, force: float) -> bool:
    i = int(np.argmin(np.abs(np.asarray(s["values"]) - force)))
    return int(s["period"]["forward"][i]) > 0


def _bifurcation(gap: str, friction: str):
    key = f"bifurcation-gap{gap}-friction{friction}"

    def read(ev: Evidence, preset: str):
        return ev.summary(preset, key), ev.figure(preset, key)
    return read


def check_d3a(ev: Evidence, preset: str) -> Verdict:
    s, fig = _bifurcation("0.1", "off")(ev, preset)
    if s is None:
        return _missing("bifurcation")
    periodic = float(np.mean([p > 0 for p in s["period"]["forward"]]))
    pts = [(f, _strobe(s, f), p) for f, p in ((10, -0.08), (20, -0.18), (30, -0.28))]
    m = {"periodic fraction": round(periodic, 2),
         **{f"strobe at {f} N mm": round(v, 3) for f, v, _ in pts}}
    off = [f"{f} N: {v:.3g} mm ({_pct(v, p)})" for f, v, p in pts if not _near(v, p)]
    return _judge(periodic >= 0.8, not off, m,
                  f"only {periodic:.0%} of the forces give a periodic response",
                  "periodic, but the strobe differs: " + "; ".join(off), fig)


def check_d3b(ev: Evidence, preset: str) -> Verdict:
    s, fig = _bifurcation("0.5", "off")(ev, preset)
    if s is None:
        return _missing("bifurcation")
    chaos10 = not _periodic(s, 10)
    above = all(_periodic(s, f) for f in (20, 30))
    pts = [(f, _strobe(s, f), p) for f, p in ((20, -0.11), (30, -0.21))]
    m = {"non-periodic at 10 N": chaos10, "periodic at 20 and 30 N": above,
         **{f"strobe at {f} N mm": round(v, 3) for f, v, _ in pts}}
    off = [f"{f} N: {v:.3g} mm ({_pct(v, p)})" for f, v, p in pts if not _near(v, p)]
    return _judge(chaos10 and above, not off, m,
                  f"10 N is {'non-periodic' if chaos10 else 'periodic'}, 20-30 N "
                  f"{'periodic' if above else 'not all periodic'}",
                  "the chaos-to-period change holds, the strobe differs: " + "; ".join(off), fig)


def check_d3c(ev: Evidence, preset: str) -> Verdict:
    s, fig = _bifurcation("0.1", "on")(ev, preset)
    if s is None:
        return _missing("bifurcation")
    ranges = s.get("hysteresis_ranges") or []
    near = [r for r in ranges if r[0] - 5 <= 19 <= r[1] + 5]
    m = {"forward/backward disagree N": ranges, "strobe at 30 N mm": round(_strobe(s, 30), 3)}
    return _judge(bool(ranges), bool(near), m,
                  "forward and backward sweeps agree everywhere: one attractor",
                  f"two attractors coexist, at {ranges} N, not near 19 N", fig)


def check_d3d(ev: Evidence, preset: str) -> Verdict:
    s, fig = _bifurcation("0.5", "on")(ev, preset)
    if s is None:
        return _missing("bifurcation")
    forces = np.asarray(s["values"])
    chaotic = [float(f) for f, p in zip(forces, s["period"]["forward"], strict=True) if p == 0]
    inside = [f for f in chaotic if 17 <= f <= 28]
    band = [f for f in forces if 17 <= f <= 28]
    m = {"periodic at 10 N": _periodic(s, 10), "non-periodic forces N": chaotic}
    qualitative = _periodic(s, 10) and bool(inside)
    return _judge(qualitative, len(inside) == len(band), m,
                  f"non-periodic at {chaotic or 'no'} N; periodic at 10 N: {_periodic(s, 10)}",
                  f"non-periodic at {len(inside)} of the {len(band)} forces in 17-28 N", fig)


def _chatter_free(res: dict, depths) -> float:
    """The deepest cut (mm) before the first that chatters."""
    for d, ch in zip(depths, res["chatter"], strict=True):
        if ch:
            return (d - (depths[1] - depths[0])) * 1e3 if d > depths[0] else 0.0
    return depths[-1] * 1e3


def check_d4(ev: Evidence, preset: str) -> Verdict:
    """From the steel ball's lobes where the output has them, else the 1200 rpm cuts."""
    steel, carbide = _depths_of(ev, preset, "lobes-steel"), _depths(ev, preset)
    s = ev.summary(preset, "sensitivity-ball")
    if steel is None or carbide is None or s is None:
        return _d4_cuts(ev, preset)
    higher, m_rms, rms_words = _steel_rms({r["value"]: r for r in s["harmonic"]})
    change = {c: (steel[c] / carbide[c] - 1) * 100 for c in steel
              if carbide.get(c, 0) > 0}
    worst = min(change.values())
    m = {"depth change steel vs carbide %": {c: round(v) for c, v in change.items()},
         "steel RMS at r = 1 higher": higher, **m_rms}
    words = ", ".join(f"{c}: {v:+.0f} %" for c, v in change.items())
    not_deeper = all(v <= 0 for v in change.values())
    # "drops by up to 15 %": some drop, and none much beyond 15 % (a drop smaller than
    # one 0.01 mm depth step cannot show, so no drop at all is only partly)
    dropped = worst < 0 and -15 * (1 + TOLERANCE) <= worst
    return _judge(not_deeper or higher, not_deeper and higher and dropped, m,
                  f"the steel ball's limits against the carbide's: {words}; its RMS at "
                  f"r = 1 is {'higher' if higher else 'not higher'} ({rms_words})",
                  f"steel against carbide: {words} (published: up to -15 %; depth steps of "
                  f"0.01 mm); RMS {'higher' if higher else 'not higher'} ({rms_words})",
                  ev.figure(preset, "lobes-steel"))


def _steel_rms(h: dict) -> tuple[bool, dict, str]:
    """Whether the steel ball's tip RMS at r = 1 is higher than the carbide ball's
    (``h``: the sensitivity step's harmonic entries by value): beyond the spread over
    the runs' starts where the step ran them (:func:`above_spread`: a rattling ball's RMS
    moves by a few per cent with its start, or with one rounding of its setup), else the
    plain comparison; the measured values and their words."""
    c, st = rms_at_ratio(h["carbide"], 1.0), rms_at_ratio(h["steel"], 1.0)
    higher, diff, se = above_spread(st, c)
    mc, ms = float(np.mean(c)), float(np.mean(st))
    m = {"RMS at r = 1 carbide / steel mm": [round(mc * 1e3, 4), round(ms * 1e3, 4)]}
    words = f"{ms * 1e3:.4g} against {mc * 1e3:.4g} mm"
    if len(c) > 1:
        m["RMS at r = 1: starts, steel - carbide mm, its standard error mm"] = [
            len(c), round(diff * 1e3, 5), round(se * 1e3, 5)]
        words += (f", the means over {len(c)} starts: steel - carbide {diff * 1e3:+.2g} "
                  f"+- {se * 1e3:.2g} mm")
    return higher, m, words


def _depths_of(ev: Evidence, preset: str, key: str) -> dict | None:
    s = ev.summary(preset, key)
    if s is None:
        return None
    return {c["case"]: (c["min_chatter_free_depth_m"] or 0.0) * 1e3 for c in s["cases"]}


def _d4_cuts(ev: Evidence, preset: str) -> Verdict:
    s = ev.summary(preset, "sensitivity-ball")
    if s is None:
        return _missing("sensitivity-ball")
    higher, m_rms, rms_words = _steel_rms({r["value"]: r for r in s["harmonic"]})
    cuts = {r["value"]: r for r in s["cuts"]["results"]}
    depths = s["cuts"]["depth_m"]
    d_c, d_s = (_chatter_free(cuts[v], depths) for v in ("carbide", "steel"))
    # steel chatters from the shallowest cut where carbide does not: its depth is lower,
    # by an amount below what the cuts tried can show (not -100 %)
    below = d_s == 0 < d_c
    change = (d_s / d_c - 1) * 100 if d_c > 0 and not below else math.nan
    if d_c == 0 and d_s == 0:  # both chatter from the shallowest cut tried
        return Verdict("partly" if higher else "not reproduced", m_rms,
                       f"both balls chatter from the shallowest cut tried "
                       f"({depths[0] * 1e3:g} mm at 1200 rpm), so the depths cannot be "
                       f"compared; the steel ball's RMS is "
                       f"{'higher' if higher else 'not higher'} ({rms_words})",
                       ev.figure(preset, "sensitivity-ball"))
    m = {**m_rms,
         "chatter-free depth at 1200 rpm carbide / steel mm": [round(d_c, 4), round(d_s, 4)],
         "depth change %": None if math.isnan(change) else round(change, 0)}
    drop_ok = math.isfinite(change) and -15 - 1e-9 <= change <= 0
    if below:
        moved = (f"down from {d_c:g} mm to below the shallowest cut tried (the steel ball "
                 f"chatters from {depths[0] * 1e3:g} mm): a drop the cuts cannot size")
    elif math.isfinite(change):
        moved = f"{change:+.0f} %"
    else:
        moved = (f"up from none (the carbide ball chatters from the shallowest cut, "
                 f"{depths[0] * 1e3:g} mm; the steel ball is stable to {d_s:g} mm)")
    return _judge(higher or drop_ok or below, higher and drop_ok, m,
                  f"the steel ball's RMS is not higher ({rms_words}) and its depth "
                  f"changes by {moved}",
                  f"steel RMS {'higher' if higher else 'not higher'} ({rms_words}); "
                  f"chatter-free depth "
                  f"{moved} (published: up to -15 %; one speed, 1200 rpm, in "
                  f"{(depths[1] - depths[0]) * 1e3:g} mm steps)",
                  ev.figure(preset, "sensitivity-ball"))


def check_d5(ev: Evidence, preset: str) -> Verdict:
    s = ev.summary(preset, "sensitivity-friction_number")
    if s is None:
        return _missing("sensitivity-friction_number")
    cuts = {r["value"]: r for r in s["cuts"]["results"]}
    depths = s["cuts"]["depth_m"]
    free = {v: round(_chatter_free(cuts[v], depths), 4) for v in sorted(cuts)}
    low_worse = all(free[v] < free[0.6] for v in (0.2, 0.4) if v in free)
    values = list(free.values())
    rising = values[-1] > values[0] and all(a <= b for a, b in zip(values, values[1:],
                                                                   strict=False))
    m = {"chatter-free depth mm by friction number": {str(k): v for k, v in free.items()}}
    below = f"< {depths[0] * 1e3:g}"  # chatters from the shallowest cut tried
    words = ", ".join(f"{k:g}: {v:g}" if v > 0 else f"{k:g}: {below}" for k, v in free.items())
    return _judge(low_worse or rising, low_worse and rising, m,
                  f"chatter-free depths ({words} mm) do not rise with friction",
                  f"chatter-free depths ({words} mm): "
                  + ("0.2 and 0.4 are worse than 0.6" if low_worse else "0.2/0.4 not worse "
                     "than 0.6") + (", rising with friction" if rising else
                                    ", not rising all the way"),
                  ev.figure(preset, "sensitivity-friction_number"))


def check_d6(ev: Evidence, preset: str) -> Verdict:
    s = ev.summary(preset, "sensitivity-restitution")
    if s is None:
        return _missing("sensitivity-restitution")
    h = {r["value"]: r for r in s["harmonic"]}
    base = h[0.7]
    changed = sum(code(a) != code(b) for v in (0.6, 0.8)
                  for a, b in zip(base["pattern"], h[v]["pattern"], strict=True))
    rms = max(abs(x / y - 1) for v in (0.6, 0.8)
              for x, y in zip(h[v]["rms_tip_m"], base["rms_tip_m"], strict=True))
    seen = sorted({code(p) for v in h for p in h[v]["pattern"] if p})
    # with no impact at all, restitution cannot matter: say which patterns were seen
    m = {"pattern changes": changed, "largest RMS change %": round(rms * 100, 1),
         "patterns seen": seen}
    return _judge(changed == 0, rms <= TOLERANCE, m,
                  f"{changed} pattern change{'s' if changed > 1 else ''} between e = 0.6, "
                  "0.7 and 0.8",
                  f"patterns unchanged; the RMS changes by up to {rms:.0%}",
                  ev.figure(preset, "sensitivity-restitution"))


def check_k1(ev: Evidence, preset: str) -> Verdict:
    d = _depths(ev, preset)
    s = ev.summary(preset, "sweep")
    if d is None or s is None:
        return _missing("lobes or sweep")
    wins = []
    for f in ("off", "on"):
        small, big = d[f"ball gap=0.1mm friction={f}"], d[f"ball gap=0.5mm friction={f}"]
        wins.append(small > big)
        rs = _rms(_case(s, "ball", 10.0, 0.1, f))
        rb = _rms(_case(s, "ball", 10.0, 0.5, f))
        wins.append(float(np.nanmax(rs)) < float(np.nanmax(rb)))
    m = {"gap 0.1 better (depth off, peak RMS off, depth on, peak RMS on)": wins}
    hits = sum(wins)
    verdict = "reproduced" if hits == 4 else "partly" if hits >= 2 else "not reproduced"
    return Verdict(verdict, m, f"the 0.1 mm gap is better in {hits} of 4 comparisons "
                   "(chatter-free depth and peak RMS at 10 N, friction off and on)",
                   ev.figure(preset, "lobes"))


CHECKS = {"H1": check_h1, "H2": check_h2, "H3": check_h3, "H4": check_h4, "H5": check_h5,
          "H6": check_h6, "H7": check_h7, "H8": check_h8, "H9": check_h9, "H10": check_h10,
          "H11": check_h11, "H12": check_h12,
          **{c: _depth_check(c) for c in LOBE_CASES}, "S7": check_s7,
          "D1": check_d1, "D2": check_d2, "D3a": check_d3a, "D3b": check_d3b,
          "D3c": check_d3c, "D3d": check_d3d, "D4": check_d4, "D5": check_d5,
          "D6": check_d6, "K1": check_k1}
