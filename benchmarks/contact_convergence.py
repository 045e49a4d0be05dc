"""The Hertz contact against its truths, and what it costs (docs/model.md, section 2.6).

Left: one impact of the published carbide ball on its steel plug at 0.5 m/s, the contact
force against time for three restitutions, with Hertz's elastic closed form (Johnson):
F = K d^1.5, d(t) from m d'' = -K d^1.5.  Right: the ball's position after one impact
against the exact impact law's, as the contact's stiffness rises: the error falls as
K^-2/5, as the contact's duration does.  Then the cost: a Hertz run of the published
bar against the impact law's, both RK4 through bb.simulate, best of 3.

    .venv/bin/python benchmarks/contact_convergence.py [--out docs/img/hertz_contact.png]
"""

from __future__ import annotations

import argparse
import math
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

import boringbar as bb  # noqa: E402
from boringbar.model.bar import ModalModel  # noqa: E402
from boringbar.model.contact import hertz_contact_time_s  # noqa: E402
from boringbar.model.dampers import NO_FRICTION, ImpactDamper  # noqa: E402
from boringbar.model.system import System, make_system  # noqa: E402
from boringbar.simulate import Initial  # noqa: E402
from boringbar.simulate.kernels import hunt_crossley_alpha  # noqa: E402

GAP, SPEED = 0.5e-3, 0.5


def pair(e, bar, *, k=None, dt=1e-7, contact="hertz", integrator="rk4", record=0,
         duration=1.5e-3):
    ball = ImpactDamper.ball("carbide", gap_m=GAP, restitution=e, friction=NO_FRICTION,
                             contact=contact, contact_stiffness_n_m1_5=k)
    run = bb.simulate(System(bar, ball, "physical"), bb.Harmonic(amplitude_n=0.0),
                      duration_s=duration, dt_s=dt, initial=Initial(ball_velocity_m_s=SPEED),
                      steady_fraction=1.0, record_every=record, integrator=integrator)
    return run, ball


def force_history(e, bar):
    """t (us from the contact's start), F (N) of one impact, from the recorded y, y'."""
    run, ball = pair(e, bar, record=1, duration=7e-4)
    t, y, yd = run.history[:, 0], run.history[:, 3], run.history[:, 4]
    d = np.abs(y) - GAP / 2
    chi = hunt_crossley_alpha(e) / run.contacts[0, 2]
    f = np.where(d > 0, ball.hertz_stiffness_n_m1_5 * np.maximum(d, 0) ** 1.5
                 * np.maximum(0.0, 1 + chi * np.sign(y) * yd), 0.0)
    return (t - run.contacts[0, 0]) * 1e6, f, run.contacts[0]


def hertz_elastic(meff, k):
    """Hertz's elastic impact at SPEED: t (us), F (N)."""
    sol = solve_ivp(lambda _t, z: [z[1], -k / meff * max(z[0], 0) ** 1.5], (0, 2e-4),
                    [0.0, SPEED], max_step=1e-7, rtol=1e-10, atol=1e-15)
    keep = sol.y[0] >= 0
    return sol.t[keep] * 1e6, k * sol.y[0][keep] ** 1.5


def convergence(bar, scales):
    ref, ball = pair(0.7, bar, contact="impact", integrator="exact")
    meff = 1 / (1 / ball.mass_kg + float((bar.psi_damper**2 / bar.mass_kg).sum()))
    k0 = ball.hertz_stiffness_n_m1_5
    errors = []
    for s in scales:
        dt = 1.5e-3 / math.ceil(1.5e-3 / (hertz_contact_time_s(meff, k0 * s, SPEED) / 400))
        run, _ = pair(0.7, bar, k=k0 * s, dt=dt)
        errors.append(abs(run.final.x[2] - ref.final.x[2]))
    return k0 * np.array(scales), np.array(errors)


def cost():
    """Seconds of a 2 s harmonic run of the published ball bar, each law, best of 3."""
    out = {}
    for contact in ("impact", "hertz"):
        system = make_system("ball", gap_m=GAP, contact=contact)
        best = math.inf
        for _ in range(3):
            tic = time.perf_counter()
            bb.simulate(system, bb.Harmonic(amplitude_n=20.0), duration_s=2.0, record_every=0,
                        integrator="rk4")
            best = min(best, time.perf_counter() - tic)
        out[contact] = best
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/img/hertz_contact.png")
    args = ap.parse_args()
    free = ModalModel.from_tap_test(2.0, 0.0, tip_mass_kg=0.5)
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    for e, colour in ((1.0, "C0"), (0.7, "C1"), (0.4, "C2")):
        t, f, row = force_history(e, free)
        a.plot(t, f, color=colour, label=f"e = {e:g}: {row[3] * 1e6:.1f} us, "
                                         f"v_out/v_in = {row[5] / row[2]:.4f}")
    meff = 1 / (1 / 0.026 + 1 / 0.5)
    th, fh = hertz_elastic(meff, ImpactDamper.ball("carbide").hertz_stiffness_n_m1_5)
    a.plot(th, fh, "k:", lw=2, label="Hertz, elastic (closed form)")
    a.set(xlim=(-5, 90), xlabel="time from contact (us)", ylabel="contact force (N)",
          title="one impact at 0.5 m/s, carbide ball on a steel plug")
    a.legend(fontsize=8)
    bar = ModalModel.from_tap_test(500.0, 0.01, tip_stiffness_n_m=3e6, damper_ratio=0.6)
    scales = (1.0, 10.0, 100.0, 1000.0, 10000.0)
    ks, err = convergence(bar, scales)
    orders = np.log10(err[:-1] / err[1:])
    b.loglog(ks, err * 1e6, "o-", label="Hertz + Hunt-Crossley, e = 0.7")
    b.loglog(ks, err[0] * 1e6 * (ks / ks[0]) ** -0.4, "k:", label="K^-2/5")
    b.set(xlabel="contact stiffness K (N/m^1.5)", ylabel="|y - y_impact law| after it (um)",
          title="the impact law as the limit (one impact, 500 Hz bar)")
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")
    print("order of the error in K per decade:", " ".join(f"{o:.4f}" for o in orders))
    c = cost()
    print(f"2 s of the published ball bar at F0 = 20 N, RK4 through bb.simulate, best of 3: "
          f"impact law {c['impact']:.3f} s, Hertz {c['hertz']:.3f} s "
          f"({c['hertz'] / c['impact']:.2f}x)")


if __name__ == "__main__":
    main()
