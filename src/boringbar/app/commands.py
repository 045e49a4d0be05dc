"""The command line that reproduces each view of the design page, on the design as
Export writes it (``--system FILE``): the page and the command run the same library
on the same description."""

from __future__ import annotations

import numpy as np

from boringbar.app import views
from boringbar.app.design_state import DT_S, RUN_S, Design


def commands(design: Design, file: str) -> dict[str, str]:
    """view -> the ``boringbar`` command that computes it (``file``: the exported
    system file)."""
    s = design.settings
    common = f"--system {file} --preset {s.preset}"
    bars = ",".join(design.systems)
    damped = views.damped(design).kind
    forcing = (f"--force-n {s.force_n:g} --ratio {s.ratio:g}" if s.forcing == "harmonic"
               else f"--rpm {s.rpm:g} --depth-mm {s.depth_mm:g}")
    r = views.RESPONSE_RATIOS
    step = (r[-1] - r[0]) / (len(r) - 1)
    band = views.lobe_speeds(design)
    out = {
        "bar": f"boringbar modes {common}",
        "run": f"boringbar simulate {common} --bar {damped} {forcing} --integrator "
               f"{s.integrator} --duration-s {RUN_S:g} --dt-s {DT_S:g}",
        "response": f"boringbar sweep {common} --bar {bars} --force-n {s.force_n:g} "
                    f"--ratios {r[0]:.4g}:{r[-1]:.4g}:{step:.4g} --duration-s {RUN_S:g} "
                    f"--integrator {s.integrator}",
        "lobes": f"boringbar lobes {common} --analytic --rpm "
                 f"{band[0]:.0f}:{band[-1]:.0f}:{np.ptp(band) / 50:.4g} --at-rpm {s.rpm:g}",
    }
    if design.spec.ball is not None:
        speeds = ",".join(f"{r:g}" for r in views.simulated_speeds(design))
        out["lobes"] += (f"\nboringbar lobes {common} --bar ball --method search --rpm "
                         f"{speeds} --duration-s {views.SIMULATED_CUT_S:g} --at-rpm {s.rpm:g}")
    return out
