"""How far the stabilisation diagram's rule stands from what it separates, measured.

    .venv/bin/python benchmarks/stabilisation_margins.py [--draws 10] [--max-order 20]

A column of the diagram (analysis/frf_fit.py) is a mode when it is stable at a
third of the model orders or more. For synthetic tip FRFs of known modes (the
receptance of the modes at 1 Hz lines from 50 Hz to 4 kHz, times 1 + n, n
complex Gaussian noise of the stated RMS), and for noise alone, this prints over
``--draws`` noise draws: how often the diagram finds exactly the known modes (each
within 1 % of its frequency), the fewest orders at which a known mode's column is
stable, and the most at which any other column is (the estimator's surplus poles
and the noise). The rule works while the first stays above the threshold and the
second below it. Where the modes are found, it prints the fit's largest relative
errors in frequency, damping ratio and tip stiffness against the known modes.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from boringbar.analysis.frf_fit import STABLE, fit_modes, min_stable_orders, stabilisation
from boringbar.model.measured_frf import MeasuredFrf
from boringbar.model.modal_fit import ModalFit

CASES = {
    "two modes": ModalFit((500.0, 2300.0), (0.02, 0.03), (2.0e6, 5.0e7)),
    "three modes": ModalFit((480.0, 1500.0, 3100.0), (0.02, 0.015, 0.03),
                            (2.0e6, 1.0e7, 4.0e7)),
    "close modes, 8 % apart": ModalFit((500.0, 540.0), (0.02, 0.02), (2.0e6, 3.0e6)),
    "close modes, 4 % apart": ModalFit((500.0, 520.0), (0.02, 0.02), (2.0e6, 3.0e6)),
    "noise alone": None,
}
NOISE = (0.0, 0.01, 0.02)


def measured(known: ModalFit | None, noise: float, seed: int) -> MeasuredFrf:
    f = np.arange(50.0, 4000.0, 1.0)
    rng = np.random.default_rng(seed)
    n = (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / math.sqrt(2)
    h = 1e-7 * n if known is None else known.tip_frf(f) * (1 + noise * n)
    return MeasuredFrf(f, h)


def margins(known: ModalFit | None, noise: float, draws: int, max_order: int) -> dict:
    """Draws that find exactly the known modes, the known modes' fewest stable orders,
    any other column's most, and the fit's largest relative errors (f, zeta, k)."""
    out = {"right": 0, "fewest": math.inf, "most": 0, "errors": np.zeros(3)}
    truth = np.array(known.frequency_hz if known is not None else [])
    for seed in range(1, draws + 1):
        d = stabilisation(measured(known, noise, seed), max_order=max_order)
        found = np.array([m.frequency_hz for m in d.modes])
        out["fewest"] = min([out["fewest"]] + [m.stable_orders for m in d.modes])
        other = (d.status == STABLE) & (d.mode < 0)
        out["most"] = max([out["most"]] + np.bincount(d.column[other]).tolist())
        if len(found) != len(truth) or np.any(np.abs(found / truth - 1) >= 0.01):
            continue
        out["right"] += 1
        if known is not None:
            fit, _ = fit_modes(d)
            errors = [np.abs(np.divide(getattr(fit, k), getattr(known, k)) - 1).max()
                      for k in ("frequency_hz", "damping_ratio", "modal_stiffness_n_m")]
            out["errors"] = np.maximum(out["errors"], errors)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=10)
    parser.add_argument("--max-order", type=int, default=20)
    args = parser.parse_args()
    print(f"a mode: a column stable at {min_stable_orders(args.max_order)} or more of "
          f"{args.max_order} orders; {args.draws} noise draws each")
    print(f"{'case':<24} {'noise':>6} {'found':>6} {'modes: fewest':>14} "
          f"{'others: most':>13} {'f error':>8} {'zeta error':>11} {'k error':>8}")
    for name, known in CASES.items():
        for noise in NOISE if known is not None else (1.0,):
            m = margins(known, noise, args.draws, args.max_order)
            level, fewest = ("-", "-") if known is None else (f"{noise:.0%}", m["fewest"])
            errors = " ".join(f"{e:>{w}.2%}" if m["right"] and known else f"{'-':>{w}}"
                              for e, w in zip(m["errors"], (8, 11, 8), strict=True))
            print(f"{name:<24} {level:>6} {m['right']:>3}/{args.draws:<2} {fewest:>14} "
                  f"{m['most']:>13} {errors}", flush=True)

if __name__ == "__main__":
    main()
