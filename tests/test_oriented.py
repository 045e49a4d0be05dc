"""Two bending planes and an oriented cut (model/oriented.py, docs/model.md, section 4.7).

Truths not from our code: the oriented transfer function built here from the section's
2 x 2 compliance matrix and the cut's two directions; Altintas' two-degree-of-freedom
example (*Manufacturing Automation*, 2nd ed., 2012, p. 131: modes of 250 and 150 Hz
oriented at 30 and -45 degrees to the force, Kf = 1000 MPa), whose absolute limit and
lobe bottoms his lab's published port (github.com/leekunhwee/Dynamics,
Cutting/Stability/FrequencyDomain/Turning/Two DOF Example, Lobe.png) shows at about
7.2 mm near 8,700 rpm; the one-plane bar as a special case; the converged verdict's
simulated lobes against the closed form; the harmonic response and the energy balance.
"""

from __future__ import annotations

import json
import math
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from cli_output import assert_one_line_error

import boringbar as bb
from boringbar._validate import ParameterError
from boringbar.cli.main import main
from boringbar.model.bar import ModalModel
from boringbar.model.oriented import CutGeometry, for_bar, oriented_model
from boringbar.model.system import System, make_system
from boringbar.model.system_file import SystemFileError, parse_system, published_file_text
from boringbar.orbits.shooting import make_flow, multipliers, periodic_orbit
from boringbar.reference.linear import tip_frf
from boringbar.reference.stability import analytic_lobes, min_limit

sys.path.insert(0, str(Path(__file__).parent))
from test_verdict import worst_error  # noqa: E402

GEOMETRY = CutGeometry(force_ratio=2.5, lead_angle_deg=30.0, hole_angle_deg=20.0,
                       principal_angle_deg=25.0, stiffness_ratio=0.8)
#: the solid bar's: no cavity, so no hole angle
SOLID = for_bar(GEOMETRY, "solid", CutGeometry())


def altintas() -> System:
    """Altintas' two-mode example: 250 Hz, 1.2 %, 2.26e8 N/m at 30 degrees and 150 Hz,
    1 %, 2.13e8 N/m at -45 degrees from the force and chip direction."""
    f, zeta, k = np.array([250.0, 150.0]), np.array([0.012, 0.01]), np.array([2.26e8, 2.13e8])
    w = 2 * np.pi * f
    theta = np.radians([30.0, -45.0])
    bar = ModalModel(k / w**2, k, zeta, np.cos(theta), np.zeros(2), np.zeros(2),
                     source="altintas-2012-p131")
    return System(bar, None, "physical")


def book_frf(w):
    """The example's oriented FRF as the book writes it: sum cos^2 theta_i / k_i
    omega_i^2 / (omega_i^2 - omega^2 + 2 i zeta_i omega_i omega)."""
    out = 0
    for f, z, k, th in ((250.0, 0.012, 2.26e8, 30.0), (150.0, 0.01, 2.13e8, -45.0)):
        wn = 2 * np.pi * f
        out = out + math.cos(math.radians(th)) ** 2 / k * wn**2 / (
            wn**2 - w**2 + 2j * z * wn * w)
    return out


# --- the oriented transfer function -------------------------------------------------------
def test_the_oriented_frf_is_the_sections_compliance_projected_on_the_cut():
    """W / F built here: the tip's 2 x 2 compliance in (radial, tangential), each plane's
    receptance along its principal direction, loaded by F = (cos kappa, rho) and read
    along (cos kappa, 0)."""
    plane = make_system("solid", n_modes=2).bar
    bar = oriented_model(plane, GEOMETRY)
    w = np.linspace(0.5, 2.0, 301) * plane.natural_frequency_rad_s
    g = GEOMETRY
    kappa, phi = math.radians(g.lead_angle_deg), math.radians(g.principal_angle_deg)
    rot = np.array([[math.cos(phi), -math.sin(phi)], [math.sin(phi), math.cos(phi)]])

    def receptance(scale):
        return sum(plane.psi_tip[i] ** 2 / (plane.stiffness_n_m[i] * scale
                                            - w**2 * plane.mass_kg[i]
                                            + 1j * w * plane.damping_n_s_m[i]
                                            * math.sqrt(scale))
                   for i in range(plane.n_modes))

    h = np.zeros((len(w), 2, 2), complex)
    h[:, 0, 0], h[:, 1, 1] = receptance(1.0), receptance(g.stiffness_ratio)
    compliance = rot @ h @ rot.T
    load, read = np.array([math.cos(kappa), g.force_ratio]), np.array([math.cos(kappa), 0.0])
    expected = np.einsum("i,wij,j->w", read, compliance, load)
    np.testing.assert_allclose(tip_frf(bar, w), expected, rtol=1e-10)


def test_a_cut_along_one_plane_is_the_one_plane_bar():
    plane = make_system("solid", n_modes=2)
    two = make_system("solid", n_modes=2, planes=2, cut_geometry=CutGeometry())
    assert two.bar.n_modes == 4 and np.all(two.bar.psi_tip[2:] == 0)
    w = np.linspace(0.5, 2.0, 101) * plane.reference_frequency_rad_s
    np.testing.assert_allclose(tip_frf(two.bar, w), tip_frf(plane.bar, w), rtol=1e-13)
    forcing = bb.Harmonic(amplitude_n=10.0)
    one_run = bb.simulate(plane, forcing, duration_s=0.05, integrator="rk4", record_every=0)
    two_run = bb.simulate(two, forcing, duration_s=0.05, integrator="rk4", record_every=0)
    assert two_run.metrics["rms_tip_m"] == pytest.approx(one_run.metrics["rms_tip_m"],
                                                         rel=1e-12)


# --- a published example ------------------------------------------------------------------
def test_altintas_two_mode_example():
    system = altintas()
    w = np.linspace(0.5, 2.0, 400_001) * 2 * np.pi * 150.0
    book = -1.0 / (2 * 1e9 * book_frf(w).real.min())
    assert min_limit(system, 1e9) == pytest.approx(book, rel=1e-6)
    assert min_limit(system, 1e9) == pytest.approx(7.2e-3, abs=0.15e-3)  # Lobe.png
    # lobes 1-3 (lobe 0 bottoms at 20,265 rpm, beyond the figure's 15,000)
    lobes = analytic_lobes(system, 1e9, lobes=range(1, 4))
    bottoms = [lobes["rpm"][j][np.nanargmin(lobes["b_lim"][j])] for j in range(3)]
    np.testing.assert_allclose(bottoms, [8678.0, 5521.0, 4049.0], rtol=2e-3)


def test_the_simulated_limit_of_altintas_example_is_its_closed_form():
    err, rpm = worst_error(altintas(), (4049.0, 5521.0, 7000.0, 8678.0, 11849.0), kr_pa=1e9,
                           max_depth_m=0.1)
    assert err <= 0.01, f"{err:.2%} at {rpm:g} rpm"


def test_the_simulated_limit_of_an_oriented_bar_is_its_closed_form():
    system = make_system("solid", n_modes=1, planes=2, cut_geometry=SOLID)
    err, rpm = worst_error(system, (3000.0, 4100.0, 5200.0, 6745.0, 9125.0))
    assert err <= 0.01, f"{err:.2%} at {rpm:g} rpm"


# --- runs ---------------------------------------------------------------------------------
@pytest.mark.parametrize("integrator", ["rk4", "exact"])
def test_a_harmonic_run_settles_on_the_oriented_response_and_balances(integrator):
    """The force works on psi_F . u', the chip reads psi_L . u: the settled amplitude is
    the oriented FRF's (measured 9e-9 RK4, 2e-9 exact), and the work of the force closes
    the balance (the exact integrator's to round-off)."""
    system = make_system("solid", n_modes=1, planes=2, cut_geometry=SOLID)
    w = system.reference_frequency_rad_s
    run = bb.simulate(system, bb.Harmonic(amplitude_n=10.0), duration_s=0.6, record_every=0,
                      integrator=integrator)
    assert run.metrics["amplitude_m"] == pytest.approx(
        10.0 * abs(tip_frf(system.bar, np.array([w]))[0]), rel=1e-6)
    assert abs(run.energy["balance_relative"]) < 1e-9
    assert bb.simulate(system, bb.Harmonic(10.0), duration_s=0.01).integrator == "exact"


def test_the_exact_integrator_steps_an_oriented_ball_bar_and_rk4_goes_to_it():
    """A ball bar at 30 degrees under Kt/Kr = 2.5 and a 30 degree lead angle (2 N, the
    ball slides without impacts): RK4's RMS goes to the exact one's at first order
    (measured 2.1e-6 and 5.0e-7 at 1 and 0.25 us), the exact balance to round-off."""
    system = make_system("ball", planes=2, cut_geometry=CutGeometry(
        force_ratio=2.5, lead_angle_deg=30.0, hole_angle_deg=30.0))
    forcing = bb.Harmonic(2.0, 1.0)
    exact = bb.simulate(system, forcing, duration_s=0.05, integrator="exact")
    assert abs(exact.energy["balance_relative"]) < 1e-12
    errors = [abs(bb.simulate(system, forcing, duration_s=0.05, integrator="rk4", dt_s=dt)
                  .metrics["rms_tip_m"] / exact.metrics["rms_tip_m"] - 1) for dt in (1e-6, 2.5e-7)]
    assert errors[0] < 1e-5 and 3.0 < errors[0] / errors[1] < 5.0, errors


@pytest.mark.parametrize("depth_m", [2.7e-5, 4.5e-5])
def test_the_exact_oriented_cut_is_rk4_s_and_balances(depth_m):
    """At 0.63 and 1.05 times the closed-form limit (4.3e-5 m at 3000 rpm): the exact
    cut's RMS is RK4's at 0.25 us to 1e-6 (measured 9e-8 and 6e-7), and its force's work
    on psi_F . u' closes the balance (measured 8e-12, 2e-11)."""
    system = make_system("solid", n_modes=1, planes=2, cut_geometry=SOLID)
    cut = bb.Regenerative(depth_m=depth_m, rpm=3000.0)
    ex = bb.simulate(system, cut, duration_s=0.3, integrator="exact", dt_s=2e-6)
    rk = bb.simulate(system, cut, duration_s=0.3, integrator="rk4", dt_s=2.5e-7)
    assert abs(ex.energy["balance_relative"]) < 1e-9
    assert ex.metrics["rms_tip_m"] == pytest.approx(rk.metrics["rms_tip_m"], rel=1e-6)


def test_a_ball_moves_along_its_cavity():
    g = CutGeometry(hole_angle_deg=90.0)
    system = make_system("ball", n_modes=1, planes=2, cut_geometry=g)
    # the cavity across the radial plane: its modes do not carry the ball
    assert system.bar.psi_damper[0] == 0 and system.bar.psi_damper[1] != 0
    assert System.from_dict(system.to_dict()).bar.psi_force.tolist() == \
        system.bar.psi_force.tolist()


# --- where it applies, and bad input ------------------------------------------------------
def test_shooting_finds_an_oriented_bar_s_orbits():
    """Shooting takes the force's shape psi_F: the oriented solid bar's orbit has the
    oriented FRF's amplitude (measured 1.6e-15), and the oriented ball bar's (gap 0.1 mm,
    20 N, six impacts a period) is where the exact integrator settles in 300 periods
    (measured 1.8e-9; its multipliers within the unit circle)."""
    solid = make_system("solid", n_modes=1, planes=2, cut_geometry=SOLID)
    forcing = bb.Harmonic(10.0, ratio=0.93)
    fl = make_flow(solid, forcing)
    x, _ = periodic_orbit(fl, np.zeros(fl.N))
    n, bar = fl.n, solid.bar
    amplitude = np.hypot(bar.psi_tip @ x[:n], bar.psi_tip @ x[n:] / fl.omega)
    assert amplitude == pytest.approx(10.0 * abs(tip_frf(bar, np.array([fl.omega]))[0]),
                                      rel=1e-12)
    ball = make_system("ball", planes=2, gap_m=0.1e-3, friction=False, cut_geometry=CutGeometry(
        force_ratio=2.5, lead_angle_deg=30.0, hole_angle_deg=30.0))
    forcing = bb.Harmonic(20.0, ratio=1.0)
    fl = make_flow(ball, forcing)
    dt = fl.period / math.ceil(fl.period / 1e-6)
    settled = bb.simulate(ball, forcing, duration_s=300 * fl.period, dt_s=dt,
                          integrator="exact").final.x
    x, pr = periodic_orbit(fl, settled)
    assert [k for _, k in pr.events].count("impact+") == 3
    assert np.max(np.abs(settled - x)) <= 1e-8 * np.max(np.abs(x))
    assert abs(multipliers(pr)[0]) < 1.0


@pytest.mark.parametrize("argv, name", [
    (["--lead-angle-deg", "95"], "--lead-angle-deg"),
    (["--lead-angle-deg", "90"], "--lead-angle-deg"),
    (["--lead-angle-deg", "-1"], "--lead-angle-deg"),
    (["--hole-angle-deg", "120"], "--hole-angle-deg"),
    (["--force-ratio", "-1"], "--force-ratio"),
    (["--stiffness-ratio", "0"], "--stiffness-ratio"),
    (["--planes", "1", "--force-ratio", "2"], "--planes 2"),
    (["--bar", "ball", "--stiffness-ratio", "0.5"], "--stiffness-ratio = 0.5 applies to the "
     "solid and tmd"),
    (["--bar", "ball", "--principal-angle-deg", "20"], "--principal-angle-deg"),
    (["--bar", "solid", "--planes", "2", "--hole-angle-deg", "30"], "--hole-angle-deg"),
])
def test_the_command_line_refuses_a_bad_orientation(argv, name, tmp_path, capsys):
    out = tmp_path / "out"
    assert_one_line_error(main, ["simulate", *argv, "--out", str(out)], out, name, capsys)


def test_modes_refuses_a_key_its_bar_does_not_use(tmp_path, capsys):
    out = tmp_path / "out"
    assert_one_line_error(main, ["modes", "--stiffness-ratio", "0.5", "--out", str(out)],
                          out, "--stiffness-ratio", capsys)


def test_a_key_a_bar_does_not_use_is_refused_where_it_is_given():
    """The ball bar's planes are its cavity's section bent each way, and nothing moves in
    a solid bar: given to make_system, those keys are refused; a system file describes
    the hardware, and each bar it builds, alone or in a comparison, takes its own keys."""
    with pytest.raises(ParameterError, match="stiffness_ratio = 0.5 applies to the solid"):
        make_system("ball", planes=2, cut_geometry=CutGeometry(stiffness_ratio=0.5))
    with pytest.raises(ParameterError, match="hole_angle_deg = 30 applies to the ball"):
        make_system("solid", planes=2, cut_geometry=CutGeometry(hole_angle_deg=30.0))
    tmd = make_system("tmd", planes=2, cut_geometry=CutGeometry(hole_angle_deg=30.0,
                                                                stiffness_ratio=0.5))
    assert tmd.bar.info["cut_geometry"]["stiffness_ratio"] == 0.5
    d = tomllib.loads(published_file_text())
    d["orientation"] = {"lead_angle_deg": 30.0, "stiffness_ratio": 0.5}
    spec = parse_system(d)
    plain = make_system("ball", planes=2, cut_geometry=CutGeometry(lead_angle_deg=30.0))
    for ball in (make_system("ball", spec=spec),
                 make_system("ball", spec=spec, cut_geometry=spec.orientation)):
        np.testing.assert_array_equal(ball.bar.omegas_rad_s, plain.bar.omegas_rad_s)
    g = CutGeometry(lead_angle_deg=30.0, hole_angle_deg=20.0, stiffness_ratio=0.5)
    cases = {c.label.split()[0]: c.system for c in bb.published_cases(
        gaps_m=(0.5e-3,), frictions=(True,), planes=2, cut_geometry=g)}
    solid = make_system("solid", planes=2, cut_geometry=CutGeometry(lead_angle_deg=30.0,
                                                                    stiffness_ratio=0.5))
    np.testing.assert_array_equal(cases["solid"].bar.omegas_rad_s, solid.bar.omegas_rad_s)
    ball = make_system("ball", planes=2, cut_geometry=CutGeometry(lead_angle_deg=30.0,
                                                                  hole_angle_deg=20.0))
    np.testing.assert_array_equal(cases["ball"].bar.psi_damper, ball.bar.psi_damper)


def test_a_system_file_gives_the_planes_and_refuses_a_bad_angle():
    d = tomllib.loads(published_file_text())
    d["orientation"] = {"force_ratio": 2.5, "lead_angle_deg": 30.0, "hole_angle_deg": 20.0}
    spec = parse_system(d)
    system = make_system("ball", spec=spec, n_modes=1)
    assert spec.planes == 2 and system.bar.n_modes == 2 and system.bar.oriented
    assert system.bar.info["cut_geometry"]["lead_angle_deg"] == 30.0
    for key, value in (("lead_angle_deg", 90.0), ("hole_angle_deg", -91.0), ("planes", 3),
                       ("planes", True), ("planes", 2.0)):
        bad = tomllib.loads(published_file_text())
        bad["orientation"] = {key: value}
        with pytest.raises(SystemFileError, match=f"orientation.{key}"):
            parse_system(bad)
    one = tomllib.loads(published_file_text())
    one["orientation"] = {"planes": 1, "force_ratio": 2.5}  # was run with the cut dropped
    with pytest.raises(SystemFileError, match="orientation.planes.*force_ratio"):
        parse_system(one)


# --- the cavity's two planes --------------------------------------------------------------
def test_the_cavity_section_across_the_ball_is_its_moment_about_the_other_axis():
    """The equivalent section for bending across the ball's direction: the flexibility
    int ds / I(s) with the strip's moment about the other axis, by adaptive quadrature."""
    from scipy.integrate import quad

    from boringbar.model.cavity_section import cavity_section_diameter, cut_section_moment
    d, bore, length, depth = 0.025, 0.008, 0.0151, 0.02
    a, h = length / 2, depth / 2
    flex = quad(lambda t: math.cos(t) / cut_section_moment(d, bore, h, a * math.cos(t)),
                0, math.pi / 2, limit=500, epsabs=0, epsrel=1e-13)[0]
    expected = (64 / math.pi / flex + bore**4) ** 0.25
    assert cavity_section_diameter(d, bore, length, depth, across=True) == pytest.approx(
        expected, rel=1e-9)


def test_a_ball_bar_bends_along_and_across_its_cavity():
    """Its planes are along the cavity (the published FE bar) and across it (the cavity's
    section about the other axis, stiffer here, with the same mass)."""
    one = make_system("ball", n_modes=1)
    two = make_system("ball", n_modes=1, planes=2, cut_geometry=CutGeometry(hole_angle_deg=0))
    f = two.bar.omegas_rad_s / (2 * np.pi)
    assert f[0] == one.bar.omegas_rad_s[0] / (2 * np.pi) and f[1] > f[0] * 1.01
    spec = one.spec
    along, across = spec.stepped_bar(True), spec.stepped_bar(True, across=True)
    assert [s.area_m2 for s in along.sections] == [s.area_m2 for s in across.sections]
    assert two.bar.psi_damper[1] == 0 and two.bar.psi_tip[1] == 0


def test_published_cases_hold_every_bar_to_the_planes_and_the_cut():
    """The solid and TMD bars of a comparison take the planes and the oriented cut the
    ball takes (the command line's sweep, lobes and chatter map build their cases so)."""
    g = CutGeometry(force_ratio=2.5, lead_angle_deg=30.0, principal_angle_deg=20.0)
    cases = bb.published_cases(gaps_m=(0.5e-3,), frictions=(True,), planes=2,
                               cut_geometry=g)
    for case in cases:
        bar = case.label.split()[0]
        gap = {"gap_m": 0.5e-3} if bar == "ball" else {}
        alone = make_system(bar, planes=2, cut_geometry=for_bar(g, bar, CutGeometry()), **gap)
        assert case.system.bar.n_modes == 4
        np.testing.assert_array_equal(case.system.bar.psi_force, alone.bar.psi_force)


def test_make_system_refuses_planes_and_a_geometry_it_cannot_take():
    for planes in (True, 2.5, 3):
        with pytest.raises(ParameterError, match="planes"):
            make_system("ball", planes=planes)
    with pytest.raises(TypeError, match="must be a CutGeometry"):
        make_system("ball", planes=2, cut_geometry={"force_ratio": 2.5})


def test_modes_lists_each_plane_s_modes_in_their_own_plane(tmp_path, capsys):
    """A plane of EI times r has the same modal masses and shapes, frequencies times
    sqrt(r), and stiffnesses times r; the modes' table shows them unprojected."""
    out = tmp_path / "m"
    assert main(["modes", "--bar", "solid", "--planes", "2", "--stiffness-ratio", "0.5",
                 "--principal-angle-deg", "30", "--modes", "2", "--json", "--out",
                 str(out)]) == 0
    table = json.loads(capsys.readouterr().out)
    one = bb.describe_modes(make_system("solid", n_modes=2))
    modes = table["modes"]
    assert [m["plane_deg"] for m in modes] == pytest.approx([30, 30, 120, 120])
    for i, mode in enumerate(one["modes"]):
        a, b = modes[i], modes[i + 2]
        assert a["frequency_hz"] == pytest.approx(mode["frequency_hz"], rel=1e-12)
        assert b["frequency_hz"] == pytest.approx(mode["frequency_hz"] * math.sqrt(0.5),
                                                  rel=1e-12)
        assert b["modal_stiffness_n_m"] == pytest.approx(0.5 * a["modal_stiffness_n_m"],
                                                         rel=1e-12)
        assert b["psi_ball"] == a["psi_ball"] == pytest.approx(mode["psi_ball"], rel=1e-12)
    assert table["tip_static_stiffness_n_m"] == one["tip_static_stiffness_n_m"]
    assert table["built_plane_deg"] == pytest.approx(30)
    assert table["runs_retain"] == 4  # the physical preset's 2 a plane
    assert (out / "modes.png").stat().st_size > 0
    assert_one_line_error(main, ["modes", "--planes", "2", "--modes", "5", "--out",
                                 str(tmp_path / "bad")], tmp_path / "bad", "--modes", capsys)
