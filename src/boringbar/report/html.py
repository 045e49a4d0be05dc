"""The HTML report of ``boringbar paper`` (the edge of the package, like plot.py).

Written from the files on disk (each step's ``summary.json``, NetCDF files and
figures), so it can be rebuilt without rerunning anything
(:func:`write_report`). Every number in it is read from those files; every
statement that compares the presets or answers a published claim is worded
from the numbers, not written in advance. Figures are linked by relative
paths, so the output folder can be moved or served as it is. A small script
at the end of the page counts the figures that loaded and writes the count
into ``<body data-figures>`` (the headless-browser test reads it).
"""

from __future__ import annotations

import html
import json
import math
import os
from pathlib import Path

import numpy as np

from boringbar.io import atomic_path

_CSS = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1500px;
       padding: 0 1em; color: #222; line-height: 1.45; }
h1 { font-size: 1.6em; } h2 { border-bottom: 2px solid #ccc; margin-top: 2em; }
h3 { margin-top: 1.5em; }
.pair { display: grid; grid-template-columns: 1fr 1fr; gap: 1.2em; align-items: start; }
.pair > div { min-width: 0; }
.pair h4 { margin: 0.3em 0; }
img { max-width: 100%; border: 1px solid #ddd; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.92em; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: right; }
th:first-child, td:first-child { text-align: left; }
code, .cmd { font-family: ui-monospace, monospace; font-size: 0.85em; }
.cmd { background: #f4f4f4; padding: 0.3em 0.5em; display: block; overflow-x: auto;
       white-space: pre; }
.finding { background: #fff8e1; border-left: 4px solid #f0b400; padding: 0.5em 0.9em;
           margin: 0.8em 0; }
.note { color: #555; font-size: 0.92em; }
"""

_SCRIPT = """
<script>
window.addEventListener('load', function () {
  var imgs = Array.prototype.slice.call(document.images);
  var ok = imgs.filter(function (i) { return i.complete && i.naturalWidth > 0; }).length;
  document.body.setAttribute('data-figures', ok + '/' + imgs.length);
});
</script>
"""


def _e(text) -> str:
    return html.escape(str(text))


def _mm(value_m, digits: int = 3) -> str:
    if value_m is None or not math.isfinite(float(value_m)):
        return "-"
    return f"{float(value_m) * 1e3:.{digits}g}"


def _table(head: list[str], rows: list[list]) -> str:
    out = ["<table><tr>" + "".join(f"<th>{_e(h)}</th>" for h in head) + "</tr>"]
    for row in rows:
        out.append("<tr>" + "".join(f"<td>{_e(c)}</td>" for c in row) + "</tr>")
    return "\n".join(out) + "</table>"


class _Report:
    def __init__(self, out: Path, manifest: dict):
        self.out = out
        self.manifest = manifest
        self.presets = manifest["presets"]
        self.steps: dict[tuple[str, str], dict] = {}
        for rec in manifest["steps"]:
            self.steps[(rec["preset"], rec["key"])] = rec
        self.keys = list(dict.fromkeys(r["key"] for r in manifest["steps"]
                                       if r["key"] != "corrections"))

    # --- helpers -------------------------------------------------------------
    def rel(self, path) -> str:
        return os.path.relpath(Path(path), self.out).replace(os.sep, "/")

    def img(self, path, alt: str) -> str:
        return f'<img src="{_e(self.rel(path))}" alt="{_e(alt)}" loading="eager">'

    def summary(self, preset: str, key: str) -> dict | None:
        rec = self.steps.get((preset, key))
        return None if rec is None else rec["summary"]

    def pair(self, key: str, body) -> str:
        """Side-by-side columns, one per preset: body(preset, record) -> html."""
        cols = []
        for preset in self.presets:
            rec = self.steps.get((preset, key))
            if rec is None:
                cols.append(f"<div><h4>{_e(preset)}</h4><p>not run</p></div>")
                continue
            cols.append(f"<div><h4>{_e(preset)} preset</h4>{body(preset, rec)}"
                        f"<span class='cmd'>{_e(rec['command'])}</span>"
                        f"<p class='note'>{rec['wall_time_s']:.1f} s</p></div>")
        return "<div class='pair'>" + "".join(cols) + "</div>"

    def per_key(self, prefix: str, body) -> list[str]:
        """One titled side-by-side pair for every step whose key starts with
        ``prefix``: body(preset, record, key) -> html."""
        parts = []
        for key in [k for k in self.keys if k.startswith(prefix)]:
            title = self.steps[(self.presets[0], key)]["title"]
            parts += [f"<h3>{_e(title)}</h3>",
                      self.pair(key, lambda preset, rec, key=key: body(preset, rec, key))]
        return parts

    # --- sections ------------------------------------------------------------
    def sweeps(self) -> str:
        def body(preset, rec):
            s = rec["summary"]
            parts = [self.img(p, f"sweep {preset}") for p in s["files"]["png"]]
            rows = []
            for c in s["cases"]:
                rms = [-1.0 if v is None else v for v in c["rms_tip_m"]]
                top = max(range(len(rms)), key=rms.__getitem__)
                k = _nearest(c["ratio"], 1.0)
                rows.append([_case_words(c), f"{c['force_n']:g}", _mm(c["rms_tip_m"][top]),
                             f"{c['ratio'][top]:g}", f"{c['ratio'][k]:g}",
                             _mm(c["rms_tip_m"][k]), c["pattern"][k]])
            parts.append(_table(["case", "F0 (N)", "peak RMS (mm)", "peak at r", "r nearest 1",
                                 "RMS there (mm)", "pattern there"], rows))
            return "".join(parts)
        text = ["<h2 id='sweeps'>Frequency sweeps</h2>",
                "<p>Tip RMS against the frequency ratio, referred to the host bar "
                "(docs/model.md, section 6): solid bar, TMD bar and the ball damper for each gap "
                "and friction. Points are marked by impact pattern.</p>",
                self.pair("sweep", body), self._sweep_findings()]
        return "\n".join(text)

    def _sweep_findings(self) -> str:
        out = []
        for preset in self.presets:
            s = self.summary(preset, "sweep")
            if s is None:
                continue
            stick = total = 0
            for c in s["cases"]:
                if c["bar"] == "ball" and c["friction"] == "on":
                    for p in c["pattern"]:
                        total += 1
                        stick += "sticking" in str(p)
            if total:
                out.append(f"<li><b>{_e(preset)}</b>: {stick} of {total} friction-on ball "
                           f"points are sticking or no-impact-with-sticking.</li>")
        if not out:
            return ""
        return ("<div class='finding'>With friction on, how often the ball moves with the "
                "bar instead of impacting:<ul>" + "".join(out) + "</ul>"
                "The paper preset's friction force (20.4 N, see the corrections below) holds "
                "the ball against the bar's acceleration: the ball then acts as a mass "
                "locked to the bar, whatever the gap.</div>")

    def lobes(self) -> str:
        def body(preset, rec):
            s = rec["summary"]
            files = s["files"]
            parts = [self.img(files["png"], f"lobes {preset}")]
            if "examples_png" in files:
                parts.append(self.img(files["examples_png"], f"lobe examples {preset}"))
            rows = []
            for c in s["cases"]:
                analytic = [sp.get("analytic_limit_m") for sp in c["speeds"]]
                analytic = [a for a in analytic if a is not None]
                rows.append([c["case"], _mm(c["min_chatter_free_depth_m"]),
                             _mm(min(analytic)) if analytic else "-"])
            parts.append(_table(["case", "min chatter-free depth, simulated (mm)",
                                 "analytic min over these speeds (mm)"], rows))
            return "".join(parts)
        return "\n".join(["<h2 id='lobes'>Stability lobes</h2>",
                          "<p>Depth of cut against spindle speed by time-domain simulation "
                          "(the published criterion: a cut chatters when the cutting force "
                          "reaches zero), with the analytic lobes of the linear bars (the "
                          "ball damper's host is the bare cavity bar). Example cuts of the "
                          "solid bar below each diagram.</p>",
                          self.pair("lobes", body)])

    def bifurcation(self) -> str:
        parts = ["<h2 id='bifurcation'>Bifurcation diagrams</h2>",
                 "<p>Stroboscopic samples of the tip displacement against F0 at "
                 "Omega = omega_n, forward then backward, each run continuing the previous "
                 "one's state and forcing phase.</p>"]

        def body(preset, rec, key):
            s = rec["summary"]
            ranges = s.get("hysteresis_ranges") or []
            text = (", ".join(f"{a:g} N" if a == b else f"{a:g}-{b:g} N" for a, b in ranges)
                    if ranges else "none: forward and backward agree")
            return (self.img(s["files"]["png"], f"{key} {preset}") +
                    f"<p>Forces where the two directions differ: {_e(text)}</p>")
        return "\n".join(parts + self.per_key("bifurcation", body))

    def basins(self) -> str:
        parts = ["<h2 id='basins'>Basins of attraction</h2>",
                 "<p>Initial tip displacement x velocity coloured by the attractor each run "
                 "ends on, with a Poincare map from the published starting point.</p>"]

        def body(preset, rec, key):
            s = rec["summary"]
            rows = [[a["id"], f"{a['fraction']:.3f}", a["pattern"],
                     a["period"] or "non-periodic", _mm(a["rms_tip_m"])]
                    for a in s["attractors"]]
            return (self.img(s["files"]["png"], f"{key} {preset}") +
                    _table(["attractor", "basin fraction", "pattern", "period",
                            "tip RMS (mm)"], rows))
        return "\n".join(parts + self.per_key("basins", body))

    def sensitivity(self) -> str:
        parts = ["<h2 id='sensitivity'>Sensitivity</h2>",
                 "<p>One parameter varied at a time (ball damper, gap 0.5 mm, friction "
                 "on, F0 = 10 N); for the ball and the friction number also cuts at "
                 "1200 rpm, depths 0.05-0.10 mm.</p>"]
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
            return self.img(s["files"]["png"], f"{key} {preset}") + _table(head, rows)
        return "\n".join(parts + self.per_key("sensitivity", body))

    def corrections(self) -> str:
        rec = next((r for r in self.manifest["steps"] if r["key"] == "corrections"), None)
        if rec is None:
            return ""
        s = rec["summary"]
        ladder = _load(s["ladder_netcdf"])
        rungs = [str(r) for r in ladder["rung"].values]
        gaps = ladder["gap"].values
        rows = []
        for i, r in enumerate(rungs):
            rows.append([r, str(ladder["description"].values[i]),
                         f"{ladder['friction_force_n'].values[i, 0]:.4g}",
                         f"{ladder['host_frequency_hz'].values[i]:.1f}",
                         *[f"{_mm(ladder['rms_tip_m'].values[i, j])} "
                           f"[{ladder['pattern'].values[i, j]}]" for j in range(len(gaps))],
                         f"{ladder['nonreciprocal_work_fraction'].values[i, 0]:.3g}",
                         _mm(ladder["host_min_depth_m"].values[i])])
        head = ["rung", "change", "F_c (N)", "host f1 (Hz)",
                *[f"RMS (mm) [pattern], gap {g * 1e3:g} mm" for g in gaps],
                "work injected / work of force", "host min depth (mm)"]
        imp = s["impact_law"]
        paper_i, rec_i = rungs.index("paper"), rungs.index("reciprocal")
        roll_i = rungs.index("rolling")
        rms = ladder["rms_tip_m"].values
        same_gap = abs(rms[paper_i, 0] - rms[paper_i, -1]) <= 0.01 * rms[paper_i, 0]
        parts = [
            "<h2 id='corrections'>The corrections to the published equations, and what each "
            "changes</h2>",
            "<p>The model (docs/model.md, section 8) corrects the published equations. The "
            "<code>paper</code> preset keeps the three published readings that can be run "
            "(friction force, bar reaction, calibrated stiffness, with one mode and the "
            "published absorber); the impact law is always the corrected one. Each is "
            "measured here.</p>",
            "<h3>1. The sign of the bar's jump at an impact</h3>",
            f"<p>Both laws applied to the {imp['impacts']} impacts of a "
            f"{imp['duration_s']:g} s run (paper preset, gap 0.1 mm, no friction, "
            f"{imp['force_n']:g} N, r = {imp['ratio']:g}). An impact must conserve the "
            "momentum (M/psi_d) u' + m u_d' and must not create kinetic energy.</p>",
            _table(["law", "largest momentum change / (m |y'-|)", "impacts gaining energy",
                    "largest relative energy gain"],
                   [[law, f"{imp['momentum_change_max'][law]:.3g}",
                     f"{imp['impacts_gaining_energy'][law]} of {imp['impacts']}",
                     f"{imp['largest_relative_energy_gain'][law]:.3g}"]
                    for law in ("corrected", "printed")]),
            "<h3>2-4. The published readings, dropped one at a time</h3>",
            "<p>The same run (ball damper, friction on, "
            f"F0 = {ladder.attrs['force_n']:g} N, r = {ladder.attrs['ratio']:g}) on each "
            "rung, from the paper preset to the physical one; each rung keeps the changes "
            "above it.</p>",
            self.img(Path(s["ladder_png"]), "readings ladder"),
            _table(head, rows),
            "<div class='finding'><ul>"
            f"<li><b>Friction force.</b> With 20.4 N the tip RMS is "
            f"{_mm(rms[paper_i, 0])} mm for gap {gaps[0] * 1e3:g} mm and "
            f"{_mm(rms[paper_i, -1])} mm for gap {gaps[-1] * 1e3:g} mm"
            + (" (the same: the gap does not matter, the ball moves with the bar)"
               if same_gap else "") +
            f"; with the physical 0.0204 N they are {_mm(rms[roll_i, 0])} and "
            f"{_mm(rms[roll_i, -1])} mm, patterns "
            f"'{ladder['pattern'].values[roll_i, 0]}' and "
            f"'{ladder['pattern'].values[roll_i, -1]}'.</li>"
            f"<li><b>Bar reaction as printed.</b> It injects "
            f"{ladder['nonreciprocal_work_fraction'].values[paper_i, 0]:.3g} of the work of "
            "the force (zero once corrected); tip RMS "
            f"{_mm(rms[paper_i, 0], 4)} mm printed, {_mm(rms[rec_i, 0], 4)} mm corrected.</li>"
            f"<li><b>Calibrated stiffness.</b> The FE model gives "
            f"{ladder['host_frequency_hz'].values[-1]:.1f} Hz for the cavity bar against the "
            f"published {ladder['host_frequency_hz'].values[paper_i]:.0f} Hz; the analytic "
            f"minimum chatter-free depth of the host moves from "
            f"{_mm(ladder['host_min_depth_m'].values[paper_i])} to "
            f"{_mm(ladder['host_min_depth_m'].values[-1])} mm.</li></ul></div>",
            "<h3>5. The published absorber at z_a = 96 mm</h3>",
        ]
        cols = []
        for preset, rows_a in s["absorbers"].items():
            table = _table(["design", "k_a (MN/m)", "c_a (N s/m)", "mass ratio",
                            "tuning omega_a/omega_n", "peak |G| (um/N)",
                            "analytic min depth (mm)"],
                           [[a["design"], f"{a['stiffness_n_m'] / 1e6:.3g}",
                             f"{a['damping_n_s_m']:.3g}", f"{a['mass_ratio']:.3g}",
                             "-" if a["tuning_ratio"] is None
                             or not math.isfinite(a["tuning_ratio"])
                             else f"{a['tuning_ratio']:.3g}",
                             f"{a['peak_receptance_m_n'] * 1e6:.3g}",
                             _mm(a["min_depth_m"])] for a in rows_a])
            best = max(rows_a, key=lambda a: a["min_depth_m"])
            pub = next(a for a in rows_a if a["design"] == "published")
            cols.append(f"<div><h4>{_e(preset)} preset's solid bar</h4>{table}"
                        f"<p>The published absorber reaches "
                        f"{pub['min_depth_m'] / best['min_depth_m']:.2f} of the best "
                        f"chatter-free depth here ({_e(best['design'])}).</p></div>")
        parts.append("<div class='pair'>" + "".join(cols) + "</div>")
        parts.append(f"<span class='cmd'>{_e(rec['command'])}</span>")
        return "\n".join(parts)

    def cannot(self) -> str:
        """The published claims, each checked against this run's data: reproduced or
        not, with the numbers that say why."""
        items = [self._ball_lobes_claim(preset) for preset in self.presets]
        items += [self._basins_claim(preset) for preset in self.presets]
        items = [i for i in items if i]
        if not items:
            return ""
        return ("<h2 id='cannot'>Published results the model does not reproduce</h2>"
                "<p>Each published claim below is checked against this run's data, and "
                "the verdict and its reason are worded from the numbers.</p><ul>"
                + "".join(items) + "</ul>")

    def _ball_lobes_claim(self, preset: str) -> str:
        s = self.summary(preset, "lobes")
        if s is None:
            return ""
        solid = next((c for c in s["cases"] if c["case"] == "solid"), None)
        balls = [c for c in s["cases"] if c["case"].startswith("ball")]
        if solid is None or not balls:
            return ""
        best = max(balls, key=lambda c: c["min_chatter_free_depth_m"] or 0.0)
        b_best = best["min_chatter_free_depth_m"] or 0.0
        b_solid = solid["min_chatter_free_depth_m"] or 0.0
        raises = b_best > b_solid
        text = (f"<li><b>{'Reproduced' if raises else 'Not reproduced'}: a ball damper "
                f"raises the chatter-free depth</b> ({_e(preset)} preset). The best ball "
                f"case ({_e(best['case'])}) has a minimum chatter-free depth of "
                f"{_mm(b_best)} mm against {_mm(b_solid)} mm for the solid bar.")
        ds = _load(s["files"]["netcdf"])
        if "max_rel_disp" in ds and "host_analytic_limit" in ds:
            text += " " + _ball_at_limit(ds, raises)
        return text + "</li>"

    def _basins_claim(self, preset: str) -> str:
        counts = []
        for key in [k for k in self.keys if k.startswith("basins")]:
            s = self.summary(preset, key)
            if s is not None:
                counts.append((key, len(s["attractors"]),
                               max(a["fraction"] for a in s["attractors"])))
        if not counts:
            return ""
        single = all(n == 1 for _, n, _ in counts)
        return (f"<li><b>{'Not reproduced' if single else 'Reproduced'}: several coexisting "
                f"attractors in the published basins</b> ({_e(preset)} preset). Attractors "
                "found: " + ", ".join(f"{k.replace('basins-', '')}: {n} (largest basin "
                                      f"{f:.0%})" for k, n, f in counts)
                + (". Every initial condition of every published grid ends on the same "
                   "motion." if single else ".") + "</li>")

    def header(self) -> str:
        m = self.manifest
        quick = (" <b>Quick version</b>: coarser grids and shorter runs (each step's command "
                 "says exactly what ran); rerun without <code>--quick</code> for the "
                 "published resolution." if m["quick"] else "")
        toc = "".join(f"<li><a href='#{a}'>{t}</a></li>" for a, t in (
            ("sweeps", "Frequency sweeps"), ("lobes", "Stability lobes"),
            ("bifurcation", "Bifurcation diagrams"), ("basins", "Basins of attraction"),
            ("sensitivity", "Sensitivity"), ("corrections", "Corrections"),
            ("cannot", "Published results the model does not reproduce")))
        if m.get("compute_time_s", 0) > m["wall_time_s"] + 1:
            timing = (f"{m['compute_time_s']:.0f} s of computation ({m['wall_time_s']:.0f} s "
                      "in the last invocation, which reused finished steps)")
        else:
            timing = f"{m['wall_time_s']:.0f} s wall time"
        return (f"<h1>{_e(m['title'])}</h1>"
                f"<p>boringbar {_e(m['boringbar_version'])}; <code>{_e(m['command'])}</code>; "
                f"{timing}.{quick}</p>"
                "<p>Each published analysis (docs/model.md, section 6) is shown with the "
                "<code>paper</code> preset (the published readings: 20.4 N friction, "
                "printed bar reaction, stiffness calibrated to 461/456 Hz, one mode, the "
                "published absorber) on the left and the <code>physical</code> preset (FE "
                "stiffness, two modes, 0.0204 N rolling friction, reciprocal reaction, "
                "Den Hartog absorber) on the right. Under each figure: the command that "
                "reproduces it.</p><ul>" + toc + "</ul>")

    def render(self) -> str:
        body = [self.header(), self.sweeps(), self.lobes(), self.bifurcation(), self.basins(),
                self.sensitivity(), self.corrections(), self.cannot()]
        return ("<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
                "<title>boringbar: the published study</title>"
                f"<style>{_CSS}</style></head><body data-figures='pending'>"
                + "\n".join(body) + _SCRIPT + "</body></html>")


def _load(path):
    """A NetCDF file read whole into memory (the file is closed again)."""
    import xarray as xr

    with xr.open_dataset(path) as ds:
        return ds.load()


def _ball_at_limit(ds, raises: bool) -> str:
    """Why the ball cases' limits are what they are, from the lobes data: per
    case, the first chattering depth against the analytic limit of the bare
    cavity bar, and at each speed's limiting depth how far the ball travelled
    against half the gap and how often it struck a wall."""
    depth = ds["depth"].values
    rows, reach_all, strikes_all, below = [], [], 0, []
    for i in range(ds.sizes["case"]):
        bar = str(ds["bar"].values[i])
        if bar not in ("solid", "ball"):
            continue
        first = ds["first_unstable_depth"].values[i]
        ratio = first / ds["host_analytic_limit"].values[i]
        ratio = ratio[np.isfinite(ratio)]
        reach, strikes = [], 0
        for j in range(ds.sizes["rpm"]):
            lim = float(ds["limit_depth"].values[i, j])
            if bar == "ball" and math.isfinite(lim):
                k = int(round(lim / depth[0])) - 1
                reach.append(float(ds["max_rel_disp"].values[i, j, k]) /
                             (0.5 * float(ds["gap"].values[i])))
                strikes += max(0, int(ds["impacts"].values[i, j, k]))
        if bar == "ball":
            reach_all += reach
            strikes_all += strikes
            if ratio.size and ratio.min() < 1.0:
                below.append((str(ds["case"].values[i]), int((ratio < 1.0).sum())))
        rows.append([str(ds["case"].values[i]),
                     f"{ratio.min():.2f}-{ratio.max():.2f}" if ratio.size else "-",
                     f"{max(reach):.0%}" if reach else "-",
                     str(strikes) if bar == "ball" else "-"])
    if not reach_all:
        return ""
    text = ("Per case, the first chattering depth at each speed against the analytic limit "
            "of the bar the cut sees while the ball does not touch (the bare cavity bar; the "
            "solid bar's own for the solid bar, where a finite run can only place it at or "
            "above), and the ball at each speed's limiting depth:" +
            _table(["case", "first chattering depth / analytic limit of the host",
                    "ball's largest excursion / half gap", "impacts"], rows))
    if strikes_all == 0 and not raises:
        text += ("The ball struck no wall at any limiting depth: at the onset of chatter the "
                 "vibration is too small for it to reach a wall, so the bar cuts as the bare "
                 "cavity bar; a ball can only bound a vibration that has already grown to the "
                 "gap (see --criterion bounded).")
    elif strikes_all == 0:
        text += ("The ball struck no wall at any limiting depth: what it adds comes from "
                 "friction while it slides, not from impacts.")
    if below:
        text += (" Below 1, the cut chattered shallower than the bare cavity bar would at "
                 + ", ".join(f"{n} speed{'s' * (n > 1)} ({_e(c)})" for c, n in below)
                 + ": the ball there adds to the bar instead of damping it (a ball carried "
                   "by friction adds its mass; the printed reaction feeds energy in, as "
                   "measured under the corrections).")
    return text


def _nearest(values: list, target: float) -> int:
    """Index of the value nearest ``target`` (the ratio closest to resonance)."""
    return min(range(len(values)), key=lambda i: abs(values[i] - target))


def _case_words(c: dict) -> str:
    if c["bar"] != "ball":
        return c["bar"]
    return f"ball, gap {c['gap_m'] * 1e3:g} mm, friction {c['friction']}"


def write_report(out, manifest: dict | None = None) -> Path:
    """Write ``out/report.html`` from ``out/manifest.json`` (or ``manifest``)."""
    out = Path(out)
    if manifest is None:
        manifest = json.loads((out / "manifest.json").read_text())
    text = _Report(out, manifest).render()
    path = out / "report.html"
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return path
