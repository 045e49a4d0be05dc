"""Closed-form symmetric two-impacts-per-period orbit of the ball damper.

The Masri-Caughey solution (S. F. Masri and T. K. Caughey, J. Appl. Mech.
33 (1966) 586-592) rederived for this package's model (docs/model.md, section 2)
with one mode, no friction, and the bar's modal damping C kept (the motion
is linear between impacts, so a closed form still exists):

    M u'' + C u' + K u = psi_L F0 sin(Omega t) + sum_k P_k delta(t - t_k)   (bar)
    u_d'' = 0 between impacts                                              (ball)
    y = u_d - psi_d u,   walls at y = +-delta/2

At an impact the ball receives an impulse J and the mode -psi_d J, with
y'+ = -e y'-.  The symmetric orbit hits the + wall at Omega t = phi (mod
2 pi) and the - wall half a period later, with u(t + T/2) = -u(t) and
u_d(t + T/2) = -u_d(t).  The ball flies at -V after a + impact and at +V
after a - impact, so J = -2 m V at the + wall and the mode receives
P = 2 m psi_d V there (and -P at the - wall).

Derivation (T_h = T/2 = pi / Omega, t_0 = phi / Omega, tau = t - t_0):

1. The bar's steady response is u = u_F + u_I: the harmonic part
   u_F(t) = psi_L F0 Im(H e^{i Omega t}), H = 1 / (K - M Omega^2 + i C Omega),
   and the response to the alternating impulse train, summed as a geometric
   series of damped free responses h(t) = Im(e^{lambda t}) / (M omega_d),
   lambda = -zeta omega_n + i omega_d:

       u_I(tau) = P / (M omega_d) Im(e^{lambda tau} / (1 + e^{lambda T_h})),  0 <= tau < T_h,

   antiperiodic (u_I(tau + T_h) = -u_I(tau)), with u_I' jumping by P / M
   at tau = 0.  At the impact, per unit P: u_I(0) = a0 P and the mean of
   u_I'(0-) and u_I'(0+) is b0 P, with
   a0 = Im(1 / (1 + E)) / (M omega_d),  b0 = Im(lambda (1 - E) / (1 + E)) / (2 M omega_d),
   E = e^{lambda T_h}.

2. Geometry: the ball crosses from the + wall to the - wall in T_h,
   V T_h = delta + 2 psi_d u(t_0).

3. Momentum and restitution at the + wall, with v_bar the mean of the
   bar's modal velocity before and after (v+ - v- = P / M):
   (1 - e)(1 + mu psi_d^2) V = -(1 + e) psi_d v_bar,   mu = m / M.

Eliminating V between 2 and 3 (both linear in V, with u(t_0) and v_bar
linear in sin phi, cos phi) leaves

    a cos phi + b sin phi = delta,    (see :func:`phase_equation`)

solved as phi = atan2(b, a) +- arccos(delta / sqrt(a^2 + b^2)): two orbits
when sqrt(a^2 + b^2) > delta, none below (the forcing is too weak for this
pattern).  Each is then checked for admissibility (V > 0, the ball
approaching the wall it hits, |y| <= delta/2 in flight) and for stability
(the eigenvalues of the linearised impact-to-impact map).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.optimize

from boringbar._validate import ParameterError, check_nonnegative, check_positive, check_range

#: Relative tolerance on the wall position when checking |y| <= delta/2.
WALL_TOL = 1e-9
#: Samples per half period for the admissibility check and the amplitude search.
FLIGHT_SAMPLES = 4001


@dataclass(frozen=True)
class ImpactSystem:
    """One bar mode with a frictionless ball damper under F0 sin(Omega t), SI units.

    ``mass`` M, ``stiffness`` K, ``damping`` C are modal (any normalisation),
    ``psi_tip`` psi_L and ``psi_ball`` psi_d the mode's values at the tip and
    at the ball; ``ball_mass`` m (kg), ``gap`` delta (m, total clearance),
    ``restitution`` e, ``force`` F0 (N), ``omega`` Omega (rad/s).
    """

    mass: float
    stiffness: float
    damping: float
    psi_tip: float
    psi_ball: float
    ball_mass: float
    gap: float
    restitution: float
    force: float
    omega: float

    def __post_init__(self):
        check_positive("modal mass M", self.mass)
        check_positive("modal stiffness K", self.stiffness)
        check_range(
            "modal damping C",
            self.damping,
            0.0,
            2.0 * math.sqrt(self.stiffness * self.mass),
            hi_open=True,
            unit="N s/m",
        )
        for name, value in (("psi_L", self.psi_tip), ("psi_d", self.psi_ball)):
            if not (math.isfinite(value) and value != 0.0):
                raise ParameterError(f"{name} = {value!r} must be finite and non-zero")
        check_positive("ball mass m", self.ball_mass, "kg")
        check_positive("gap", self.gap, "m")
        check_range("restitution e", self.restitution, 0.0, 1.0)
        check_nonnegative("force amplitude F0", self.force, "N")
        check_positive("forcing frequency Omega", self.omega, "rad/s")
        self._check_not_resonant()

    def _check_not_resonant(self) -> None:
        """An undamped bar has no steady response at Omega = omega_n (H infinite) nor at
        Omega = omega_n / (2 j + 1) (the alternating impulse train resonates)."""
        dyn = abs(complex(self.stiffness - self.mass * self.omega**2, self.damping * self.omega))
        train = abs(1.0 + np.exp(self.eigenvalue * self.half_period))
        if dyn < 1e-9 * self.stiffness or train < 1e-9:
            wn = math.sqrt(self.stiffness / self.mass)
            raise ParameterError(
                f"forcing frequency Omega = {self.omega!r} rad/s: an (almost) undamped bar "
                f"(C = {self.damping!r}) has no steady two-impact orbit at resonance "
                f"(Omega = omega_n / (2 j + 1), omega_n = {wn:.6g} rad/s)"
            )

    # --- derived constants -------------------------------------------------
    @property
    def half_period(self) -> float:
        return math.pi / self.omega

    @property
    def omega_d(self) -> float:
        """Damped natural frequency (rad/s)."""
        wn = math.sqrt(self.stiffness / self.mass)
        zeta = self.damping / (2.0 * math.sqrt(self.stiffness * self.mass))
        return wn * math.sqrt(1.0 - zeta * zeta)

    @property
    def eigenvalue(self) -> complex:
        """lambda = -zeta omega_n + i omega_d (1/s)."""
        return complex(-self.damping / (2.0 * self.mass), self.omega_d)

    @property
    def receptance(self) -> complex:
        """H = 1 / (K - M Omega^2 + i C Omega), modal."""
        w = self.omega
        return 1.0 / complex(self.stiffness - self.mass * w * w, self.damping * w)

    @property
    def effective_ratio(self) -> float:
        """mu psi_d^2 = m psi_d^2 / M: the ball's mass against the bar's at z_d."""
        return self.ball_mass * self.psi_ball**2 / self.mass

    def impulse_train_constants(self) -> tuple[float, float]:
        """(a0, b0): u_I(0) = a0 P and mean(u_I'(0-), u_I'(0+)) = b0 P."""
        lam, e_half = self.eigenvalue, np.exp(self.eigenvalue * self.half_period)
        md = self.mass * self.omega_d
        a0 = (1.0 / (1.0 + e_half)).imag / md
        b0 = (lam * (1.0 - e_half) / (1.0 + e_half)).imag / (2.0 * md)
        return a0, b0

    # --- motion on the orbit ------------------------------------------------
    def forced_modal(self, t):
        """u_F(t) = psi_L F0 Im(H e^{i Omega t}) and its derivative (modal)."""
        z = self.psi_tip * self.force * self.receptance * np.exp(1j * self.omega * np.asarray(t))
        return z.imag, (1j * self.omega * z).imag


@dataclass(frozen=True)
class Orbit:
    """A symmetric two-impacts-per-period orbit (one + wall and one - wall impact).

    ``phase`` phi (rad, in [0, 2 pi)): the + wall impact happens at
    Omega t = phi (mod 2 pi) relative to the forcing F0 sin(Omega t).
    ``ball_speed`` V (m/s, absolute) is the ball's speed in flight;
    ``impulse`` J = -2 m V (N s) the impulse on the ball at the + wall (the
    - wall's is -J).  ``bar_velocity_before``/``after``: the bar's velocity at
    z_d, psi_d u', just before/after the + wall impact (m/s; independent of
    the mode's normalisation).  ``admissible`` says whether the orbit is
    physical; ``message`` why not.  ``stable``: all eigenvalues of the
    linearised impact map inside the unit circle (``multipliers``).
    """

    phase: float
    ball_speed: float
    impulse: float
    bar_velocity_before: float
    bar_velocity_after: float
    admissible: bool
    message: str
    system: ImpactSystem = field(repr=False)
    stable: bool | None = None
    multipliers: tuple = field(default=(), repr=False)

    # --- time histories -----------------------------------------------------
    @property
    def impact_time(self) -> float:
        """t_0 = phi / Omega (s), the first + wall impact at t >= 0."""
        return self.phase / self.system.omega

    @property
    def modal_impulse(self) -> float:
        """P = 2 m psi_d V: the mode's impulse at the + wall (N s in modal units)."""
        return -self.system.psi_ball * self.impulse

    def _split(self, t):
        """(sign, tau): t = t_0 + k T_h + tau, 0 <= tau < T_h, sign = (-1)^k."""
        th = self.system.half_period
        s = (np.asarray(t, dtype=float) - self.impact_time) / th
        k = np.floor(s)
        return 1.0 - 2.0 * np.mod(k, 2.0), (s - k) * th

    def modal_displacement(self, t):
        """u(t) on the orbit (vectorised), the harmonic plus the impulse-train part."""
        sys = self.system
        sign, tau = self._split(t)
        lam = sys.eigenvalue
        kernel = np.exp(lam * tau) / (1.0 + np.exp(lam * sys.half_period))
        u_imp = sign * self.modal_impulse / (sys.mass * sys.omega_d) * kernel.imag
        return sys.forced_modal(t)[0] + u_imp

    def modal_velocity(self, t):
        """u'(t) on the orbit (vectorised); at an impact instant, the value just after."""
        sys = self.system
        sign, tau = self._split(t)
        lam = sys.eigenvalue
        kernel = lam * np.exp(lam * tau) / (1.0 + np.exp(lam * sys.half_period))
        v_imp = sign * self.modal_impulse / (sys.mass * sys.omega_d) * kernel.imag
        return sys.forced_modal(t)[1] + v_imp

    def tip(self, t):
        """Tip displacement W(t) = psi_L u(t) (m)."""
        return self.system.psi_tip * self.modal_displacement(t)

    def ball_displacement(self, t):
        """Absolute ball displacement u_d(t) (m): straight flights between the walls."""
        sys = self.system
        sign, tau = self._split(t)
        u0 = float(self.modal_displacement(self.impact_time))
        return sign * (0.5 * sys.gap + sys.psi_ball * u0 - self.ball_speed * tau)

    def relative_displacement(self, t):
        """y(t) = u_d(t) - psi_d u(t) (m), in [-delta/2, delta/2] on an admissible orbit."""
        return self.ball_displacement(t) - self.system.psi_ball * self.modal_displacement(t)

    # --- summaries --------------------------------------------------------------
    def rms_tip(self) -> float:
        """RMS of W over one period (m), in closed form.

        On a half period u(tau) = sum_j c_j e^{s_j tau} with s_j in
        {i Omega, -i Omega, lambda, conj(lambda)}, so the mean square is
        (psi_L^2 / T_h) sum_jk c_j c_k (e^{(s_j + s_k) T_h} - 1) / (s_j + s_k);
        antisymmetry makes the other half period identical.
        """
        sys = self.system
        th = sys.half_period
        a = sys.psi_tip * sys.force * sys.receptance * np.exp(1j * self.phase)
        b = self.modal_impulse / (sys.mass * sys.omega_d * (1 + np.exp(sys.eigenvalue * th)))
        c = np.array([a, -np.conj(a), b, -np.conj(b)]) / 2j
        s = np.array([1j * sys.omega, -1j * sys.omega, sys.eigenvalue, np.conj(sys.eigenvalue)])
        sigma = s[:, None] + s[None, :]
        small = np.abs(sigma * th) < 1e-12
        integral = np.where(small, th, np.expm1(sigma * th) / np.where(small, 1.0, sigma))
        mean_square = (c[:, None] * c[None, :] * integral).sum().real / th
        return abs(sys.psi_tip) * math.sqrt(max(mean_square, 0.0))

    def tip_amplitude(self) -> float:
        """max |W| over the orbit (m): grid search over a half period, then refined."""
        th = self.system.half_period
        t = self.impact_time + np.linspace(0.0, th, FLIGHT_SAMPLES)
        w = np.abs(self.tip(t))
        i = int(np.argmax(w))
        lo, hi = t[max(i - 1, 0)], t[min(i + 1, len(t) - 1)]
        res = scipy.optimize.minimize_scalar(
            lambda x: -abs(float(self.tip(x))),
            bounds=(lo, hi),
            method="bounded",
            options={"xatol": 1e-12 * th},
        )
        return max(float(w[i]), -float(res.fun))


# --- the closed form ----------------------------------------------------------
def orbit_coefficients(system: ImpactSystem) -> tuple[float, float]:
    """(A_g, A_r): the geometry and restitution conditions, linear in V.

    Geometry V T_h = delta + 2 psi_d (u_F(t_0) + a0 P) with P = 2 m psi_d V:
    A_g V = delta + 2 psi_d u_F(t_0), A_g = T_h - 4 m psi_d^2 a0.
    Restitution (1 - e)(1 + mu psi_d^2) V = -(1 + e) psi_d (v_F(t_0) + b0 P):
    A_r V = -(1 + e) psi_d v_F(t_0), A_r = (1 - e)(1 + mu psi_d^2) + 2 (1 + e) m psi_d^2 b0.
    """
    sys = system
    a0, b0 = sys.impulse_train_constants()
    m_psi2 = sys.ball_mass * sys.psi_ball**2
    e = sys.restitution
    a_r = (1 - e) * (1 + sys.effective_ratio) + 2 * (1 + e) * m_psi2 * b0
    if abs(a_r) < 1e-300:
        raise ParameterError(
            "two_impact_orbit: the restitution condition is degenerate "
            "(A_r = 0); the ball speed is not determined"
        )
    return sys.half_period - 4.0 * m_psi2 * a0, a_r


def phase_equation(system: ImpactSystem) -> tuple[float, float, float]:
    """(a, b, c) of a cos phi + b sin phi = c, the orbit's phase equation.

    Eliminating V between the two conditions of :func:`orbit_coefficients`,
    with u_F(t_0) = q' (H_r sin phi + H_i cos phi), v_F(t_0) = q' Omega
    (H_r cos phi - H_i sin phi), q' = psi_L F0, q = q' psi_d and
    r = (1 + e) Omega A_g / A_r:

        a = -q (r H_r + 2 H_i),   b = -q (2 H_r - r H_i),   c = delta.
    """
    sys = system
    a_g, a_r = orbit_coefficients(sys)
    r = (1 + sys.restitution) * sys.omega * a_g / a_r
    q = sys.psi_tip * sys.force * sys.psi_ball
    h = sys.receptance
    return -q * (r * h.real + 2 * h.imag), -q * (2 * h.real - r * h.imag), sys.gap


def ball_speed(system: ImpactSystem, phase: float) -> float:
    """V (m/s) from the restitution condition, A_r V = -(1 + e) psi_d v_F(phi / Omega)."""
    sys = system
    _, a_r = orbit_coefficients(sys)
    v_f = sys.forced_modal(phase / sys.omega)[1]
    return float(-(1 + sys.restitution) * sys.psi_ball * v_f / a_r)


def two_impact_orbit(
    M: float,
    K: float,
    C: float,
    psi_L: float,
    psi_d: float,
    m: float,
    gap: float,
    e: float,
    F0: float,
    Omega: float,
) -> list[Orbit]:
    """Every symmetric two-impacts-per-period orbit, in closed form.

    Arguments as :class:`ImpactSystem` (M, K, C modal; m, gap in kg, m;
    F0 in N; Omega in rad/s).  Returns zero or two :class:`Orbit` objects
    (one if the two roots coincide), admissible or not, each with its
    stability; see the module docstring for the equations.
    """
    sys = ImpactSystem(M, K, C, psi_L, psi_d, m, gap, e, F0, Omega)
    a, b, c = phase_equation(sys)
    radius = math.hypot(a, b)
    if radius < c:
        return []
    base, half = math.atan2(b, a), math.acos(c / radius)
    phases = [base + half] if half == 0.0 else [base + half, base - half]
    return [_orbit(sys, phi % (2 * math.pi)) for phi in phases]


def _orbit(sys: ImpactSystem, phase: float) -> Orbit:
    v = ball_speed(sys, phase)
    p = 2 * sys.ball_mass * sys.psi_ball * v
    draft = Orbit(
        phase=phase,
        ball_speed=v,
        impulse=-2 * sys.ball_mass * v,
        bar_velocity_before=0.0,
        bar_velocity_after=0.0,
        admissible=False,
        message="",
        system=sys,
    )
    _, b0 = sys.impulse_train_constants()
    v_mean = sys.forced_modal(phase / sys.omega)[1] + b0 * p
    before, after = v_mean - 0.5 * p / sys.mass, v_mean + 0.5 * p / sys.mass
    message = _inadmissible(draft, before)
    multipliers = impact_map_multipliers(draft, after) if not message else ()
    stable = bool(np.all(np.abs(multipliers) < 1.0)) if not message else None
    return Orbit(
        phase=phase,
        ball_speed=v,
        impulse=-2 * sys.ball_mass * v,
        bar_velocity_before=sys.psi_ball * before,
        bar_velocity_after=sys.psi_ball * after,
        admissible=not message,
        message=message,
        system=sys,
        stable=stable,
        multipliers=tuple(multipliers),
    )


def _inadmissible(orbit: Orbit, modal_velocity_before: float) -> str:
    """Why ``orbit`` is not physical ('' if it is)."""
    sys = orbit.system
    if not orbit.ball_speed > 0.0:
        return f"ball speed V = {orbit.ball_speed:.6g} m/s is not positive"
    approach = orbit.ball_speed - sys.psi_ball * modal_velocity_before
    if not approach > 0.0:
        return f"the ball does not approach the + wall (y'- = {approach:.6g} m/s)"
    t = orbit.impact_time + np.linspace(0.0, sys.half_period, FLIGHT_SAMPLES)[1:-1]
    excess = np.max(np.abs(orbit.relative_displacement(t))) - 0.5 * sys.gap
    if excess > WALL_TOL * sys.gap:
        return f"the ball passes through a wall in flight (by {excess:.3g} m)"
    return ""


# --- stability: the linearised impact-to-impact map ---------------------------
def impact_map_multipliers(orbit: Orbit, modal_velocity_after: float) -> np.ndarray:
    """Eigenvalues of the impact-to-impact map linearised about the orbit.

    The state just after a + wall impact is (t, u, u', u_d') with u_d fixed
    by the wall.  The map flies the exact linear motion to the next wall
    contact (time by Newton on y = -delta/2), applies the impact law, and
    mirrors the state (u -> -u, time -> time - T_h), so that the orbit is a
    fixed point.  Its Jacobian is taken by central differences; a
    perturbation along the time-shift direction of the forcing is not
    neutral (the forcing fixes the phase), so all four multipliers count.
    """
    sys = orbit.system
    x0 = np.array(
        [
            orbit.impact_time,
            float(orbit.modal_displacement(orbit.impact_time)),
            modal_velocity_after,
            -orbit.ball_speed,
        ]
    )
    scales = np.array(
        [
            1.0 / sys.omega,
            abs(x0[1]) + sys.gap / abs(sys.psi_ball),
            abs(x0[2]) + sys.gap * sys.omega / abs(sys.psi_ball),
            orbit.ball_speed + sys.gap * sys.omega,
        ]
    )
    jac = np.empty((4, 4))
    h = 1e-6
    for j in range(4):
        dx = np.zeros(4)
        dx[j] = h * scales[j]
        jac[:, j] = (_half_map(sys, x0 + dx) - _half_map(sys, x0 - dx)) / (2 * dx[j])
    return np.linalg.eigvals(jac)


def _half_map(sys: ImpactSystem, state: np.ndarray) -> np.ndarray:
    """From just after a + wall impact to just after the next impact, mirrored."""
    t0, u0, v0, w0 = state
    ud0 = 0.5 * sys.gap + sys.psi_ball * u0

    def rel(t):
        u, v = _free_flight(sys, t0, u0, v0, t)
        return ud0 + w0 * (t - t0) - sys.psi_ball * u + 0.5 * sys.gap, w0 - sys.psi_ball * v

    t = t0 + sys.half_period
    for _ in range(50):
        y, dy = rel(t)
        step = y / dy
        t -= step
        if abs(step) < 1e-15 * sys.half_period:
            break
    u, v = _free_flight(sys, t0, u0, v0, t)
    approach = w0 - sys.psi_ball * v
    e, ratio = sys.restitution, sys.effective_ratio
    v_after = v + (1 + e) * (sys.ball_mass / sys.mass) * sys.psi_ball * approach / (1 + ratio)
    w_after = sys.psi_ball * v_after - e * approach
    return np.array([t - sys.half_period, -u, -v_after, -w_after])


def _free_flight(sys: ImpactSystem, t0: float, u0: float, v0: float, t: float):
    """Exact (u, u') at t of M u'' + C u' + K u = psi_L F0 sin(Omega t) from (u0, v0) at t0."""
    uf0, vf0 = sys.forced_modal(t0)
    uf, vf = sys.forced_modal(t)
    lam = sys.eigenvalue
    # homogeneous part: Re(z e^{lam s}) with z fixed by the initial deviation
    du, dv = u0 - uf0, v0 - vf0
    z = complex(du, -(dv - lam.real * du) / lam.imag)
    s = t - t0
    hom = z * np.exp(lam * s)
    return float(uf + hom.real), float(vf + (lam * hom).real)
