"""The validation gallery's figures (docs/validation.md): published results against ours.

1. Altintas' two-mode oriented example (Manufacturing Automation, 2nd ed., 2012, p. 131):
   our closed-form lobes, our simulated limits (the converged verdict) at five speeds,
   and the lobe bottoms of his formula, with the depth his lab's published figure shows.
2. Hunt and Crossley (1975): the restitution of a damped Hertz impact against its
   damping alpha = chi v_in, ours (the core's integration) against their small-damping
   law e = 1 - 2/3 alpha and the later closed forms of Lankarani and Nikravesh (1990,
   alpha = 3/4 (1 - e^2)) and Flores et al. (2011, alpha = 8/5 (1 - e) / e).
3. Masri and Caughey (1966): their closed-form symmetric two-impact orbit (RMS tip and
   impact speed) over the frequency ratio and the force, stable and unstable by our
   shooting's Floquet multipliers, against our exact integrator's steady state started
   next to it.
4. Den Hartog (1956) and Sims (2007) on an undamped one-mode host: |G| with Den
   Hartog's tuning against his fixed points (height sqrt(1 + 2/mu)), Re G with Sims'
   tuning against the numerical minimax's optimum.

    .venv/bin/python benchmarks/validation_figures.py [--out docs/img]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_linear import absorber_mass_for, local_extrema, tap_bar  # noqa: E402
from test_masri_caughey import (  # noqa: E402
    closed_form,
    gallery_system,
    impact_speed,
    settle,
    shooting_multiplier,
)
from test_oriented import altintas  # noqa: E402

from boringbar.analysis.lobes import LobesOptions, lobes  # noqa: E402
from boringbar.model.dampers import (  # noqa: E402
    TunedMassDamper,
    den_hartog_parameters,
    sims_parameters,
    sims_tuning,
)
from boringbar.reference.linear import (  # noqa: E402
    min_real_part,
    minimax_real_tuning,
    static_tip_compliance,
    tip_frf,
)
from boringbar.reference.stability import analytic_lobes, min_limit  # noqa: E402
from boringbar.simulate.kernels import hunt_crossley_restitution  # noqa: E402

KF = 1e9  # Pa, Altintas' Kf = 1000 MPa
SPEEDS = (4049.0, 5521.0, 7000.0, 8678.0, 11849.0)
#: his formula's lobe bottoms (rpm) and the absolute limit his lab's figure shows (m)
PUBLISHED_BOTTOMS = (8678.0, 5521.0, 4049.0)
PUBLISHED_LIMIT = 7.2e-3
#: Masri-Caughey: the ratio swept at MC_FORCE, the force swept at ratio 1
MC_FORCE = 30.0
MC_RATIOS = np.linspace(0.81, 1.19, 153)
MC_FORCES = np.linspace(12.0, 60.0, 97)
#: Den Hartog and Sims: the absorber's mass ratio on the undamped one-mode host
MU = 0.25


def altintas_figure(path: Path) -> None:
    system = altintas()
    lob = analytic_lobes(system, KF, lobes=range(0, 12))
    ds = lobes({"altintas": system}, LobesOptions(rpm=SPEEDS, kr_pa=KF, max_depth_m=0.1))
    sim = ds["limit_depth_m"].values[0]
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for j in range(len(lob["lobe"])):
        ax.plot(lob["rpm"][j], lob["b_lim"][j] * 1e3, color="C0", lw=1,
                label="ours, closed form" if j == 0 else None)
    ax.plot(SPEEDS, sim * 1e3, "o", color="C3", label="ours, simulated (converged verdict)")
    ax.plot(PUBLISHED_BOTTOMS, [PUBLISHED_LIMIT * 1e3] * 3, "kx", ms=9,
            label="Altintas: his formula's lobe bottoms, the depth his lab's figure shows")
    ax.axhline(min_limit(system, KF) * 1e3, color="C0", ls=":", lw=1)
    ax.set(xlim=(2000, 15000), ylim=(0, 60), xlabel="spindle speed (rpm)",
           ylabel="depth of cut (mm)",
           title="Altintas (2012), p. 131: two modes at 30 and -45 degrees, Kf = 1000 MPa")
    ax.legend(fontsize=8, loc="center right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}: absolute limit {min_limit(system, KF) * 1e3:.4f} mm; simulated "
          f"against closed form at {SPEEDS}: "
          + " ".join(f"{e:+.3%}" for e in sim / ds["host_analytic_limit_m"].values[0] - 1))


def hunt_crossley_figure(path: Path) -> None:
    alpha = np.geomspace(1e-3, 30, 60)
    e = np.array([hunt_crossley_restitution(a) for a in alpha])
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    ax.semilogx(alpha, e, "o", ms=4, label="ours (the core's integration)")
    ax.semilogx(alpha, np.clip(1 - 2 / 3 * alpha, 0, 1), "k:",
                label="Hunt & Crossley: e = 1 - 2/3 alpha (small damping)")
    ee = np.linspace(0.05, 1.0, 200)
    ax.semilogx(0.75 * (1 - ee**2), ee, "C1--", label="Lankarani & Nikravesh: 3/4 (1 - e^2)")
    ax.semilogx(1.6 * (1 - ee) / ee, ee, "C2-.", label="Flores et al.: 8/5 (1 - e) / e")
    ax.set(xlabel="alpha = chi v_in", ylabel="restitution e", ylim=(0, 1.02),
           title="a damped Hertz impact: restitution against damping")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def _branches(system, values, which: str) -> list:
    """Their admissible orbits at each value, sorted into two branches by the phase of the
    + wall impact (nearest to the branch's last): rows (value, branch, orbit, force, ratio)."""
    rows, last = [], [None, None]
    for v in values:
        force, ratio = (MC_FORCE, v) if which == "ratio" else (v, 1.0)
        for o in closed_form(system, force, ratio):
            gaps = [np.inf if p is None else abs(np.angle(np.exp(1j * (o.phase - p))))
                    for p in last]
            b = int(np.argmin(gaps)) if min(gaps) < 0.5 else last.index(None) if None in last \
                else int(np.argmin(gaps))
            last[b] = o.phase
            rows.append((v, b, o, force, ratio))
    return rows


def masri_caughey_points(system, values, which: str, every: int) -> dict:
    """Theirs (closed form, with our shooting's largest |multiplier|) on a branch each, and
    ours (the exact integrator's steady state started next to their orbit) at every
    ``every``-th value."""
    out = {k: [] for k in ("value", "branch", "rms", "speed", "mult", "ours")}
    for v, b, o, force, ratio in _branches(system, values, which):
        out["value"].append(v)
        out["branch"].append(b)
        out["rms"].append(o.rms_tip())
        out["speed"].append(impact_speed(o))
        out["mult"].append(shooting_multiplier(system, o, force, ratio))
        if np.isclose(values, v).nonzero()[0][0] % every == 0:
            run, rms, speed = settle(system, o, force, ratio)
            out["ours"].append((v, rms, speed, o.rms_tip(), run.pattern.name))
    return {k: np.array(x, dtype=object if k == "ours" else float) for k, x in out.items()}


def _theirs(ax, p, key, scale):
    """Their branches, solid where stable, dashed where unstable (our shooting)."""
    for b in (0, 1):
        on = p["branch"] == b
        x, y, stable = p["value"][on], p[key][on] * scale, p["mult"][on] < 1.0
        # where the branch has no orbit the line breaks, not bridges the gap
        cut = np.flatnonzero(np.diff(x) > 1.5 * np.min(np.diff(np.unique(p["value"]))))
        x, y = np.insert(x, cut + 1, np.nan), np.insert(y, cut + 1, np.nan)
        stable = np.insert(stable, cut + 1, False)
        # a stretch's end point joins both styles, so that no gap opens where they meet
        joined = stable | np.r_[stable[1:], False] | np.r_[False, stable[:-1]]
        ax.plot(x, np.where(joined, y, np.nan), "k-", lw=1.2,
                label="Masri & Caughey, stable" if b == 0 else None)
        ax.plot(x, np.where(stable, np.nan, y), "k--", lw=0.9,
                label="Masri & Caughey, unstable" if b == 0 else None)


def _ours(ax, ours, col, scale):
    x = ours[:, 0].astype(float)
    y = ours[:, col].astype(float) * scale
    on = np.abs(ours[:, 1].astype(float) / ours[:, 3].astype(float) - 1) < 1e-6
    ax.plot(x[on], y[on], "o", color="C0", ms=6, mfc="none",
            label="ours (exact integrator): on their orbit")
    ax.plot(x[~on], y[~on], "s", color="C3", ms=4,
            label="ours: left it for another attractor")


def masri_caughey_figure(path: Path) -> None:
    system = gallery_system()
    cols = [("ratio", MC_RATIOS, 4, f"frequency ratio Omega / omega_n (F0 = {MC_FORCE:g} N)"),
            ("force", MC_FORCES, 4, "force amplitude F0 (N), Omega = omega_n")]
    fig, axes = plt.subplots(2, 2, figsize=(10, 6.6), sharex="col")
    for j, (which, values, every, xlabel) in enumerate(cols):
        p = masri_caughey_points(system, values, which, every)
        ours = np.array(p["ours"].tolist(), dtype=object)
        for i, (key, col, scale, ylabel) in enumerate((
                ("rms", 1, 1e6, "RMS tip displacement (um)"),
                ("speed", 2, 1.0, "impact speed |y'-| (m/s)"))):
            _theirs(axes[i, j], p, key, scale)
            _ours(axes[i, j], ours, col, scale)
            axes[i, j].set(ylabel=ylabel)
        axes[1, j].set(xlabel=xlabel)
        _print_masri_caughey(which, p, ours)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8)
    fig.suptitle("Masri & Caughey (1966): the symmetric two-impact orbit; one-mode bar, "
                 "frictionless ball, gap 0.5 mm, e = 0.7", fontsize=10)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def _print_masri_caughey(which, p, ours) -> None:
    err = ours[:, 1].astype(float) / ours[:, 3].astype(float) - 1
    on = np.abs(err) < 1e-6
    stable = p["value"][p["mult"] < 1]
    print(f"{which}: their orbits stable (our shooting) at {np.round(stable, 4)}; ours on "
          f"theirs at {ours[on, 0]} (largest RMS error {np.max(np.abs(err[on])):.1e}); "
          f"left at {ours[~on, 0]} for {ours[~on, 4]}")


def den_hartog_fixed_points(mu: float) -> np.ndarray:
    """His fixed points' frequencies (/ omega_n) under his tuning f = 1 / (1 + mu)."""
    root = np.sqrt(mu / (2 + mu))
    return np.sqrt((1 + np.array([-root, root])) / (1 + mu))


def absorber_figure(path: Path) -> None:
    bar = tap_bar(zeta=0.0)
    m_a = absorber_mass_for(MU, bar)
    wn, g0 = bar.natural_frequency_rad_s, static_tip_compliance(bar)
    r = np.linspace(0.6, 1.5, 90_001)
    dh = TunedMassDamper.den_hartog(m_a, bar)
    sims = sims_tuning(m_a, bar)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4.2))
    for scale, ls in ((0.5, ":"), (2.0, "-.")):
        other = TunedMassDamper(m_a, dh.stiffness_n_m, scale * dh.damping_n_s_m, dh.position_m)
        a1.plot(r, np.abs(tip_frf(bar, r * wn, tmd=other)) / g0, color="0.6", ls=ls, lw=0.9,
                label=f"ours, his stiffness, {scale:g} x his damping")
    mag = np.abs(tip_frf(bar, r * wn, tmd=dh)) / g0
    a1.plot(r, mag, "C0", label="ours: |G| with Den Hartog's tuning")
    height, fixed = np.sqrt(1 + 2 / MU), den_hartog_fixed_points(MU)
    a1.axhline(height, color="k", lw=0.8, ls="--", label="Den Hartog: sqrt(1 + 2/mu)")
    a1.plot(fixed, [height] * 2, "kx", ms=9, mew=1.5, label="his fixed points")
    a1.set(xlabel="frequency ratio omega / omega_n", ylabel="|G| / static compliance (-)",
           ylim=(0, 2.6 * height), title=f"Den Hartog, mu = {MU:g}, undamped host")
    a1.legend(fontsize=7.5, loc="upper right")
    re_s = tip_frf(bar, r * wn, tmd=sims).real / g0
    a2.plot(r, tip_frf(bar, r * wn, tmd=dh).real / g0, color="0.6", lw=0.9,
            label="ours, Den Hartog's tuning")
    a2.plot(r, re_s, "C0", label="ours: Re G with Sims' tuning")
    best = min_real_part(bar, minimax_real_tuning(m_a, bar, start=dh, xatol=1e-9))[0] / g0
    a2.axhline(best, color="k", lw=0.8, ls="--", label="numerical minimax of max(-Re G)")
    troughs = local_extrema(re_s, "min")
    a2.plot(r[troughs], re_s[troughs], "kx", ms=9, mew=1.5, label="Sims' equal troughs")
    a2.set(xlabel="frequency ratio omega / omega_n", ylabel="Re G / static compliance (-)",
           ylim=(2.0 * best, -0.9 * best), title=f"Sims, mu = {MU:g}, undamped host")
    a2.legend(fontsize=7.5, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    _print_absorber(path, mag, r, height, fixed, re_s[troughs], best, m_a, bar)


def _print_absorber(path, mag, r, height, fixed, troughs, best, m_a, bar) -> None:
    peaks = mag[local_extrema(mag, "max")]
    print(f"wrote {path}: Den Hartog {den_hartog_parameters(m_a, bar)['frequency_ratio']:.6f}, "
          f"fixed points at {fixed} omega_n, height {height:.6f}; peaks {peaks} "
          f"({peaks / height - 1} above); Sims {sims_parameters(m_a, bar)}, troughs "
          f"{troughs}, the minimax's {best:.9f} (at r = {r[0]:g}..{r[-1]:g})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/img")
    ap.add_argument("--only-new", action="store_true",
                    help="only the Masri-Caughey and absorber figures")
    args = ap.parse_args()
    out = Path(args.out)
    if not args.only_new:
        altintas_figure(out / "validation_altintas.png")
        hunt_crossley_figure(out / "validation_hunt_crossley.png")
    masri_caughey_figure(out / "validation_masri_caughey.png")
    absorber_figure(out / "validation_absorbers.png")


if __name__ == "__main__":
    main()
