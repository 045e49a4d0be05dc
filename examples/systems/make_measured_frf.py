"""Write examples/systems/measured_tip_frf.csv: a synthetic "measured" tip FRF.

A known two-mode bar (the modes below), its tip receptance at 1 Hz lines from
50 Hz to 4 kHz, times (1 + n) with n complex Gaussian noise of 1 % RMS
(seed 7): the scatter of a good averaged tap test.  Rerun it to get the same
file: `python examples/systems/make_measured_frf.py`.
"""

from pathlib import Path

import numpy as np

from boringbar.io import atomic_path
from boringbar.model.measured_frf import MeasuredFrf, frf_csv_text
from boringbar.model.modal_fit import ModalFit

#: The known modes: frequency (Hz), damping ratio, stiffness referred to the tip (N/m).
MODES = ModalFit(frequency_hz=(480.0, 2350.0), damping_ratio=(0.02, 0.03),
                 modal_stiffness_n_m=(2.2e6, 6.0e7))
NOISE = 0.01
SEED = 7


def measured() -> MeasuredFrf:
    f = np.arange(50.0, 4000.0 + 0.5, 1.0)
    rng = np.random.default_rng(SEED)
    noise = (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / np.sqrt(2)
    return MeasuredFrf(f, MODES.tip_frf(f) * (1 + NOISE * noise),
                       {"file": "measured_tip_frf.csv", "format": "csv"})


if __name__ == "__main__":
    path = Path(__file__).with_name("measured_tip_frf.csv")
    header = (f"synthetic tip receptance W/F (m/N): modes f = {MODES.frequency_hz} Hz, "
              f"zeta = {MODES.damping_ratio}, k = {MODES.modal_stiffness_n_m} N/m;\n"
              f"{NOISE:.0%} complex Gaussian noise, seed {SEED} "
              "(examples/systems/make_measured_frf.py)")
    with atomic_path(path) as tmp:
        tmp.write_text(frf_csv_text(measured(), header))
    print(f"wrote {path}")
