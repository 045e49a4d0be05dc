"""The modal-fit file: the receptance it describes, and the ModalModel it becomes."""

import json
import math

import numpy as np
import pytest

from boringbar import ParameterError
from boringbar.model.modal_fit import ModalFit


def test_modal_model_has_the_fits_receptance():
    fit = ModalFit((450.0, 2900.0), (0.01, 0.02), (2.0e6, 4.0e7))
    model = fit.to_modal_model(damper_ratio=(0.9, 0.4))
    f = np.linspace(100.0, 3500.0, 57)
    # closed form: sum of single-mode receptances, written out independently
    w = 2 * math.pi * f
    direct = sum(1.0 / (k - m * w**2 + 1j * c * w)
                 for k, m, c in zip(model.stiffness_n_m, model.mass_kg, model.damping_n_s_m,
                                    strict=True))
    np.testing.assert_allclose(fit.tip_frf(f), direct, rtol=1e-12)
    np.testing.assert_allclose(model.omegas_rad_s / (2 * math.pi), (450.0, 2900.0), rtol=1e-12)
    assert model.psi_damper.tolist() == [0.9, 0.4]


def test_file_round_trip(tmp_path):
    fit = ModalFit((450.0,), (0.012,), (2.5e6,), source={"file": "x.csv"})
    p = tmp_path / "fit.json"
    p.write_text(json.dumps(fit.to_dict()))
    back = ModalFit.read(p)
    assert back.to_dict() == fit.to_dict()


@pytest.mark.parametrize("data, word", [
    ({"format": "other"}, "format"),
    ({"format": "boringbar-modal-fit", "modes": []}, "modes"),
    ({"format": "boringbar-modal-fit", "modes": [{"frequency_hz": 1.0}]}, "damping_ratio"),
    ({"format": "boringbar-modal-fit",
      "modes": [{"frequency_hz": -1.0, "damping_ratio": 0.01, "modal_stiffness_n_m": 1e6}]},
     "frequency_hz"),
])
def test_bad_files_name_the_key(data, word):
    with pytest.raises(ParameterError, match=word):
        ModalFit.from_dict(data)
