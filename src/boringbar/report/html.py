"""The HTML report of ``boringbar paper`` (the edge of the package, like plot/).

Written from the files on disk (each step's ``summary.json``, NetCDF files and
figures), so it can be rebuilt without rerunning anything
(:func:`write_report`). The page is the jinja2 template
``templates/report.html.j2`` (package data); this module only reads the files
and hands the template plain data: table rows of formatted numbers, figure
paths, and the facts each finding is worded from (counts, numbers, which way a
comparison went). The figures come first, each linked to its full-size PNG; the
audit follows, its verdicts counted and its full table folded, each verdict
linked to the figure of the page it is judged on. Every number in the page is
read from those files; every statement that compares the presets or answers a
published claim is worded by the template from those facts, not written in
advance. Figures are linked by relative paths, so the output folder can be
moved or served as it is. A small script at the end of the page counts the
figures that loaded and writes the count into ``<body data-figures>``, and each
figure's width as drawn into its ``data-shown-width`` (the headless-browser test
reads them).
"""

from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path

import numpy as np
import xarray as xr
from jinja2 import Environment, PackageLoader, StrictUndefined, select_autoescape
from markupsafe import Markup, escape

from boringbar.analysis.design import interval_ends
from boringbar.analysis.design_options import objective_reading, reading
from boringbar.io import atomic_path
from boringbar.report.audit import audit
from boringbar.report.audit_data import TOLERANCE, VERDICTS

_ENV = Environment(
    loader=PackageLoader("boringbar.report", "templates"),
    autoescape=select_autoescape(enabled_extensions=("html", "j2"), default_for_string=True),
    undefined=StrictUndefined,  # a value the template needs and is not given fails loudly
    trim_blocks=True,
    lstrip_blocks=True,
    keep_trailing_newline=False,
)


def _words(command: str) -> Markup:
    """A command line whose words do not break: it wraps only between them (a flag
    split at its hyphen reads as two), and copies as it is."""
    return Markup(" ".join(f"<span class='w'>{escape(w)}</span>" for w in command.split(" ")))


_ENV.filters["words"] = _words


def _mm(value_m, digits: int = 3) -> str:
    if value_m is None or not math.isfinite(float(value_m)):
        return "-"
    return f"{float(value_m) * 1e3:.{digits}g}"


def _table(head: list, rows: list[list]) -> dict:
    """A table for the template: header and rows as strings."""
    return {"head": [str(h) for h in head], "rows": [[str(c) for c in row] for row in rows]}


class _Report:
    """The template's data, read from the manifest and the files it names."""

    def __init__(self, out: Path, manifest: dict):
        self.out = out
        self.manifest = manifest
        self.presets = manifest["presets"]
        self.steps: dict[tuple[str, str], dict] = {}
        for rec in manifest["steps"]:
            self.steps[(rec["preset"], rec["key"])] = rec
        self.keys = list(dict.fromkeys(r["key"] for r in manifest["steps"]
                                       if r["key"] != "corrections"))
        #: figure path (relative to the report) -> its anchor in the page
        self.shown: dict[str, str] = {}

    # --- helpers -------------------------------------------------------------
    def img(self, path, alt: str) -> dict:
        """A figure of the page: its path relative to the report, its alt text and its
        anchor (``fig-`` and the path's letters and digits)."""
        src = os.path.relpath(Path(path), self.out).replace(os.sep, "/")
        self.shown[src] = "fig-" + re.sub(r"[^A-Za-z0-9]+", "-", src).strip("-")
        return {"src": src, "alt": alt, "id": self.shown[src]}

    def summary(self, preset: str, key: str) -> dict | None:
        rec = self.steps.get((preset, key))
        return None if rec is None else rec["summary"]

    def pair(self, key: str, body) -> list[dict]:
        """One column per preset: body(preset, record) -> the column's figures,
        table and any facts; ``run`` False where the step is missing."""
        cols = []
        for preset in self.presets:
            rec = self.steps.get((preset, key))
            if rec is None:
                cols.append({"preset": preset, "run": False})
                continue
            cols.append({"preset": preset, "run": True, "command": rec["command"],
                         "wall_time": f"{rec['wall_time_s']:.1f}",
                         "integrator": rec["summary"].get("integrator_used", ""),
                         **body(preset, rec)})
        return cols

    def per_key(self, prefix: str, body) -> list[dict]:
        """A titled pair for every step whose key starts with ``prefix``:
        body(preset, record, key) -> the column's content."""
        groups = []
        for key in [k for k in self.keys if k.startswith(prefix)]:
            title = self.steps[(self.presets[0], key)]["title"]
            groups.append({"title": title, "columns": self.pair(
                key, lambda preset, rec, key=key: body(preset, rec, key))})
        return groups

    # --- sections ------------------------------------------------------------
    def sweeps(self) -> dict:
        def body(preset, rec):
            s = rec["summary"]
            rows = []
            for c in s["cases"]:
                rms = [-1.0 if v is None else v for v in c["rms_tip_m"]]
                top = max(range(len(rms)), key=rms.__getitem__)
                k = _nearest(c["ratio"], 1.0)
                rows.append([_case_words(c), f"{c['force_n']:g}", _mm(c["rms_tip_m"][top]),
                             f"{c['ratio'][top]:g}", f"{c['ratio'][k]:g}",
                             _mm(c["rms_tip_m"][k]), c["pattern"][k]])
            return {"images": [self.img(p, f"sweep {preset}") for p in s["files"]["png"]],
                    "table": _table(["case", "F0 (N)", "largest RMS of the sweep (mm)",
                                     "at r", "r nearest 1", "RMS there (mm)",
                                     "pattern there"], rows)}
        return {"columns": self.pair("sweep", body), "sticking": self._sweep_sticking()}

    def _sweep_sticking(self) -> list[dict]:
        """Per preset, how many friction-on ball points stick (where there are any)."""
        counts = []
        for preset in self.presets:
            s = self.summary(preset, "sweep")
            if s is None:
                continue
            patterns = [str(p) for c in s["cases"]
                        if c["bar"] == "ball" and c["friction"] == "on" for p in c["pattern"]]
            if patterns:
                counts.append({"preset": preset, "total": len(patterns),
                               "sticking": sum("sticking" in p for p in patterns)})
        return counts

    def lobes(self) -> dict:
        def body(preset, rec):
            s = rec["summary"]
            files = s["files"]
            images = [self.img(files["png"], f"lobes {preset}")]
            if "examples_png" in files:
                images.append(self.img(files["examples_png"], f"lobe examples {preset}"))
            rows = []
            for c in s["cases"]:
                analytic = [sp.get("analytic_limit_m") for sp in c["speeds"]]
                analytic = [a for a in analytic if a is not None]
                rows.append([c["case"], _mm(c["min_chatter_free_depth_m"]),
                             _mm(min(analytic)) if analytic else "-"])
            return {"images": images,
                    "line": "method: " + s.get("method_text", s["criterion"]),
                    "table": _table(["case", "min chatter-free depth, simulated (mm)",
                                     "analytic min over these speeds (mm)"], rows)}
        return {"columns": self.pair("lobes", body)}

    def bifurcation(self) -> list[dict]:
        def body(preset, rec, key):
            s = rec["summary"]
            ranges = [{"low": f"{a:g}", "high": None if a == b else f"{b:g}"}
                      for a, b in s.get("hysteresis_ranges") or []]
            return {"images": [self.img(s["files"]["png"], f"{key} {preset}")],
                    "table": None, "hysteresis": ranges}
        return self.per_key("bifurcation", body)

    def continuation(self) -> dict:
        if "continuation" not in self.keys:
            return {"columns": []}

        def body(preset, rec):
            s = rec["summary"]
            images, rows, stops, checks = [], [], [], []
            for key, c in s["cases"].items():
                images.append(self.img(c["files"]["png"], f"continuation {key} {preset}"))
                for i, b in enumerate(c["branches"]):
                    rows.append(_branch_row(key, i, b))
                    stops.append(b["stop"])
                checks += c.get("attractor_check", [])
            return {"images": images, "table": _table(
                        ["case", "branch (period, born at, N)", "points", "F0 covered (N)",
                         "stable (N)", "events (N)", "why it stopped"], rows),
                    "facts": _stop_facts(stops),
                    "attractors": len(checks),
                    "on_stable": sum(c["on_stable_branch"] for c in checks),
                    "overlaid": sum(c["overlay"] for c in s["cases"].values()),
                    "cases": len(s["cases"])}
        return {"columns": self.pair("continuation", body)}

    def chatter_orbits(self) -> dict:
        if "chatter-orbits" not in self.keys:
            return {"columns": []}

        def body(preset, rec):
            s = rec["summary"]
            rows = [[c["case"], e["kind"] + (f" ({e['detail']})" if e["detail"] else ""),
                     f"{e['depth_mm']:.5g}", f"{e['amplitude_mm'] * 1e3:.4g}",
                     f"{e['frequency_hz']:.5g}"] for c in s["cases"] for e in c["events"]]
            stops = [f"{c['case']}: {c['points']} orbits, {c['stop']}" for c in s["cases"]]
            return {"images": [self.img(s["files"]["png"], f"chatter orbits {preset}")],
                    "table": _table(["bar", "event", "depth (mm)", "amplitude (um)",
                                     "frequency (Hz)"], rows),
                    "line": "; ".join(stops) + "."}
        return {"columns": self.pair("chatter-orbits", body)}

    def basins(self) -> list[dict]:
        def body(preset, rec, key):
            s = rec["summary"]
            rows = [[a["id"], f"{a['fraction']:.3f}", a["pattern"],
                     a["period"] or "non-periodic", _mm(a["rms_tip_m"])]
                    for a in s["attractors"]]
            return {"images": [self.img(s["files"]["png"], f"{key} {preset}")],
                    "table": _table(["attractor", "basin fraction", "pattern", "period",
                                     "tip RMS (mm)"], rows)}
        return self.per_key("basins", body)

    def sensitivity(self) -> list[dict]:
        def body(preset, rec, key):
            s = rec["summary"]
            rows = []
            for h in s["harmonic"]:
                k = _nearest(h["ratio"], 1.0)
                row = [h["value"], f"{h['ratio'][k]:g}", _mm(h["rms_tip_m"][k]),
                       h["pattern"][k]]
                if s.get("cuts"):
                    res = next(r for r in s["cuts"]["results"] if r["value"] == h["value"])
                    n_ch = sum(bool(c) for c in res["chatter"])
                    row.append(f"{n_ch} of {len(res['chatter'])}")
                rows.append(row)
            head = ["value", "r nearest 1", "RMS at r (mm)", "pattern at r"]
            if s.get("cuts"):
                head.append("cuts that chatter")
            return {"images": [self.img(s["files"]["png"], f"{key} {preset}")],
                    "table": _table(head, rows)}
        return self.per_key("sensitivity", body)

    def design(self) -> list[dict]:
        def body(preset, rec, key):
            s = rec["summary"]
            pub = json.loads(_load(s["files"]["netcdf"]).attrs["published_values"])
            rows = [_design_row(k, v, pub.get(k, "-")) for k, v in s["best"].items()]
            unit, k = objective_reading(s["objective_name"], s["statistic_name"])
            rows.append([f"{s['statistic_name']} of {s['objective_name']}"
                         + (f" ({unit})" if unit else ""),
                         f"{s['objective'] * k:.4g}", f"{s['published_objective'] * k:.4g}"])
            rows.append(["improvement" + (f" ({unit})" if unit else "")
                         + f", {round(100 * s['confidence'])} % CI", improvement_cell(s, k), "-"])
            if "pareto" in s:
                rows.append(["designs on the Pareto front", str(len(s["pareto"])), "-"])
            found = s["improvement"] > 0 and s["significant"] is not False
            return {"images": [self.img(s["files"]["png"], f"{key} {preset}"),
                               self.img(s["files"]["best_png"], f"{key} best {preset}")],
                    "table": _table(["", "best design" if found else "best design tried",
                                     "the file's design"], rows),
                    "line": s["summary"]}
        return self.per_key("design", body)

    def corrections(self) -> dict | None:
        rec = next((r for r in self.manifest["steps"] if r["key"] == "corrections"), None)
        if rec is None:
            return None
        s = rec["summary"]
        ladder = _load(s["ladder_netcdf"])
        return {"impact": _impact_law(s["impact_law"]),
                "ladder": {"force": f"{ladder.attrs['force_n']:g}",
                           "ratio": f"{ladder.attrs['ratio']:g}",
                           "image": self.img(Path(s["ladder_png"]), "readings ladder"),
                           "table": _ladder_table(ladder)},
                **_ladder_findings(ladder),
                "absorbers": [_absorbers(preset, rows) for preset, rows
                              in s["absorbers"].items()],
                "command": rec["command"]}

    def cannot(self) -> list[dict]:
        """The published claims, each checked against this run's data: the facts
        (reproduced or not, and the numbers that say why) for the template."""
        items = [self._ball_lobes_claim(preset) for preset in self.presets]
        items += [self._basins_claim(preset) for preset in self.presets]
        return [i for i in items if i]

    def _ball_lobes_claim(self, preset: str) -> dict | None:
        s = self.summary(preset, "lobes")
        if s is None:
            return None
        solid = next((c for c in s["cases"] if c["case"] == "solid"), None)
        balls = [c for c in s["cases"] if c["case"].startswith("ball")]
        if solid is None or not balls:
            return None
        best = max(balls, key=lambda c: c["min_chatter_free_depth_m"] or 0.0)
        b_best = best["min_chatter_free_depth_m"] or 0.0
        b_solid = solid["min_chatter_free_depth_m"] or 0.0
        ds = _load(s["files"]["netcdf"])
        why = (_ball_at_limit(ds) if "max_rel_disp_m" in ds and "host_analytic_limit_m" in ds
               else None)
        return {"claim": "ball_lobes", "preset": preset, "reproduced": b_best > b_solid,
                "best_case": best["case"], "best_depth": _mm(b_best),
                "solid_depth": _mm(b_solid), "why": why}

    def _basins_claim(self, preset: str) -> dict | None:
        counts = []
        for key in [k for k in self.keys if k.startswith("basins")]:
            s = self.summary(preset, key)
            if s is not None:
                counts.append({"grid": key.replace("basins-", ""),
                               "attractors": len(s["attractors"]),
                               "largest": f"{max(a['fraction'] for a in s['attractors']):.0%}"})
        if not counts:
            return None
        single = all(c["attractors"] == 1 for c in counts)
        return {"claim": "basins", "preset": preset, "reproduced": not single,
                "counts": counts}

    def header(self) -> dict:
        m = self.manifest
        return {"title": m["title"], "version": m["boringbar_version"],
                "command": m["command"], "quick": bool(m["quick"]),
                "reused": any(r.get("reused") for r in m["steps"]),
                # steps run side by side: their times add up to more than the wall time
                "overlapped": m.get("compute_time_s", 0) > m["wall_time_s"] + 1,
                "compute_time": f"{m.get('compute_time_s', 0):.0f}",
                "wall_time": f"{m['wall_time_s']:.0f}"}

    def audit(self) -> dict:
        """The audit (report/audit.py) for the template: the verdicts counted per column,
        and the table, each verdict linked to its figure in the page (where the page
        shows it: call after the sections that show figures), else to the PNG."""
        result = audit(self.out)
        rows = []
        for c in result["claims"]:
            published = "; ".join(  # a ratio's unit "1" left out
                f"{p['name']} {p['value']}{' ' + p['unit'] if p['unit'] not in ('', '1') else ''}"
                for p in c["published"])
            cells = [{"verdict": c["verdict"][p], "css": _VERDICT_CSS[c["verdict"][p]],
                      "reason": c["reason"][p], "figure": self._figure_link(c["figure"][p]),
                      "measured": "; ".join(f"{k} {v}" for k, v in c["measured"][p].items())}
                     for p in result["presets"]]
            rows.append({"id": c["id"], "source": c["source"], "statement": c["statement"],
                         "published": published, "cells": cells})
        variants = {v["name"]: v["description"] for v in result["variants"]}
        heads = [p if p in variants else f"{p} preset" for p in result["presets"]]
        counts = [{"column": head, "cells": [{"count": result["counts"][p][v],
                                              "css": _VERDICT_CSS[v]} for v in VERDICTS]}
                  for p, head in zip(result["presets"], heads, strict=True)]
        return {"rows": rows, "presets": heads, "quick": result["quick"],
                "variants": [{"name": k, "description": d} for k, d in variants.items()],
                "verdicts": [{"name": v, "css": _VERDICT_CSS[v]} for v in VERDICTS],
                "counts": counts, "tolerance": f"{TOLERANCE:.0%}"}

    def _figure_link(self, figure: str | None) -> str | None:
        """The anchor of ``figure`` (a path relative to the report) where the page shows
        it, else the path itself."""
        if figure is None:
            return None
        return "#" + self.shown[figure] if figure in self.shown else figure

    def context(self) -> dict:
        sections = {"header": self.header(), "sweeps": self.sweeps(), "lobes": self.lobes(),
                    "bifurcation": self.bifurcation(), "continuation": self.continuation(),
                    "chatter_orbits": self.chatter_orbits(),
                    "basins": self.basins(), "sensitivity": self.sensitivity(),
                    "design": self.design(), "corrections": self.corrections(),
                    "cannot": self.cannot()}
        return {**sections, "audit": self.audit()}  # last: it links to the figures shown


#: The CSS class of each verdict's colour.
_VERDICT_CSS = {"reproduced": "reproduced", "partly": "partly", "not reproduced": "not",
                "not available": "na"}


def _load(path):
    """A NetCDF file read whole into memory (the file is closed again)."""
    with xr.open_dataset(path) as ds:
        return ds.load()


def _impact_law(imp: dict) -> dict:
    """The impact-law check (corrected against printed) for the template."""
    rows = [[law, f"{imp['momentum_change_max'][law]:.3g}",
             f"{imp['impacts_gaining_energy'][law]} of {imp['impacts']}",
             f"{imp['largest_relative_energy_gain'][law]:.3g}"]
            for law in ("corrected", "printed")]
    return {"impacts": imp["impacts"], "duration": f"{imp['duration_s']:g}",
            "force": f"{imp['force_n']:g}", "ratio": f"{imp['ratio']:g}",
            "table": _table(["law", "largest momentum change / (m |y'-|)",
                             "impacts gaining energy", "largest relative energy gain"], rows)}


def _ladder_table(ladder) -> dict:
    """One row per rung of the readings ladder, one RMS column per gap."""
    gaps = ladder["gap_m"].values
    rows = []
    for i, r in enumerate(ladder["rung"].values):
        rows.append([str(r), str(ladder["description"].values[i]),
                     f"{ladder['friction_force_n'].values[i, 0]:.4g}",
                     f"{ladder['host_frequency_hz'].values[i]:.1f}",
                     *[f"{_mm(ladder['rms_tip_m'].values[i, j])} "
                       f"[{ladder['pattern'].values[i, j]}]" for j in range(len(gaps))],
                     f"{ladder['nonreciprocal_work_fraction'].values[i, 0]:.3g}",
                     _mm(ladder["host_min_depth_m"].values[i])])
    head = ["rung", "change", "F_c (N)", "host f1 (Hz)",
            *[f"RMS (mm) [pattern], gap {g * 1e3:g} mm" for g in gaps],
            "work injected / work of force", "host min depth (mm)"]
    return _table(head, rows)


def _ladder_findings(ladder) -> dict:
    """The facts of the three findings under the ladder: friction force, bar
    reaction, calibrated stiffness (paper rung against the later ones)."""
    rungs = [str(r) for r in ladder["rung"].values]
    paper_i, rec_i, roll_i = (rungs.index(r) for r in ("paper", "reciprocal", "rolling"))
    gaps = ladder["gap_m"].values
    rms = ladder["rms_tip_m"].values
    pattern = ladder["pattern"].values
    hz = ladder["host_frequency_hz"].values
    depth = ladder["host_min_depth_m"].values
    return {
        "friction": {"gap_first": f"{gaps[0] * 1e3:g}", "gap_last": f"{gaps[-1] * 1e3:g}",
                     "paper_first": _mm(rms[paper_i, 0]), "paper_last": _mm(rms[paper_i, -1]),
                     "gap_irrelevant": bool(abs(rms[paper_i, 0] - rms[paper_i, -1])
                                            <= 0.01 * rms[paper_i, 0]),
                     "rolling_first": _mm(rms[roll_i, 0]),
                     "rolling_last": _mm(rms[roll_i, -1]),
                     "rolling_pattern_first": str(pattern[roll_i, 0]),
                     "rolling_pattern_last": str(pattern[roll_i, -1])},
        "reaction": {"work_fraction":
                     f"{ladder['nonreciprocal_work_fraction'].values[paper_i, 0]:.3g}",
                     "printed": _mm(rms[paper_i, 0], 4), "corrected": _mm(rms[rec_i, 0], 4)},
        "stiffness": {"fe_hz": f"{hz[-1]:.1f}", "published_hz": f"{hz[paper_i]:.0f}",
                      "paper_depth": _mm(depth[paper_i]), "fe_depth": _mm(depth[-1])},
    }


def _absorbers(preset: str, rows_a: list[dict]) -> dict:
    """The absorber designs on one preset's solid bar, and how the published one
    compares with the best."""
    rows = [[a["design"], f"{a['stiffness_n_m'] / 1e6:.3g}", f"{a['damping_n_s_m']:.3g}",
             f"{a['mass_ratio']:.3g}",
             "-" if a["tuning_ratio"] is None or not math.isfinite(a["tuning_ratio"])
             else f"{a['tuning_ratio']:.3g}",
             f"{a['peak_receptance_m_n'] * 1e6:.3g}", _mm(a["min_depth_m"])] for a in rows_a]
    best = max(rows_a, key=lambda a: a["min_depth_m"])
    pub = next(a for a in rows_a if a["design"] == "published")
    return {"preset": preset,
            "table": _table(["design", "k_a (MN/m)", "c_a (N s/m)", "mass ratio",
                             "tuning omega_a/omega_n", "peak |G| (um/N)",
                             "analytic min depth (mm)"], rows),
            "published_of_best": f"{pub['min_depth_m'] / best['min_depth_m']:.2f}",
            "best": best["design"]}


def _ball_at_limit(ds) -> dict | None:
    """Why the ball cases' limits are what they are, from the lobes data: per
    case, the first chattering depth against the analytic limit of the bare
    cavity bar, and at each speed's limiting depth how far the ball travelled
    against half the gap and how often it struck a wall. None when no ball
    case has a limiting depth, or the lobes are judged by the converged verdict (its
    runs keep no fixed-run excursion; the growth rates and settled vibrations say it)."""
    if "max_rel_disp_m" not in ds:
        return None
    depth = ds["depth_m"].values
    rows, reach_all, strikes_all, below = [], [], 0, []
    for i in range(ds.sizes["case"]):
        bar = str(ds["bar"].values[i])
        if bar not in ("solid", "ball"):
            continue
        ratio = ds["first_unstable_depth_m"].values[i] / ds["host_analytic_limit_m"].values[i]
        ratio = ratio[np.isfinite(ratio)]
        reach, strikes = [], 0
        for j in range(ds.sizes["rpm"]):
            lim = float(ds["limit_depth_m"].values[i, j])
            if bar == "ball" and math.isfinite(lim):
                k = int(round(lim / depth[0])) - 1
                reach.append(float(ds["max_rel_disp_m"].values[i, j, k]) /
                             (0.5 * float(ds["gap_m"].values[i])))
                strikes += max(0, int(ds["impacts"].values[i, j, k]))
        if bar == "ball":
            reach_all += reach
            strikes_all += strikes
            if ratio.size and ratio.min() < 1.0:
                below.append({"case": str(ds["case"].values[i]),
                              "speeds": int((ratio < 1.0).sum())})
        rows.append([str(ds["case"].values[i]),
                     f"{ratio.min():.2f}-{ratio.max():.2f}" if ratio.size else "-",
                     f"{max(reach):.0%}" if reach else "-",
                     str(strikes) if bar == "ball" else "-"])
    if not reach_all:
        return None
    return {"table": _table(["case", "first chattering depth / analytic limit of the host",
                             "ball's largest excursion / half gap", "impacts"], rows),
            "strikes": strikes_all, "below": below}


def _branch_row(key: str, i: int, b: dict) -> list:
    """A branch of an orbit map as a table row (its summary from analysis.continuation):
    its birth, the F0 it covers and its stable stretches."""
    pts = b["points"]
    covered = f"{min(p['value'] for p in pts):.4g}-{max(p['value'] for p in pts):.4g}" \
        if pts else "-"
    events = ", ".join(f"{e['kind']} {e['value']:.4g}" for e in b["events"]) or "-"
    born = b.get("born", {"kind": "start", "value": math.nan})
    parent = "" if b.get("parent") is None else f" of {b['parent']}"
    mirror = "" if b.get("mirror") is None else f", mirror of {b['mirror']}"
    name = f"{i} ({b.get('periods', 1)}, {born['kind']}{parent} {born['value']:.4g}{mirror})"
    return [key, name, len(pts), covered, _stable_stretches(pts), events, b["stop"]]


def _stable_stretches(pts: list) -> str:
    """The F0 ranges of a branch's consecutive stable points ("-" if none)."""
    out, run = [], []
    for p in [*pts, {"stable": False}]:
        if p["stable"]:
            run.append(p["value"])
        elif run:
            out.append(f"{min(run):.4g}-{max(run):.4g}" if len(run) > 1 else f"{run[0]:.4g}")
            run = []
    return ", ".join(out) or "-"


def _stop_facts(stops: list[str]) -> dict:
    """How the branches ended, counted from their stop reasons (the words of
    boringbar.orbits)."""
    start = [s for s in stops if "refused at the start" in s]  # a map without branches
    later = [s for s in stops if "refused at the start" not in s]
    return {"branches": len(stops), "refused_start": len(start),
            "start_stick": sum("stick" in s for s in start),
            "start_singular": sum("singular" in s for s in start),
            "end": sum(s.startswith("end of range") for s in later),
            "max_points": sum(s.startswith("point budget") for s in later),
            "stick": sum("stick" in s for s in later),
            "wall": sum("wall contact" in s for s in later),
            "grazing": sum("grazing" in s for s in later),
            "section": sum("Poincare section" in s for s in later),
            "corrector": sum("corrector did not converge" in s for s in later)}


def _fmt(v) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def _design_row(name: str, best, published) -> list[str]:
    """A design variable's row: its name and unit as a person reads them (lengths in
    mm), the best design's value and the published one's."""
    words, unit, factor = reading(name)
    return [f"{words} ({unit})" if unit else words,
            *(_fmt(v * factor if isinstance(v, float) else v) for v in (best, published))]


def improvement_cell(s: dict, k: float) -> str:
    """The design table's improvement: '+0.007 (-0.004 to +0.018): within noise', or
    with the reason there is no interval (one sample)."""
    text = f"{s['improvement'] * k:+.3g}"
    interval = s["improvement_interval"]
    if interval is None:
        return f"{text} ({s['interval_note']})"
    text += " ({} to {})".format(*interval_ends(interval[0] * k, interval[1] * k))
    return text + ("" if s["significant"] else ": within noise")


def _nearest(values: list, target: float) -> int:
    """Index of the value nearest ``target`` (the ratio closest to resonance)."""
    return min(range(len(values)), key=lambda i: abs(values[i] - target))


def _case_words(c: dict) -> str:
    if c["bar"] != "ball":
        return c["bar"]
    return f"ball, gap {c['gap_m'] * 1e3:g} mm, friction {c['friction']}"


def render_report(out, manifest: dict) -> str:
    """The report's HTML for the study in ``out`` described by ``manifest``."""
    return _ENV.get_template("report.html.j2").render(_Report(Path(out), manifest).context())


def write_report(out, manifest: dict | None = None) -> Path:
    """Write ``out/report.html`` from ``out/manifest.json`` (or ``manifest``)."""
    out = Path(out)
    if manifest is None:
        manifest = json.loads((out / "manifest.json").read_text())
    text = render_report(out, manifest)
    path = out / "report.html"
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return path
