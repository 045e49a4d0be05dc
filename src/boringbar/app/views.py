"""What each view of the design page shows, computed from a :class:`Design` as plain
arrays in the page's units (mm, ms, Hz, rpm): pure functions of the design, so the
page can run them in worker threads and a test can check them without a browser.

- :func:`bar_view`: the bar to scale and its first modes;
- :func:`run_view`: one run of the design's damped bar;
- :func:`response_view`: the tip's RMS against forcing frequency, the ball bar
  simulated at :data:`RESPONSE_RATIOS`, the solid and TMD bars in closed form;
- :func:`lobes_view`: the analytic lobes of every bar and the chatter-free depth at
  the design's speed; :func:`simulated_lobes`: the ball bar's by simulating cuts.
"""

from __future__ import annotations

import json
import math
import threading
import time
from collections import OrderedDict

import numpy as np

from boringbar.analysis.lobes import LobesOptions, lobes
from boringbar.analysis.speeds import lobe_speeds as default_lobe_speeds
from boringbar.analysis.sweep import SweepOptions, sweep, tmd_window
from boringbar.app.design_state import DT_S, RUN_S, Design
from boringbar.execute import Execution
from boringbar.model.cutting import KR_ALUMINIUM
from boringbar.model.system import describe_modes, make_system
from boringbar.reference.stability import (
    limit_at_speeds,
    system_receptance,
)
from boringbar.simulate import Integration, simulate

#: forcing ratios (Omega / omega_n of the ball bar) the response simulates
RESPONSE_RATIOS = tuple(float(r) for r in np.linspace(0.85, 1.15, 11))
#: closed-form points per linear bar's response curve
RESPONSE_POINTS = 400
#: forcing periods the run's time plots show (the end of the run)
PERIODS_SHOWN = 12
#: spindle speeds the analytic lobes are drawn at, from at most LOW_RPM (the published
#: study's lowest speed) up
LOBE_POINTS = 300
LOW_RPM = 900.0
#: results kept for the next request (:func:`kept`): lobe curves, sweeps, mode tables
KEPT = 64
_KEPT: OrderedDict[str, object] = OrderedDict()
_KEPT_LOCK = threading.Lock()
#: speeds and cut length of the simulated lobes (a quick diagram: the `lobes` command
#: gives the full one)
SIMULATED_SPEEDS = 8
SIMULATED_CUT_S = 0.5


def bar_view(design: Design, n_modes: int = 3) -> dict:
    """The bar's outline (mm), its cavity, ball and absorber, and the first
    ``n_modes`` modes of the bar with its cavity (or the solid bar)."""
    spec, data = design.spec, design.data
    sections, z0 = [], 0.0
    for s in data["bar"]["sections"]:
        sections.append({"z0": z0, "z1": s["end_mm"], "d": s["diameter_mm"],
                         "bore": s.get("bore_mm", 0.0)})
        z0 = s["end_mm"]
    out = {"sections": sections, "cavity": None, "ball": None, "tmd": None}
    if spec.cavity is not None:
        c = data["cavity"]
        out["cavity"] = {"z0": c["position_mm"] - c["length_mm"] / 2,
                         "z1": c["position_mm"] + c["length_mm"] / 2, "depth": c["depth_mm"]}
    if spec.ball is not None:
        out["ball"] = {"z": data["cavity"]["position_mm"], "d": data["ball"]["diameter_mm"],
                       "gap": data["ball"]["gap_mm"]}
    if spec.tmd is not None:
        out["tmd"] = {"z": data["tmd"]["position_mm"], "mass_kg": data["tmd"]["mass_kg"]}
    # the bar `boringbar modes` describes by default (the damped one), with as many
    # modes as it shows; they do not move with the ball or the absorber's mass (only
    # with its position)
    kind = damped(design).kind
    bare = {k: v for k, v in data.items() if k not in ("ball", "tmd")}
    key = [bare, spec.absorber_position_m, kind, design.settings.preset, n_modes]
    table = kept(["modes", *key], lambda: describe_modes(
        make_system(kind, design.settings.preset, spec=spec, n_modes=n_modes)))
    nodes, shapes, _ = kept(["shapes", *key],
                            lambda: spec.mode_shapes(spec.ball is not None, n_modes))
    out["modes"] = [{"frequency_hz": m["frequency_hz"], "modal_mass_kg": m["modal_mass_kg"],
                     "tip_stiffness_n_m": m["modal_stiffness_n_m"]}
                    for m in table["modes"][:n_modes]]
    out["static_stiffness_n_m"] = table["tip_static_stiffness_n_m"]
    out["shapes"] = {"z": nodes * 1e3, "w": shapes[:, :len(out["modes"])].T}
    return out


def damped(design: Design):
    """The bar the page runs: the ball bar if there is a ball, else the TMD bar, else
    the solid one."""
    systems = design.systems
    return systems.get("ball", systems.get("tmd", systems["solid"]))


def run_view(design: Design) -> dict:
    """One run of the damped bar: the last :data:`PERIODS_SHOWN` periods of the tip
    and of the ball between its walls (mm against ms), the impacts (phase in the
    forcing period against period number), the pattern, the energies (J)."""
    system, forcing = damped(design), design.forcing()
    t0 = time.perf_counter()
    run = simulate(system, forcing, duration_s=RUN_S, dt_s=DT_S,
                   integrator=design.settings.integrator)
    h = run.history
    period = 2 * math.pi / run.omega_rad_s
    shown = h[:, 0] >= h[-1, 0] - PERIODS_SHOWN * period
    imp = run.impacts[run.impacts[:, 0] >= run.steady_start_s] if run.impacts.size else \
        np.zeros((0, 3))
    s = run.summary()
    return {
        "t_ms": h[shown, 0] * 1e3, "tip_mm": h[shown, 1] * 1e3,
        "aux_mm": h[shown, 3] * 1e3, "aux": "ball" if system.kind == "ball" else
        ("absorber" if system.kind == "tmd" else None),
        "half_gap_mm": system.damper.gap_m / 2 * 1e3 if system.kind == "ball" else None,
        "impact_cycle": np.floor(imp[:, 0] / period),
        "impact_phase": (imp[:, 0] / period) % 1.0, "impact_wall": imp[:, 1],
        "pattern": s["pattern"], "rms_tip_mm": s["rms_tip_m"] * 1e3,
        "energy": run.energy, "integrator": run.integrator, "bar": system.kind,
        "chatter": s["cutting"]["chatter"] if "cutting" in s else None,
        "elapsed_s": time.perf_counter() - t0,
    }


def response_view(design: Design, progress=None) -> dict:
    """Tip RMS (mm) against forcing frequency (Hz) at the design's force: the ball
    bar simulated at :data:`RESPONSE_RATIOS` of its own f1 (with its patterns), the
    solid and TMD bars in closed form (RMS = |G| F / sqrt 2) over the same band."""
    systems, force = design.systems, design.settings.force_n
    host = systems.get("ball", systems["solid"])
    f1 = host.reference_frequency_rad_s / (2 * math.pi)
    f = np.linspace(*response_band(design, f1), RESPONSE_POINTS)
    out = {"f_hz": f, "curves": {}}
    for kind in ("solid", "tmd"):
        if kind in systems:
            g = system_receptance(systems[kind], 2 * math.pi * f)
            out["curves"][kind] = np.abs(g) * force / math.sqrt(2) * 1e3
    if "ball" in systems:
        rms, patterns = kept(["sweep", physics(systems["ball"]), force,
                              design.settings.integrator],
                             lambda: _ball_sweep(systems["ball"], design, progress))
        out.update(ball_f_hz=np.array(RESPONSE_RATIOS) * f1, ball_rms_mm=rms,
                   ball_pattern=patterns)
    return out


def _ball_sweep(system, design: Design, progress) -> tuple[np.ndarray, list[str]]:
    """Tip RMS (mm) and pattern of the ball bar at :data:`RESPONSE_RATIOS`."""
    ds = sweep([system], SweepOptions(forces_n=(design.settings.force_n,),
                                      ratios=RESPONSE_RATIOS),
               integration=Integration(duration_s=RUN_S, dt_s=DT_S,
                                       integrator=design.settings.integrator),
               progress=progress)
    return (ds["rms_tip_m"].values.reshape(-1) * 1e3,
            [str(p) for p in ds["pattern"].values.reshape(-1)])


def response_band(design: Design, f1: float) -> tuple[float, float]:
    """The band (Hz) the response is drawn over: the simulated ratios of the ball
    bar's f1, widened to the TMD bar's window (its two peaks: what ``boringbar sweep``
    takes by default for it), which a band around f1 alone would hide."""
    lo, hi = RESPONSE_RATIOS[0] * f1, RESPONSE_RATIOS[-1] * f1
    tmd = design.systems.get("tmd")
    if tmd is not None:
        f_tmd = tmd.reference_frequency_rad_s / (2 * math.pi)
        w_lo, w_hi = tmd_window(tmd)
        lo, hi = min(lo, w_lo * f_tmd), max(hi, w_hi * f_tmd)
    return lo, hi


def lobe_speeds(design: Design) -> np.ndarray:
    """The speeds (rpm) the lobes are drawn over, evenly in the lobe number: the command
    line's default band (the first lobes of every bar, from their first frequencies)
    down to the published study's :data:`LOW_RPM`, widened only if the design's speed
    falls outside it (so moving the speed within it redraws no curve)."""
    f1 = [s.reference_frequency_rad_s / (2 * math.pi) for s in design.systems.values()]
    band = default_lobe_speeds(f1)
    lo, hi, rpm = min(band[0], LOW_RPM), band[-1], design.settings.rpm
    lo, hi = (lo if rpm >= lo else rpm / 1.2), (hi if rpm <= hi else rpm * 1.2)
    # evenly in 1/rpm, the lobe number's axis: every lobe gets as many points
    return np.sort(1.0 / np.linspace(1.0 / hi, 1.0 / lo, LOBE_POINTS))


def kept(key, compute):
    """``compute()``, or what it gave for the same ``key`` (any JSON-able value) a
    request before: a change of one bar's description leaves the others' curves,
    sweeps and modes as they were.  The last :data:`KEPT` results are kept."""
    found = known(key)
    if found is not None:
        return found
    value = compute()
    with _KEPT_LOCK:
        _KEPT[_key_text(key)] = value
        while len(_KEPT) > KEPT:
            _KEPT.popitem(last=False)
    return value


def known(key):
    """What :func:`kept` holds for ``key``, or None."""
    text = _key_text(key)
    with _KEPT_LOCK:
        if text in _KEPT:
            _KEPT.move_to_end(text)
            return _KEPT[text]
    return None


def _key_text(key) -> str:
    return json.dumps(key, sort_keys=True, default=str)


def lobe_curve(system, rpm: np.ndarray, at: float,
               kr_pa: float = KR_ALUMINIUM) -> tuple[np.ndarray, float]:
    """The analytic chatter-free depth (mm) of ``system`` at ``rpm`` (:func:`kept`;
    a free ball's is its bare host's, which the ball's gap and friction leave alone)
    and at the speed ``at``, found with the curve when the curve is new (one
    frequency grid and one bisection for both); ``kr_pa``: the cut's law linearised at
    its feed (Pa, :attr:`~boringbar.model.forcing.Regenerative.linear_coefficient_pa`)."""
    host = system.linear_host()
    key = ["lobes", physics(host), rpm.tolist(), kr_pa]
    curve = known(key)
    if curve is None:
        both = limit_at_speeds(host, np.append(rpm, at), kr_pa) * 1e3
        return kept(key, lambda: both[:-1]), float(both[-1])
    return curve, float(limit_at_speeds(host, [at], kr_pa)[0]) * 1e3


def physics(system) -> dict:
    """What a system's results depend on: its bar and damper (its description without
    the system file it came from, whose other parts it does not use)."""
    return {k: v for k, v in system.to_dict().items() if k != "system_file"}


def lobes_view(design: Design) -> dict:
    """The analytic chatter-free depth (mm) against speed of every bar (for the ball
    bar, its linear host: the bar a small vibration sees, the ball held by its friction
    or, without friction, not acting), and each one's depth at the design's speed."""
    rpm, at = lobe_speeds(design), design.settings.rpm
    out = {"rpm": rpm, "curves": {}, "at_rpm": at, "depth_at_mm": {}}
    kr = design.cut().linear_coefficient_pa
    for kind, system in design.systems.items():
        out["curves"][kind], out["depth_at_mm"][kind] = lobe_curve(system, rpm, at, kr)
    return out


def simulated_speeds(design: Design) -> np.ndarray:
    """The speeds (whole rpm) the simulated lobes cut at: :data:`SIMULATED_SPEEDS`
    across the lobe band and the design's speed."""
    band = lobe_speeds(design)
    return np.unique(np.append(np.geomspace(band[0], band[-1], SIMULATED_SPEEDS).round(),
                               design.settings.rpm))


def simulated_lobes(design: Design, progress=None, workers: int | None = None) -> dict:
    """The ball bar's chatter-free depth (mm) at :data:`SIMULATED_SPEEDS` speeds over
    the lobe band and at the design's speed, by simulating cuts (bisection,
    ``progress(done, total)`` as speeds finish; raising in it stops the rest)."""
    system = design.systems["ball"]
    rpm = simulated_speeds(design)
    ds = lobes([system], LobesOptions(rpm=tuple(rpm), method="search", analytic=False),
               integration=Integration(duration_s=SIMULATED_CUT_S),
               execution=Execution("threads", workers=workers), progress=progress)
    limit = ds["limit_depth_m"].values[0] * 1e3
    return {"rpm": rpm, "limit_mm": limit, "method": ds.attrs["method_text"],
            "max_depth_mm": LobesOptions().max_depth_m * 1e3,
            "depth_at_mm": float(limit[np.searchsorted(rpm, design.settings.rpm)])}


def inputs(view: str, design: Design) -> str:
    """What ``view`` depends on, as text: a change that leaves it alone needs no
    recomputation (the lobes and the bar do not move with the gap; the analytic lobes
    see the ball bar's linear host, which the gap does not change: its kind and the
    mass it adds stand for the ball)."""
    data, s = design.data, design.settings
    if view == "lobes":
        host = design.systems["ball"].linear_host() if data.pop("ball", None) else None
        used = [s.preset, s.rpm, None if host is None or host.damper is None
                else (host.kind, host.damper.mass_kg)]
    elif view == "bar":
        used = [s.preset]
    elif view == "response":
        used = [s.preset, s.integrator, s.force_n]
    else:
        used = [s]
    return json.dumps([data, repr(used)], sort_keys=True)
