"""One chatter-free depth for one design, whichever way it is asked: ``bb.lobes``, the
``boringbar lobes`` command, the design page's simulated lobes and the design search's
min_depth objective run the same method with the same defaults, and each says which.

The design is examples/systems/steel_ld7_tungsten.toml (a 40 mm steel bar at L/D 7, a
20 mm tungsten ball, gap 0.079 mm) at 1200 rpm: by default without the ball's friction
(its cuts decide in seconds), with ``-m slow`` as the file gives it.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_output import json_out

import boringbar as bb
from boringbar.analysis.design_objectives import objective_samples
from boringbar.analysis.design_options import DesignOptions, Variable
from boringbar.analysis.lobes import LobesOptions
from boringbar.app import views
from boringbar.app.design_state import Design
from boringbar.cli.main import main
from boringbar.execute import Execution
from boringbar.simulate import Initial

DESIGN = Path(__file__).resolve().parents[1] / "examples" / "systems" / "steel_ld7_tungsten.toml"
RPM = 1200.0


def design_file(tmp_path: Path, friction: bool) -> Path:
    text = DESIGN.read_text()
    if not friction:
        text = text.replace("friction = { rolling_mm = 0.6 }", "friction = { none = true }")
    path = tmp_path / "design.toml"
    path.write_text(text)
    return path


def four_ways(path: Path, tmp_path: Path, capsys, monkeypatch) -> dict:
    """The ball bar's chatter-free depth at RPM (m) and the method each way names."""
    spec = bb.load_system(path)
    ball = bb.variants(spec)["ball"]
    ds = bb.lobes({"ball": ball}, LobesOptions(rpm=(RPM,)), execution=Execution("serial"))
    out = {"python": (float(ds["limit_depth_m"][0, 0]), ds.attrs["method_text"])}
    assert main(["lobes", "--system", str(path), "--bar", "ball", "--rpm", f"{RPM:g}",
                 "--out", str(tmp_path / "cli"), "--json"]) == 0
    s = json_out(capsys)
    # the command runs the file's ball with friction off and on: the file's own is the
    # case whose friction is as the file gives it
    friction = "off" if ball.damper.friction.kind == "none" else "on"
    case, = (c for c in s["cases"] if c["case"].endswith(f"friction={friction}"))
    out["cli"] = (case["speeds"][0]["limit_depth_m"], s["method_text"])
    monkeypatch.setattr(views, "SIMULATED_SPEEDS", 1)  # the design's speed and one more
    sim = views.simulated_lobes(Design.of(spec), workers=1)
    out["page"] = (sim["depth_at_mm"] * 1e-3, sim["method"])
    options = DesignOptions("ball", (Variable("gap_m", 0.05e-3, 0.3e-3),),
                            objective="min_depth", rpms=(RPM,))
    depth, _ = objective_samples(options, "min_depth", [(ball, Initial())], Execution("serial"))
    out["design"] = (float(depth[0]), options.lobes_options().criterion)
    return out


def check(out: dict) -> None:
    depths = {way: d for way, (d, _) in out.items()}
    assert len(set(depths.values())) == 1, depths
    for way in ("python", "cli", "page"):
        assert out[way][1].startswith("converged verdict"), way
    assert out["design"][1] == "growth"


def test_one_design_one_chatter_free_depth(tmp_path, capsys, monkeypatch):
    check(four_ways(design_file(tmp_path, friction=False), tmp_path, capsys, monkeypatch))


@pytest.mark.slow
def test_the_design_as_its_file_gives_it_one_chatter_free_depth(tmp_path, capsys, monkeypatch):
    check(four_ways(design_file(tmp_path, friction=True), tmp_path, capsys, monkeypatch))
