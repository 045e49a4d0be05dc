"""A section that is not round (flats, an off-centre bore) gives its own second moments a
plane and its area in a system file (docs/systems.md, `[[bar.sections]]`): each plane of
the bar is then a finite-element bar of its own.

Truths: a double-D shank (a round bar with two parallel flats) has the area and second
moments of its integrals, computed here by quadrature; a uniform cantilever of given
E I and rho A has Euler-Bernoulli's frequencies beta_i^2 / (2 pi L^2) sqrt(E I / (rho A))
in each plane; and a bar whose sections all give the second plane r times the first's
moment is the bar of stiffness_ratio r (the same masses and shapes, stiffnesses times r).
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from cli_output import assert_one_line_error
from scipy.integrate import quad

import boringbar as bb
from boringbar._validate import ParameterError
from boringbar.cli.main import main
from boringbar.model.bar import Section
from boringbar.model.materials import MATERIALS
from boringbar.model.system_file import SystemFileError, load_system, parse_system

#: beta_i L of a clamped-free beam, i = 1, 2 (Blevins, table 8-1)
BETA_L = (1.8751040687119611, 4.694091132974175)
ROUND = math.pi * 25.0**4 / 64  # mm^4 of the 25 mm round bar
EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "systems"


def double_d(diameter: float, flats: float) -> tuple[float, float, float]:
    """Area (mm^2) and second moments (mm^4) about the axis parallel to the flats and
    about the one across them, of a round bar of ``diameter`` with two flats
    ``flats`` apart (mm), by quadrature over the chord's half-width."""
    r, c = diameter / 2, flats / 2
    half = lambda y: math.sqrt(r * r - y * y)  # noqa: E731
    area = quad(lambda y: 2 * half(y), -c, c)[0]
    across = quad(lambda y: y * y * 2 * half(y), -c, c)[0]  # bending across the flats
    along = quad(lambda y: (2 * half(y)) ** 3 / 12, -c, c)[0]
    return area, across, along


def spec(sections, **orientation):
    return parse_system({"name": "shank", "bar": {"material": "steel", "sections": sections},
                         "orientation": {"force_ratio": 2.5} | orientation})


def test_a_uniform_shank_bends_in_each_plane_as_euler_bernoulli_says():
    """A 25 mm steel shank with two flats 22 mm apart, 250 mm long: each plane's two
    modes within 1e-6 of the closed form (element 5 mm)."""
    area, across, along = double_d(25.0, 22.0)
    s = spec([{"end_mm": 250.0, "diameter_mm": 25.0, "second_moments_mm4": [across, along],
               "area_mm2": area}])
    table = bb.describe_modes(bb.make_system("solid", spec=s, n_modes=2))["modes"]
    mat = MATERIALS["steel"]
    e, rho = mat.youngs_modulus, mat.density
    for k, moment in enumerate((across, along)):
        for i, beta in enumerate(BETA_L):
            exact = beta**2 / (2 * math.pi * 0.25**2) * math.sqrt(e * moment * 1e-12
                                                                  / (rho * area * 1e-6))
            assert table[2 * k + i]["frequency_hz"] == pytest.approx(exact, rel=1e-6)
    assert [m["plane_deg"] for m in table] == [0, 0, 90, 90]


def test_sections_giving_r_times_the_moment_are_the_bar_of_stiffness_ratio_r():
    """Every section's second plane at 0.64 of its first: the stiffness-ratio bar, to
    1e-9 (two FE solves against one scaled; measured 2e-11)."""
    sections = [{"end_mm": 120.0, "diameter_mm": 25.0},
                {"end_mm": 250.0, "diameter_mm": 22.0}]
    given = [dict(row, second_moments_mm4=[m, 0.64 * m])
             for row, m in zip(sections, (ROUND, math.pi * 22.0**4 / 64), strict=True)]
    a = bb.make_system("solid", spec=spec(given, principal_angle_deg=20.0), n_modes=2).bar
    b = bb.make_system("solid", spec=spec(sections, principal_angle_deg=20.0,
                                          stiffness_ratio=0.64), n_modes=2).bar
    for key in ("mass_kg", "stiffness_n_m", "psi_tip", "psi_force", "psi_damper"):
        x, y = getattr(a, key), getattr(b, key)
        assert np.max(np.abs(x - y)) <= 1e-9 * np.max(np.abs(y)), key


def test_a_ball_bar_s_sections_give_their_planes_beside_its_cavity():
    """The carbide example with a flat shank before its cavity: its planes, along and
    across the cavity, each take their sections' own moments there (the first plane is
    the cavity's), and the cavity's span stays the computed round host's."""
    base = load_system(EXAMPLES / "carbide_ld10_tungsten.toml").data
    flat = math.pi * 32.0**4 / 64
    base["bar"]["sections"] = [{"end_mm": 200.0, "diameter_mm": 32.0,
                                "second_moments_mm4": [0.9 * flat, 0.7 * flat]},
                               {"end_mm": 320.0, "diameter_mm": 32.0}]
    base["orientation"] = {"force_ratio": 2.5, "hole_angle_deg": 30.0}
    s = parse_system(base)
    assert s.stepped_bar(True).sections[0].second_moment_m4 == pytest.approx(0.9 * flat * 1e-12)
    assert s.stepped_bar(True, across=True).sections[0].second_moment_m4 == pytest.approx(
        0.7 * flat * 1e-12)
    modes = bb.describe_modes(bb.make_system("ball", spec=s, n_modes=1))["modes"]
    assert [m["plane_deg"] for m in modes] == pytest.approx([30, 120])
    assert modes[1]["frequency_hz"] < modes[0]["frequency_hz"]  # 0.7 against 0.9
    base["cavity"]["position_mm"] = 150.0  # in the flat shank: its section is not round
    with pytest.raises(SystemFileError, match="round section of its own"):
        parse_system(base)


@pytest.mark.parametrize("row, key", [
    ({"second_moments_mm4": [ROUND * 1.01, ROUND]}, "second_moments_mm4[0]"),
    ({"second_moments_mm4": [ROUND, -1.0]}, "second_moments_mm4[1]"),
    ({"second_moments_mm4": [ROUND]}, "second_moments_mm4"),
    ({"second_moments_mm4": "big"}, "second_moments_mm4"),
    ({"area_mm2": 500.0}, "area_mm2"),
    ({"area_mm2": 0.0}, "area_mm2"),
])
def test_a_bad_section_shape_is_refused_naming_its_key(row, key):
    with pytest.raises(SystemFileError, match=re.escape(f"bar.sections[0].{key}")):
        spec([{"end_mm": 250.0, "diameter_mm": 25.0} | row])


def test_both_the_sections_moments_and_a_stiffness_ratio_are_refused():
    given = [{"end_mm": 250.0, "diameter_mm": 25.0, "second_moments_mm4": [ROUND, ROUND / 2]}]
    with pytest.raises(SystemFileError, match="orientation.stiffness_ratio"):
        spec(given, stiffness_ratio=0.5)
    with pytest.raises(ParameterError, match="stiffness_ratio"):
        bb.make_system("solid", spec=spec(given), cut_geometry=bb.CutGeometry(
            force_ratio=2.5, stiffness_ratio=0.5))
    with pytest.raises(ParameterError, match="given_moments_m4"):
        Section(0.0, 0.25, 0.025, given_moments_m4=(1e-9,))


def test_the_command_line_takes_a_shank_with_flats(tmp_path, capsys):
    """`modes --system` lists each plane's own modes; a bad shape is one line, exit 2."""
    area, across, along = double_d(25.0, 22.0)
    good = tmp_path / "shank.toml"
    good.write_text(f"""name = "shank"
[bar]
material = "steel"
[[bar.sections]]
end_mm = 250.0
diameter_mm = 25.0
second_moments_mm4 = [{across!r}, {along!r}]
area_mm2 = {area!r}
[orientation]
force_ratio = 2.5
""")
    assert main(["modes", "--system", str(good), "--bar", "solid", "--json", "--out",
                 str(tmp_path / "m")]) == 0
    modes = json.loads(capsys.readouterr().out)["modes"]
    assert modes[len(modes) // 2]["frequency_hz"] / modes[0]["frequency_hz"] == pytest.approx(
        math.sqrt(along / across), rel=1e-9)
    bad = tmp_path / "bad.toml"
    bad.write_text(good.read_text().replace(f"area_mm2 = {area!r}", "area_mm2 = 600.0"))
    assert_one_line_error(main, ["modes", "--system", str(bad), "--out",
                                 str(tmp_path / "b")], tmp_path / "b", "area_mm2", capsys)
