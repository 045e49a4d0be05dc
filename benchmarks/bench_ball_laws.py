"""What the ball's laws and a second bending plane cost through bb.simulate, side by side
in one process.

The ball bar (physical preset, gap 0.5 mm, friction on), 2 s of RK4 at dt = 1e-6 s, CPU
time, best of ``--repeat`` taken round robin (so that the machine's drifts in speed fall
on every variant alike), each with its ratio to the first of its group:

- the ball's laws, 2 modes: the sliding ball and the impact law (the published model), a
  Hertz contact (docs/model.md, section 2.6) and a rolling ball (section 2.7), at
  F0 = 20 N and Omega = omega_n (the ball rattles, and a rolling one slips), at
  F0 = 0.05 N (a rolling ball rolls and slips in turn) and in a cut at 1200 rpm and
  0.2 mm;
- planes (section 4.7): one plane and two (Kt / Kr = 2.5, lead angle 30 degrees), with
  1 and 2 modes a plane, at F0 = 20 N, with RK4 and with the exact integrator;
- the exact integrator's sliding and rolling ball (docs/exact.md, "A rolling ball") at
  F0 = 20 N, 2 N (a rolling ball rolls and slips each half period), 0.05 N and in the
  cut, each call
  timed five times a round (a call takes milliseconds), with the run's events (impacts,
  sticks and slips, a rolling ball's roll/slip switches) and the time per event.

    .venv/bin/python benchmarks/bench_ball_laws.py [--repeat 7]
"""

from __future__ import annotations

import argparse
import math
import time

from machine import describe

import boringbar as bb
from boringbar.model.oriented import CutGeometry

LAWS = {"slide, impact law": {}, "slide, Hertz contact": {"contact": "hertz"},
        "roll, impact law": {"motion": "roll"}}
LOADS = {"F0 = 20 N": bb.Harmonic(amplitude_n=20.0),
         "F0 = 0.05 N": bb.Harmonic(amplitude_n=0.05),
         "cut, 0.2 mm": bb.Regenerative(depth_m=2e-4, rpm=1200.0)}
EXACT_LOADS = {"exact, F0 = 20 N": bb.Harmonic(amplitude_n=20.0),
               "exact, F0 = 2 N": bb.Harmonic(amplitude_n=2.0),
               "exact, F0 = 0.05 N": bb.Harmonic(amplitude_n=0.05),
               "exact, cut, 0.2 mm": LOADS["cut, 0.2 mm"]}
EXACT_CALLS = 5  # an exact call's timings a round
TWO_PLANES = {"planes": 2, "cut_geometry": CutGeometry(force_ratio=2.5, lead_angle_deg=30.0)}


def cases() -> dict:
    """(group, variant) -> (system, forcing, integrator)."""
    out = {}
    for load, forcing in LOADS.items():
        for law, kw in LAWS.items():
            out[load, law] = (bb.make_system("ball", **kw), forcing, "rk4")
    for integrator, group in (("rk4", "{} mode(s) a plane"),
                              ("exact", "exact, {} mode(s) a plane")):
        for n in (1, 2):
            for planes, kw in (("one plane", {}), ("two planes", TWO_PLANES)):
                out[group.format(n), planes] = (bb.make_system("ball", n_modes=n, **kw),
                                                LOADS["F0 = 20 N"], integrator)
    for load, forcing in EXACT_LOADS.items():
        for law in ("slide", "roll"):
            out[load, law + ", impact law"] = (bb.make_system("ball", motion=law), forcing,
                                               "exact")
    return out


def run_once(system, forcing, integrator: str, duration_s: float = 2.0) -> tuple[float, int]:
    """(CPU seconds, the run's events: the exact integrator's count, else 0)."""
    tic = time.process_time()
    run = bb.simulate(system, forcing, duration_s=duration_s, record_every=0,
                      integrator=integrator)
    return time.process_time() - tic, run.metrics["events"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    print(f"machine: {describe()}")
    runs = cases()
    for system, forcing, integrator in runs.values():  # warm: the first call loads
        run_once(system, forcing, integrator, 0.01)
    times, events = dict.fromkeys(runs, math.inf), dict.fromkeys(runs, 0)
    for _ in range(args.repeat):
        for key, (system, forcing, integrator) in runs.items():
            for _ in range(EXACT_CALLS if integrator == "exact" else 1):
                t, events[key] = run_once(system, forcing, integrator)
                times[key] = min(times[key], t)
    base = {}
    for (group, variant), t in times.items():
        if group not in base:
            base[group] = (t, events[group, variant])
            print(group)
        line = f"  {variant:22s} {t:.4f} s  ({t / base[group][0]:.2f}x)"
        if events[group, variant]:  # the exact integrator's cost follows its events
            e0, e = base[group][1], events[group, variant]
            line += (f"  {e} events ({e / e0:.2f}x), {t / e * 1e6:.2f} us an event "
                     f"({t / e / (base[group][0] / e0):.2f}x)")
        print(line)


if __name__ == "__main__":
    main()
