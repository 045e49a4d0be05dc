"""A modal model fitted to a measured tip FRF, and its file.

A tap test at the tip measures H(omega) = W_tip / F_tip. Fitted with n
uncoupled modes it reads

    H(omega) = sum_i 1 / (k_i (1 - (omega/omega_i)^2 + 2 j zeta_i omega/omega_i)),

with k_i the modal stiffness referred to the tip (N/m), omega_i = 2 pi f_i and
zeta_i the damping ratio. That is a :class:`~boringbar.model.bar.ModalModel`
normalised to psi_i(L) = 1: K_i = k_i, M_i = k_i / omega_i^2. A tip FRF cannot
know the mode shapes at the ball or at the absorber, so those ratios
psi_i(z)/psi_i(L) are given by the user when the fit is used.

The file (``boringbar fit-frf`` writes it, ``--frf FILE`` reads it) is JSON::

    {"format": "boringbar-modal-fit", "version": 1,
     "modes": [{"frequency_hz": ..., "damping_ratio": ..., "modal_stiffness_n_m": ...}, ...],
     "source": {...}, "quality": {...}}

``source`` (where the FRF came from, how it was fitted) and ``quality`` (fit
residuals) are free-form provenance.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from boringbar._validate import ParameterError, check_positive, check_range
from boringbar.model.bar import ModalModel
from boringbar.model.frf_units import implausible_modes

FORMAT = "boringbar-modal-fit"
VERSION = 1
MODE_KEYS = ("frequency_hz", "damping_ratio", "modal_stiffness_n_m")


@dataclass(frozen=True, eq=False)
class ModalFit:
    """Modes fitted to a tip FRF: ``frequency_hz`` f_i (Hz), ``damping_ratio``
    zeta_i and ``modal_stiffness_n_m`` k_i (N/m, referred to the tip), one value
    per mode; ``source`` (where the FRF came from, how it was fitted) and
    ``quality`` (fit residuals) are free-form provenance."""

    frequency_hz: tuple[float, ...]
    damping_ratio: tuple[float, ...]
    modal_stiffness_n_m: tuple[float, ...]
    source: dict = field(default_factory=dict)
    quality: dict = field(default_factory=dict)

    def __post_init__(self):
        n = len(self.frequency_hz)
        if n < 1:
            raise ParameterError("modal fit: modes = [] needs at least one mode")
        for name in MODE_KEYS:
            values = tuple(float(v) for v in getattr(self, name))
            if len(values) != n:
                raise ParameterError(f"modal fit: {name} has {len(values)} values, "
                                     f"expected {n} (one per mode)")
            object.__setattr__(self, name, values)
        for i in range(n):
            check_positive(f"mode {i + 1} frequency_hz", self.frequency_hz[i], "Hz")
            check_range(f"mode {i + 1} damping_ratio", self.damping_ratio[i], 0.0, 1.0,
                        hi_open=True)
            check_positive(f"mode {i + 1} modal_stiffness_n_m", self.modal_stiffness_n_m[i],
                           "N/m")

    @property
    def n_modes(self) -> int:
        return len(self.frequency_hz)

    @property
    def static_stiffness_n_m(self) -> float:
        """The tip's static stiffness 1 / H(0) = 1 / sum_i 1/k_i (N/m)."""
        return 1.0 / sum(1.0 / k for k in self.modal_stiffness_n_m)

    def implausible(self) -> list[str]:
        """What in the static stiffness and the natural frequencies no boring bar has
        (:data:`~boringbar.model.frf_units.PLAUSIBLE_STIFFNESS_N_M`,
        :data:`~boringbar.model.frf_units.PLAUSIBLE_FREQUENCY_HZ`); empty: nothing."""
        return implausible_modes(self.static_stiffness_n_m, self.frequency_hz)

    def tip_frf(self, frequency_hz) -> np.ndarray:
        """The fitted receptance H (m/N, complex) at ``frequency_hz``."""
        f = np.asarray(frequency_hz, dtype=float)
        h = np.zeros(f.shape, dtype=complex)
        for fi, zi, ki in zip(self.frequency_hz, self.damping_ratio,
                              self.modal_stiffness_n_m, strict=True):
            r = f / fi
            h += 1.0 / (ki * (1.0 - r**2 + 2j * zi * r))
        return h

    def to_modal_model(self, damper_ratio=1.0, absorber_ratio=1.0, *,
                       z_damper_m: float | None = None,
                       z_absorber_m: float | None = None) -> ModalModel:
        """The fit as a ModalModel with psi_i(L) = 1.

        ``damper_ratio`` and ``absorber_ratio``: psi_i(z)/psi_i(L) at the ball
        (``z_damper_m``, m from the clamp) and at the absorber (``z_absorber_m``), one
        number for every mode or one per mode.
        """
        n = self.n_modes
        ratios = {}
        for name, value in (("damper_ratio", damper_ratio), ("absorber_ratio", absorber_ratio)):
            arr = np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy()
            for i, v in enumerate(arr):
                check_range(f"{name} of mode {i + 1}", v, -10.0, 10.0)
            ratios[name] = arr
        k = np.array(self.modal_stiffness_n_m)
        omega = 2.0 * math.pi * np.array(self.frequency_hz)
        extra = {}
        if z_damper_m is not None:
            extra["z_damper_m"] = float(z_damper_m)
        if z_absorber_m is not None:
            extra["z_absorber_m"] = float(z_absorber_m)
        return ModalModel(mass_kg=k / omega**2, stiffness_n_m=k,
                          damping_ratio=np.array(self.damping_ratio), psi_tip=np.ones(n),
                          psi_damper=ratios["damper_ratio"],
                          psi_absorber=ratios["absorber_ratio"], source="frf-fit",
                          info={"frf_fit": self.to_dict()}, **extra)

    def to_dict(self) -> dict:
        modes = [dict(zip(MODE_KEYS, values, strict=True))
                 for values in zip(self.frequency_hz, self.damping_ratio,
                                   self.modal_stiffness_n_m, strict=True)]
        return {"format": FORMAT, "version": VERSION, "modes": modes,
                "source": dict(self.source), "quality": dict(self.quality)}

    @classmethod
    def from_dict(cls, data: dict, *, where: str = "modal fit") -> ModalFit:
        found = data.get("format") if isinstance(data, dict) else data
        if found != FORMAT:
            raise ParameterError(f"{where}: format = {found!r} is not {FORMAT!r} "
                                 "(write it with boringbar fit-frf)")
        modes = data.get("modes")
        if not isinstance(modes, list) or not modes:
            raise ParameterError(f"{where}: modes = {modes!r} must be a non-empty list")
        for i, mode in enumerate(modes):
            missing = [k for k in MODE_KEYS if not isinstance(mode, dict) or k not in mode]
            if missing:
                raise ParameterError(f"{where}: mode {i + 1} lacks {', '.join(missing)}")
        return cls(**{k: tuple(m[k] for m in modes) for k in MODE_KEYS},
                   source=data.get("source", {}), quality=data.get("quality", {}))

    @classmethod
    def read(cls, path, name: str = "frf") -> ModalFit:
        """Read a fit written by :meth:`to_dict` (``boringbar fit-frf``); an error names
        the file as ``name`` (the command line: "--frf")."""
        p = Path(path)
        try:
            data = json.loads(p.read_text())
        except FileNotFoundError:
            raise ParameterError(f"{name} = {str(p)!r}: no such file") from None
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise ParameterError(f"{name} = {str(p)!r} is not a JSON modal fit ({exc})") \
                from None
        return cls.from_dict(data, where=f"{name} = {str(p)!r}")
