"""The bending stiffness of a bar's section through the ball's cavity: a round hole
across the bar, centred on its axis (docs/systems.md, ``[cavity]``), whose equivalent
round section a system file's cavity takes where it does not give one."""

from __future__ import annotations

import math

import numpy as np

from boringbar._validate import ParameterError

#: Gauss-Legendre nodes on each smooth piece of the integral along the cavity.
_GAUSS_NODES = 24


def _column_integral(radius: float, x: float) -> float:
    """The closed form of int_0^x (radius^2 - t^2)^(3/2) dt, 0 <= x <= radius."""
    x = min(x, radius)
    q = math.sqrt(max(radius * radius - x * x, 0.0))
    return (x * q**3 / 4 + 3 * radius**2 * x * q / 8
            + 3 * radius**4 / 8 * math.asin(x / radius))


def cut_section_moment(diameter: float, bore: float, half_width: float,
                       half_depth: float) -> float:
    """The second moment of area (m^4), about the bending axis, of a round section of
    ``diameter`` with a concentric ``bore`` (m), less the rectangle |x| < half_width,
    |y| < half_depth that a cavity cuts from it (y: the bending direction; docs/systems.md).

    I = int (2/3) (Y^3 - m^3) dx over the section's width, Y = sqrt(R^2 - x^2) the
    solid half-height and m(x) = min(Y, max(half_depth if |x| < half_width, the bore's
    half-chord)) the removed one, in closed form between the points where m changes
    branch."""
    big, small, h, c = diameter / 2, bore / 2, half_depth, half_width
    breaks = {0.0, big, min(c, big), min(small, big)}
    breaks |= {math.sqrt(r * r - h * h) for r in (small, big) if r > h}
    points = sorted(b for b in breaks if b <= big)
    removed = 0.0
    for x0, x1 in zip(points, points[1:], strict=False):
        xm = 0.5 * (x0 + x1)
        cut = h if xm < c else 0.0
        chord = math.sqrt(small * small - xm * xm) if xm < small else 0.0
        if cut >= math.sqrt(big * big - xm * xm):
            removed += _column_integral(big, x1) - _column_integral(big, x0)
        elif cut >= chord:
            removed += cut**3 * (x1 - x0)
        else:
            removed += _column_integral(small, x1) - _column_integral(small, x0)
    return 4.0 / 3.0 * (_column_integral(big, big) - removed)


def cavity_section_diameter(diameter: float, bore: float, length: float,
                            depth: float, across: bool = False) -> float:
    """The outer diameter (m) of the equivalent section, with the host's ``bore``, that
    has the bending stiffness of the host section (``diameter``, ``bore``, m) through a
    cavity: a round hole of diameter ``length`` (its length along the bar) across
    the bar in the ball's direction of travel, ``depth`` (m) deep, centred on the bar's
    axis (docs/systems.md).

    At a distance s from the cavity's centre the hole cuts a strip of half-width
    c(s) = sqrt(a^2 - s^2), a = length / 2 (:func:`cut_section_moment` gives I(s)); a
    segment under a bending moment that changes little along it bends as one of
    constant I_eq = L / int ds / I(s) (its flexibility), here integrated with
    s = a sin(theta) by Gauss-Legendre on the pieces where I(s) is smooth.  Then
    pi (D^4 - bore^4) / 64 = I_eq.  ``across``: bending across the ball's direction, the
    same strip's moment about the other axis (half-width and half-depth exchanged),
    on pieces split eightfold (its kinks lie elsewhere: 1e-9 against adaptive
    quadrature on the published cavity)."""
    a = length / 2
    if a >= diameter / 2:
        raise ParameterError(f"length = {length:g} m must be less than the section's "
                             f"diameter {diameter:g} m: a round cavity this wide cuts "
                             "the section in two")
    r, h = diameter / 2, depth / 2
    kinks = [b for b in (bore / 2, math.sqrt(max((bore / 2) ** 2 - h * h, 0.0)),
                         math.sqrt(max(r * r - h * h, 0.0))) if 0.0 < b < a]
    edges = sorted({0.0, math.pi / 2, *(math.acos(b / a) for b in kinks)})
    if across:
        edges = sorted({t0 + (t1 - t0) * k / 8 for t0, t1 in zip(edges, edges[1:],
                                                                 strict=False)
                        for k in range(9)})
    nodes, weights = np.polynomial.legendre.leggauss(_GAUSS_NODES)
    flexibility = 0.0  # int_0^(pi/2) cos(theta) / I(a cos(theta)) d theta = 1 / I_eq
    for t0, t1 in zip(edges, edges[1:], strict=False):
        for x, w in zip(nodes, weights, strict=True):
            t = 0.5 * (t1 - t0) * x + 0.5 * (t0 + t1)
            c = a * math.cos(t)
            moment = (cut_section_moment(diameter, bore, h, c) if across
                      else cut_section_moment(diameter, bore, c, h))
            flexibility += 0.5 * (t1 - t0) * w * math.cos(t) / moment
    # never above the host's own diameter, which a hole inside the bore leaves
    return min(float((64.0 / math.pi / flexibility + bore**4) ** 0.25), diameter)
