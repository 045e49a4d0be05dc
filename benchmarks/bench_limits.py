"""The analytic chatter limit at many speeds (``reference/stability.limit_at_speeds``):
its crossing search against the one-speed-at-a-time search it replaced, in one process.

    .venv/bin/python benchmarks/bench_limits.py [--repeat 5]

For the published bar's solid, ball (its bare host) and TMD bars under both presets,
at the design page's 300 speeds (lobes 1-5 down to 900 rpm, evenly in 1/rpm) and at
the published study's 15 (900..1600 rpm): the limits of both searches compared bit for
bit, and the best-of-``repeat`` wall time of each with their ratio.  The baseline
(``one_speed_at_a_time``) is the earlier search kept here: every speed's crossings
found on the whole frequency grid, its contenders kept, then one bisection for all.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from boringbar.analysis.lobes import PUBLISHED_RPM
from boringbar.app.design_state import Design
from boringbar.app.views import lobe_speeds
from boringbar.model.system import make_system
from boringbar.reference import stability as S
from boringbar.reference.linear import tip_frf


def one_speed_at_a_time(system, rpm, kr=S.KR_ALUMINIUM, n_freq=20000):
    """The earlier search: a loop over the speeds, each over every grid step."""
    bar, tmd, added = S.linear_host(system, None, 0.0)
    flat = np.asarray(rpm, dtype=float).ravel()
    w = S._frequency_grid(bar, tmd, added, n_freq, None)
    g = tip_frf(bar, w, tmd=tmd, added_mass_kg=added)
    eps = S.regeneration_phase(g)
    brackets = [_contenders(w, g, *_crossings(w, g, eps, 60.0 / s)) for s in flat]
    count = [len(b[2]) for b in brackets]
    owner = np.repeat(np.arange(len(flat)), count)
    out = np.full(flat.shape, np.inf)
    if owner.size:
        lo, hi, j = (np.concatenate([b[k] for b in brackets]) for k in range(3))
        root = S._bisect(bar, tmd, added, lo, hi, j, np.repeat(60.0 / flat, count))
        re = tip_frf(bar, root, tmd=tmd, added_mass_kg=added).real
        b = np.where(re < 0.0, -0.5 / (kr * np.minimum(re, -1e-300)), np.inf)
        for k in np.unique(owner):
            mine = np.flatnonzero(owner == k)
            out[k] = b[mine[int(np.argmin(b[mine]))]]
    return out


def _crossings(w, g, eps, tau):
    h = (w * tau - eps) / S.TWO_PI
    inside = (g.real[:-1] < 0.0) & (g.real[1:] < 0.0)
    top = np.floor(np.maximum(h[:-1], h[1:]))
    bottom = np.floor(np.minimum(h[:-1], h[1:]))
    count = np.where(inside, top - bottom, 0).astype(int)
    idx = np.repeat(np.arange(len(count)), count)
    offset = np.arange(len(idx)) - np.repeat(np.cumsum(count) - count, count)
    j = bottom[idx] + 1 + offset
    keep = j >= 0
    return w[idx[keep]], w[idx[keep] + 1], j[keep]


def _contenders(w, g, lo, hi, j):
    if len(j) < 2:
        return lo, hi, j
    a = np.searchsorted(w, lo)
    ends = np.stack([g.real[a], g.real[a + 1]])
    keep = ends.min(axis=0) <= (1.0 - S.CONTENDER_MARGIN) * ends.max(axis=0).min()
    return lo[keep], hi[keep], j[keep]


def best_of(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    page = lobe_speeds(Design.of(make_system("ball", "physical").spec))
    total = {"new": 0.0, "old": 0.0}
    for preset in ("physical", "paper"):
        for kind in ("solid", "ball", "tmd"):
            host = make_system(kind, preset).linear_host()
            for label, rpm in (("page, 300 speeds", page), ("published, 15", PUBLISHED_RPM)):
                rpm = np.asarray(rpm, dtype=float)
                same = np.array_equal(S.limit_at_speeds(host, rpm),
                                      one_speed_at_a_time(host, rpm))
                new = best_of(lambda h=host, r=rpm: S.limit_at_speeds(h, r), args.repeat)
                old = best_of(lambda h=host, r=rpm: one_speed_at_a_time(h, r), args.repeat)
                total["new"] += new
                total["old"] += old
                print(f"{preset:9s} {kind:6s} {label:17s} one at a time {old * 1e3:7.1f} ms"
                      f"  now {new * 1e3:6.1f} ms  ({old / new:4.1f}x)  "
                      f"{'bit-identical' if same else 'DIFFERENT'}")
    print(f"all cases: one at a time {total['old']:.3f} s, now {total['new']:.3f} s "
          f"({total['old'] / total['new']:.1f}x)")


if __name__ == "__main__":
    main()
