"""A system with some of its parameters changed: what the design search's samples and the
draws of the chance of chatter do to a bar (docs/design.md, docs/chatter_probability.md).

One function, :func:`perturbed`, so that both read a friction force, a restitution or a
damping ratio the same way.  The ball's parameters change only where the system has a
ball; a bar without one keeps its description.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from boringbar.model.dampers import ImpactDamper
from boringbar.model.system import System

#: The largest damping ratio a perturbed mode takes: ModalModel takes zeta < 1, and a
#: drawn or sampled ratio near 1 is no boring bar's.
MAX_DAMPING_RATIO = 0.99


def perturbed(system: System, *, stiffness_scale=None, damping_scale=None,
              damping_ratio: float | None = None, friction_scale: float | None = None,
              friction_force_n: float | None = None,
              restitution: float | None = None) -> System:
    """``system`` with its modal stiffnesses K_i times ``stiffness_scale`` (one factor a
    mode; the first n_modes of a longer sequence), its damping ratios times
    ``damping_scale`` (likewise) or all set to ``damping_ratio`` (each kept within [0,
    :data:`MAX_DAMPING_RATIO`]); a free or locked ball's friction force F_c times
    ``friction_scale`` or set to ``friction_force_n`` (N, at least 0: a Coulomb force),
    its ``restitution`` (kept within [0, 1]).  None: unchanged."""
    bar = system.bar
    n = bar.n_modes
    if stiffness_scale is not None:
        bar = replace(bar, stiffness_n_m=bar.stiffness_n_m * np.asarray(stiffness_scale)[:n])
    if damping_scale is not None:
        bar = replace(bar, damping_ratio=np.clip(bar.damping_ratio * np.asarray(
            damping_scale)[:n], 0.0, MAX_DAMPING_RATIO))
    if damping_ratio is not None:
        bar = replace(bar, damping_ratio=np.full(n, float(np.clip(
            damping_ratio, 0.0, MAX_DAMPING_RATIO))))
    return replace(system, bar=bar, damper=_ball(system.damper, friction_scale,
                                                 friction_force_n, restitution))


def _ball(damper, friction_scale, friction_force_n, restitution):
    """The damper with the ball's friction and restitution changed (a ball's only)."""
    if not isinstance(damper, ImpactDamper):
        return damper
    fr = damper.friction
    if friction_scale is not None:  # F_c is linear in every friction law's value
        fr = replace(fr, value=fr.value * max(float(friction_scale), 0.0))
    if friction_force_n is not None:
        fr = replace(fr, kind="force", value=max(float(friction_force_n), 0.0))
    if restitution is not None:
        damper = replace(damper, restitution=float(np.clip(restitution, 0.0, 1.0)))
    return replace(damper, friction=fr)
