"""The published RK4 scheme converging to the exact integrator's answer as dt shrinks.

    .venv/bin/python benchmarks/rk4_convergence.py [--out docs/img/rk4_convergence.png]

Periodic impacting orbits, each started on its attractor so that RK4 and the
exact integrator follow the same orbit:

- the Masri-Caughey symmetric two-impact orbit (1 mode, no friction, gap
  0.5 mm, 30 N at Omega = omega_n), started just after a + wall impact from
  the closed form (analysis/masri_caughey.py), 40 periods;
- the physical preset (2 modes), gap 0.1 mm, no friction, 20 N, r = 1.00
  (a symmetric two-impact orbit), started from the exact integrator's state
  after 2 s from rest, 40 periods.

For dt = 4e-6 ... 2.5e-7 s it prints and plots the relative error of the tip
RMS over the run and the largest impact-time error (impacts matched in
order), log-log, with a slope-1 guide.  Prints the observed orders.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from boringbar import Harmonic, State, make_system, simulate
from boringbar.reference.masri_caughey import two_impact_orbit

DTS = [4e-6, 2e-6, 1e-6, 5e-7, 2.5e-7]
N_PERIODS = 40


def masri_caughey_case():
    s = make_system("ball", "physical", n_modes=1, friction=False, gap_m=0.5e-3)
    bar, d = s.bar, s.damper
    om = s.reference_frequency_rad_s
    o = [o for o in two_impact_orbit(bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0],
                                     bar.psi_tip[0], bar.psi_damper[0], d.mass_kg, d.gap_m,
                                     d.restitution, 30.0, om) if o.admissible][0]
    t0 = o.impact_time
    x = np.array([float(o.modal_displacement(t0)), o.bar_velocity_after / bar.psi_damper[0],
                  d.gap_m / 2, -o.ball_speed - o.bar_velocity_after])
    return "Masri-Caughey orbit, 1 mode, 30 N", s, Harmonic(30.0, 1.0), State(x, t0), o


def settled_case():
    s = make_system("ball", "physical", gap_m=0.1e-3, friction=False)
    f = Harmonic(20.0, 1.0)
    settled = simulate(s, f, duration_s=2.0, integrator="exact")
    return "physical, 2 modes, gap 0.1 mm, 20 N", s, f, settled.final, None


def errors(label, s, f, start, orbit):
    period = 2 * math.pi / f.omega(s.reference_frequency_rad_s)
    dur = N_PERIODS * period
    ex = simulate(s, f, duration_s=dur, dt_s=period / 4000, initial=start, steady_fraction=1.0,
                  integrator="exact")
    if orbit is not None:
        print(f"{label}: exact rms {ex.rms_tip_m:.12e}, closed form {orbit.rms_tip():.12e} "
              f"(rel. diff {abs(ex.rms_tip_m / orbit.rms_tip() - 1):.1e})")
    rms_err, t_err = [], []
    for dt in DTS:
        run = simulate(s, f, duration_s=dur, dt_s=dt, initial=start, steady_fraction=1.0)
        m = min(len(run.impacts), len(ex.impacts)) - 1
        rms_err.append(abs(run.rms_tip_m - ex.rms_tip_m) / ex.rms_tip_m)
        t_err.append(float(np.max(np.abs(run.impacts[:m, 0] - ex.impacts[:m, 0]))))
        print(f"  dt {dt:.2e}: rms error {rms_err[-1]:.3e}, impact-time error "
              f"{t_err[-1]:.3e} s ({len(run.impacts)} vs {len(ex.impacts)} impacts)")
    for name, e in (("rms", rms_err), ("impact time", t_err)):
        order = np.polyfit(np.log(DTS), np.log(e), 1)[0]
        print(f"  observed order ({name}): {order:.2f}")
    return rms_err, t_err


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/img/rk4_convergence.png")
    args = ap.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    for case in (masri_caughey_case(), settled_case()):
        label = case[0]
        rms_err, t_err = errors(*case)
        axes[0].loglog(DTS, rms_err, "o-", label=label)
        axes[1].loglog(DTS, t_err, "o-", label=label)
    dts = np.array(DTS)
    whats = ("relative error of the tip RMS", "largest impact-time error (s)")
    for ax, what in zip(axes, whats, strict=True):
        ref = ax.get_lines()[0].get_ydata()[0]
        ax.loglog(dts, ref * dts / dts[0], "k--", lw=0.8, label="slope 1")
        ax.set_xlabel("RK4 time step dt (s)")
        ax.set_ylabel(what)
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Published RK4 scheme against the exact event-driven integrator "
                 f"({N_PERIODS} periods on the orbit)")
    fig.tight_layout()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
