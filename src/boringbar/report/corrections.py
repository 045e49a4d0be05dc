"""What each correction to the published equations (docs/model.md, section 8)
changes, measured.

The ``paper`` preset reruns the study with three published readings
(docs/model.md, section 2): the friction force as computed in the paper
(20.4 N), the bar reaction as printed (+psi_d F_b) and the stiffness
calibrated to the published frequencies; it also keeps one mode and the
published absorber.  The ``physical`` preset drops all of them.  Three
measurements show, from data, what lies between the two:

- :func:`readings_ladder`: the same harmonic run (ball damper, friction
  on) with the published readings dropped one at a time, from ``paper`` to
  ``physical``: tip RMS, impact pattern, the work the printed reaction
  injects, the host frequency and the analytic chatter-free depth of the
  host bar.
- :func:`impact_law_check`: the impact law with the sign of the bar's jump
  as printed and as corrected, applied to the real impacts of a run: the
  momentum (M / psi_d) u' + m u_d' that an impact must conserve, and the
  kinetic energy it must not create.
- :func:`absorber_designs`: the published absorber, Den Hartog's and Sims'
  at z_a = 96 mm: mass ratio, tuning, peak tip receptance and the analytic
  minimum chatter-free depth.
"""

from __future__ import annotations

import math

import numpy as np

from boringbar.model.bar import published_bar
from boringbar.model.dampers import TunedMassDamper, absorber_mass_ratio, sims_tuning
from boringbar.model.forcing import Harmonic
from boringbar.model.system import System, make_system
from boringbar.reference.linear import tip_frf
from boringbar.reference.stability import KR_ALUMINIUM, min_limit
from boringbar.simulate import simulate
from boringbar.version import __version__

#: The rungs of :func:`readings_ladder`, from the paper preset to the physical one.
LADDER = (
    ("paper", "paper preset: 20.4 N friction, printed reaction, calibrated K, 1 mode"),
    ("reciprocal", "reaction corrected to -psi_d F_b (action = reaction)"),
    ("rolling", "friction from the rolling-resistance length: 0.0204 N"),
    ("fe-stiffness", "stiffness from the FE model (no calibration)"),
    ("physical", "2 modes: the physical preset"),
)


def ladder_system(rung: str, gap: float, restitution: float = 0.7) -> System:
    """The ball-damper System of one rung of :data:`LADDER` (friction on)."""
    physical_friction = make_system("ball", "physical", gap_m=gap).damper.friction_force_n
    common = dict(gap_m=gap, friction=True, restitution=restitution)
    if rung == "paper":
        return make_system("ball", "paper", **common)
    if rung == "reciprocal":
        return make_system("ball", "paper", friction_reaction="reciprocal", **common)
    if rung == "rolling":
        return make_system("ball", "paper", friction_reaction="reciprocal",
                           friction_force_n=physical_friction, **common)
    if rung == "fe-stiffness":
        return make_system("ball", "paper", friction_reaction="reciprocal",
                           friction_force_n=physical_friction,
                           modal=published_bar(cavity=True, n_modes=1), **common)
    if rung == "physical":
        return make_system("ball", "physical", **common)
    raise ValueError(f"rung = {rung!r} must be one of {[r for r, _ in LADDER]}")


def readings_ladder(gaps=(0.5e-3, 0.1e-3), force: float = 10.0, ratio: float = 1.0, *,
                    duration: float = 2.0, dt: float = 1e-6):
    """Harmonic runs with the published readings dropped one at a time.

    Returns an xarray Dataset over (rung, gap): tip RMS (m), pattern,
    impacts per cycle, friction force (N), the work injected by a
    non-reciprocal reaction as a fraction of the work of the force, the
    host's first natural frequency (Hz) and the analytic minimum
    chatter-free depth of the bare host bar (m, the ball not touching).
    """
    import xarray as xr

    rungs = [r for r, _ in LADDER]
    shape = (len(rungs), len(gaps))
    rms = np.full(shape, np.nan)
    per_cycle = np.full(shape, np.nan)
    injected = np.full(shape, np.nan)
    friction = np.full(shape, np.nan)
    pattern = np.full(shape, "", dtype=object)
    f1 = np.full(len(rungs), np.nan)
    depth = np.full(len(rungs), np.nan)
    for i, rung in enumerate(rungs):
        for j, gap in enumerate(gaps):
            system = ladder_system(rung, gap)
            run = simulate(system, Harmonic(force, ratio), duration_s=duration, dt_s=dt,
                           record_every=0)
            rms[i, j] = run.rms_tip_m
            pattern[i, j] = run.pattern.name if run.pattern else ""
            per_cycle[i, j] = (run.pattern.impacts_per_cycle if run.pattern else math.nan)
            w = run.energy["work_force_j"]
            injected[i, j] = run.energy["work_nonreciprocal_friction_j"] / w if w else 0.0
            friction[i, j] = system.damper.friction_force_n
        f1[i] = system.reference_frequency_rad_s / (2 * math.pi)
        depth[i] = min_limit(system.linear_host(), KR_ALUMINIUM)
    dims = ("rung", "gap_m")
    return xr.Dataset(
        {
            "rms_tip_m": (dims, rms, {"units": "m"}),
            "pattern": (dims, pattern.astype(str)),
            "impacts_per_cycle": (dims, per_cycle, {"units": "1/period"}),
            "friction_force_n": (dims, friction, {"units": "N"}),
            "nonreciprocal_work_fraction": (dims, injected, {
                "long_name": "work injected by the printed reaction / work of the force"}),
            "host_frequency_hz": ("rung", f1, {"units": "Hz"}),
            "host_min_depth_m": ("rung", depth, {
                "units": "m", "long_name": "analytic minimum chatter-free depth of the bare "
                                           "host bar (ball not touching)"}),
        },
        coords={"rung": rungs, "gap_m": ("gap_m", np.asarray(gaps, float), {"units": "m"}),
                "description": ("rung", [d for _, d in LADDER])},
        attrs={"title": "boringbar: the published readings dropped one at a time",
               "boringbar_version": __version__, "force_n": force, "ratio": ratio,
               "duration_s": duration, "dt_s": dt, "integrator": "rk4"},
    )


def impact_law_check(system: System, force: float = 10.0, ratio: float = 1.0, *,
                     duration: float = 0.2, dt: float = 1e-6) -> dict:
    """The printed and the corrected impact law applied to the impacts of one run.

    The run (one mode, as published) records every step; at each counted
    impact the pre-impact modal velocity u'- and relative ball velocity y'-
    are read back, and both laws are applied:

        corrected: u'+ = u'- + (1 + e) mu psi_d y'- / (1 + mu psi_d^2)
        printed:   u'+ = u'- - (1 + e) mu psi_d y'- / (1 + mu psi_d^2)

    (y'+ = -e y'- in both).  Returned: the largest momentum change
    |Delta((M / psi_d) u' + m u_d')| relative to m |y'-| under each law, and
    the number of impacts whose kinetic energy rises under each.
    """
    bar = system.bar
    if bar.n_modes != 1:
        raise ValueError("impact_law_check needs a one-mode system (as published)")
    d = system.damper
    run = simulate(system, Harmonic(force, ratio), duration_s=duration, dt_s=dt, record_every=1,
                   steady_fraction=1.0)
    h = run.history
    big_m, psi_d, psi_l = bar.mass_kg[0], bar.psi_damper[0], bar.psi_tip[0]
    m, e = d.mass_kg, d.restitution
    mu = m / big_m
    n_imp = len(run.impacts)
    momentum = {"corrected": 0.0, "printed": 0.0}
    gains = {"corrected": 0, "printed": 0}
    largest_gain = {"corrected": 0.0, "printed": 0.0}
    for t, _wall, v_minus in run.impacts:
        k = int(round((t - run.t0_s) / dt)) - 1  # the recorded row before the impact step
        k = min(max(k, 0), len(h) - 1)
        du = h[k, 2] / psi_l  # modal velocity u'
        ball = v_minus + psi_d * du  # absolute ball velocity u_d'
        for law, sign in (("corrected", 1.0), ("printed", -1.0)):
            jump = sign * (1 + e) * mu * psi_d * v_minus / (1 + mu * psi_d**2)
            du_plus = du + jump
            ball_plus = -e * v_minus + psi_d * du_plus
            p0 = big_m / psi_d * du + m * ball
            p1 = big_m / psi_d * du_plus + m * ball_plus
            momentum[law] = max(momentum[law], abs(p1 - p0) / (m * abs(v_minus)))
            e0 = 0.5 * big_m * du**2 + 0.5 * m * ball**2
            e1 = 0.5 * big_m * du_plus**2 + 0.5 * m * ball_plus**2
            if e1 > e0:
                gains[law] += 1
                largest_gain[law] = max(largest_gain[law], (e1 - e0) / e0)
    return {"impacts": n_imp, "duration_s": duration, "force_n": force, "ratio": ratio,
            "momentum_change_max": momentum, "impacts_gaining_energy": gains,
            "largest_relative_energy_gain": largest_gain}


def absorber_designs(preset: str = "physical", mass: float = 0.39) -> list[dict]:
    """The published absorber, Den Hartog's and Sims' on the solid bar of ``preset``
    (one mode for ``paper``, two for ``physical``), at z_a = 96 mm."""
    host = make_system("solid", preset).bar
    designs = {
        "published": TunedMassDamper.published(position_m=host.z_absorber_m),
        "den-hartog": TunedMassDamper.den_hartog(mass, host),
        "sims": sims_tuning(mass, host),
    }
    wn = host.natural_frequency_rad_s
    w = wn * np.linspace(0.5, 1.6, 22001)
    rows = []
    for name, tmd in designs.items():
        g = tip_frf(host, w, tmd=tmd)
        rows.append({
            "design": name,
            "mass_kg": tmd.mass_kg,
            "stiffness_n_m": tmd.stiffness_n_m,
            "damping_n_s_m": tmd.damping_n_s_m,
            "mass_ratio": absorber_mass_ratio(tmd.mass_kg, host),
            "tuning_ratio": math.sqrt(tmd.stiffness_n_m / tmd.mass_kg) / wn,
            "peak_receptance_m_n": float(np.max(np.abs(g))),
            "min_depth_m": min_limit(System(host, tmd, preset, ()), KR_ALUMINIUM),
        })
    rows.append({"design": "none (solid bar)", "mass_kg": 0.0, "stiffness_n_m": 0.0,
                 "damping_n_s_m": 0.0, "mass_ratio": 0.0, "tuning_ratio": math.nan,
                 "peak_receptance_m_n": float(np.max(np.abs(tip_frf(host, w)))),
                 "min_depth_m": min_limit(System(host, None, preset, ()), KR_ALUMINIUM)})
    return rows
