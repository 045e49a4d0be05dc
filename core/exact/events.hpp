// The exact kernel's event functions and their roots: Hermite starts, the safeguarded
// Newton search (find_root), W extrema, the ranges that rule steps out and a free ball's
// wall step (wall_step).
//
// Each event function reads the segment's closed form through a SegView (the segment, its
// regime and start, the run's eigen-data, the model's rows, the forcing and the scratch it
// evaluates into):
//   double g_value(idx kind, double tau, const SegView& s);          // g
//   std::tuple<double, double> ball_rates(const Segment& seg, double tau, Mat mk, Vec X,
//                                         Vec Xd, idx n);           // y', y''
//   std::tuple<double, double, double> _gd(idx kind, double tau, const SegView& s);
//                                                                    // g, g', g'' (or NaN)
//   double hermite(double a, double b, double p0, double p1, double d0, double d1,
//                  idx order);
//   double hermite5(double a, double b, Jet f0, Jet f1, idx order);
//   double find_root(idx kind, double a, double ga, double b, double gb, const SegView& s,
//                    double c0);
//   double find_root_1 / find_root_2 (the same, n = 1 or 2 modes in conjugate pairs);
//   double find_root_any(the same: the copy with constant sizes where they fit);
//   double w_extremum(double a, double ga, double b, double gb, double c0, double h,
//                     const SegView& s);   // and w_extremum_1, _2, _any as find_root's
//   std::tuple<double, double> quad_range(double p, double d, double dd, double s);
//   constexpr int NSUB = 16;
//   bool may_graze(double a, double b, Vec ev_a, Vec ev_b, double half, double b4);
//   bool w_may_exceed(double h, TipW wa, TipW wb, double bw4, double max_w, double min_w,
//                     double max_abs_w);
//   struct StepEnds                 a step [a, b], its level, the event functions and y''
//                                   at its ends
//   std::tuple<idx, double> wall_step(StepEnds st, bool watch_v, bool watch_ext,
//                     const SegView& s);
//
// X, Xd are seen with their own length by g_value, _gd and state_at: give views of length
// nz.  The _1 / _2 copies are the same operations with the sizes as constants, which the
// compiler specialises.
#pragma once

#include <cmath>
#include <initializer_list>
#include <limits>
#include <tuple>

#include "../arrays.hpp"
#include "consts.hpp"
#include "nmath.hpp"
#include "propagate.hpp"

namespace bb::exact {

// Event function ``kind`` at tau on the segment described by ``seg``.
inline double g_value(idx kind, double tau, const SegView& s) {
    [[maybe_unused]] const auto& [seg, r, q0, cf, ks, q, X, Xd, n, mk, f0, om] = s;
    state_at(s, tau, q, X);
    if (kind == EV_WEXT) return psi_dot(mk, MK_PSI_L, X, n).second;  // W'
    if (kind == EV_CUT || kind == EV_HEXT) {
        auto [w, wd] = psi_dot(mk, MK_PSI_L, X, n);
        auto [sv, sd] = surface_at(seg, tau);
        return kind == EV_CUT ? seg.cdir * (w - sv) : sd - wd;
    }
    if (kind <= EV_YEXT || kind == EV_SLIP) {
        auto [pdu, pdv] = psi_dot(mk, MK_PSI_D, X, n);
        if (kind == EV_PLUS || kind == EV_MINUS) {
            double y = ball_y(seg, tau, pdu);
            return kind == EV_PLUS ? y - seg.half : -seg.half - y;
        }
        double yd = ball_yd(seg, tau, pdv);
        if (kind == EV_SLIP) return -seg.slip * (yd - (seg.s0 + seg.sd * tau));
        return kind == EV_VSTOP ? -seg.sdir * yd : yd;
    }
    double F = freq_rhs(X, cut_force(seg, tau, X, n, mk, f0, om), n, mk, seg.kappa) - seg.foff;
    if (kind == EV_REL_NEG) return F - seg.fs;
    if (kind == EV_REL_POS) return -F - seg.fs;
    return seg.wall * F - seg.fs;
}

// The ball's y' and y'' at tau from the modes' velocity rows of X and X' (psi_d . u',
// psi_d . u'').
inline std::tuple<double, double> ball_rates(const Segment& seg, double tau, Mat mk, Vec X,
                                             Vec Xd, idx n) {
    double pdv = 0.0;
    double pda = 0.0;
    for (idx i = 0; i < n; ++i) {
        pdv += mk(MK_PSI_D, i) * X[n + i];
        pda += mk(MK_PSI_D, i) * Xd[n + i];
    }
    return {ball_yd(seg, tau, pdv), seg.acc - seg.cy * pda};
}

// Event function ``kind``, its time derivative and its second derivative at tau: the
// second only where it comes free (the walls and the cut's h), NaN elsewhere.
inline std::tuple<double, double, double> _gd(idx kind, double tau, const SegView& s) {
    [[maybe_unused]] const auto& [seg, r, q0, cf, ks, q, X, Xd, n, mk, f0, om] = s;
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    double ts = seg.ts;
    if (kind == EV_VSTOP || kind == EV_YEXT || kind == EV_SLIP) {
        // y' and y'' alone: the modes' velocity rows
        state_at2(s, tau, Rows{n, 2 * n});
        auto [yd, ydd] = ball_rates(seg, tau, mk, X, Xd, n);
        if (kind == EV_SLIP)
            return {-seg.slip * (yd - (seg.s0 + seg.sd * tau)), -seg.slip * (ydd - seg.sd), nan};
        if (kind == EV_VSTOP) return {-seg.sdir * yd, -seg.sdir * ydd, nan};
        return {yd, ydd, nan};
    }
    state_at2(s, tau);
    if (kind == EV_WEXT) {
        double g = 0.0;
        double dg = 0.0;
        for (idx i = 0; i < n; ++i) {
            g += mk(MK_PSI_L, i) * X[n + i];
            dg += mk(MK_PSI_L, i) * Xd[n + i];
        }
        return {g, dg, nan};
    }
    if (kind == EV_CUT || kind == EV_HEXT) {
        double w = 0.0;
        double wd = 0.0;
        double wdd = 0.0;
        for (idx i = 0; i < n; ++i) {
            w += mk(MK_PSI_L, i) * X[i];
            wd += mk(MK_PSI_L, i) * X[n + i];
            wdd += mk(MK_PSI_L, i) * Xd[n + i];
        }
        auto [sv, sd] = surface_at(seg, tau);
        double sdd = 2.0 * seg.s[2] + 6.0 * seg.s[3] * tau;
        if (kind == EV_CUT)
            return {seg.cdir * (w - sv), seg.cdir * (wd - sd), seg.cdir * (wdd - sdd)};
        return {sd - wd, sdd - wdd, nan};
    }
    if (kind == EV_PLUS || kind == EV_MINUS) {
        double y = ball_y(seg, tau, psi_dot(mk, MK_PSI_D, X, n).first);
        auto [yd, ydd] = ball_rates(seg, tau, mk, X, Xd, n);
        if (kind == EV_PLUS) return {y - seg.half, yd, ydd};
        return {-seg.half - y, -yd, -ydd};  // EV_MINUS
    }
    double t = ts + tau;
    double f = f0 * std::sin(om * t);
    double fd = f0 * om * std::cos(om * t);
    if (seg.krb != 0.0) {
        auto [w, wd] = psi_dot(mk, MK_PSI_L, X, n);
        auto [sv, sd] = surface_at(seg, tau);
        f += seg.krb * (sv - w);
        fd += seg.krb * (sd - wd);
    }
    double F = 0.0;
    double Fd = 0.0;
    for (idx i = 0; i < n; ++i) {
        const double fm = mk(MK_FM, i), km = mk(MK_KM, i), cm = mk(MK_CM, i);
        F += mk(MK_PSI_D, i) * dynamics::free_acceleration(fm, km, cm, f, X[i], X[n + i]);
        Fd += mk(MK_PSI_D, i) * dynamics::free_acceleration(fm, km, cm, fd, X[n + i], Xd[n + i]);
    }
    F = F / seg.kappa - seg.foff;
    Fd /= seg.kappa;
    if (kind == EV_REL_NEG) return {F - seg.fs, Fd, nan};
    if (kind == EV_REL_POS) return {-F - seg.fs, -Fd, nan};
    return {seg.wall * F - seg.fs, seg.wall * Fd, nan};
}

// Where the cubic Hermite interpolant of values p0, p1 and slopes d0, d1 on [a, b]
// (order 0), or its derivative (order 1), changes sign: a few safeguarded Newton steps on
// the cubic (a starting point for find_root).
inline double hermite(double a, double b, double p0, double p1, double d0, double d1,
                      idx order) {
    double h = b - a;
    double m0 = d0 * h;
    double m1 = d1 * h;
    double lo = 0.0;
    double hi = 1.0;
    double flo, x;
    if (order == 0) {
        flo = p0;
        x = p0 != p1 ? p0 / (p0 - p1) : 0.5;
    } else {
        flo = m0;
        x = m0 != m1 ? m0 / (m0 - m1) : 0.5;
    }
    for (int it = 0; it < 8; ++it) {
        if (!(lo < x && x < hi)) x = 0.5 * (lo + hi);
        double s2 = x * x;
        double f, df;
        if (order == 0) {
            f = ((2.0 * s2 * x - 3.0 * s2 + 1.0) * p0 + (s2 * x - 2.0 * s2 + x) * m0 +
                 (-2.0 * s2 * x + 3.0 * s2) * p1 + (s2 * x - s2) * m1);
            df = ((6.0 * s2 - 6.0 * x) * p0 + (3.0 * s2 - 4.0 * x + 1.0) * m0 +
                  (-6.0 * s2 + 6.0 * x) * p1 + (3.0 * s2 - 2.0 * x) * m1);
        } else {
            f = ((6.0 * s2 - 6.0 * x) * p0 + (3.0 * s2 - 4.0 * x + 1.0) * m0 +
                 (-6.0 * s2 + 6.0 * x) * p1 + (3.0 * s2 - 2.0 * x) * m1);
            df = ((12.0 * x - 6.0) * p0 + (6.0 * x - 4.0) * m0 + (-12.0 * x + 6.0) * p1 +
                  (6.0 * x - 2.0) * m1);
        }
        if ((f > 0.0) == (flo > 0.0))
            lo = x;
        else
            hi = x;
        double xn = df != 0.0 ? x - f / df : 0.5 * (lo + hi);
        if (std::fabs(xn - x) <= 1e-13) {  // converged (the cubic is only a starting point)
            x = xn;
            break;
        }
        x = xn;
    }
    if (!(0.0 < x && x < 1.0)) x = 0.5 * (lo + hi);
    return a + x * h;
}

// A function's value and its first two derivatives at a point.
struct Jet {
    double v, d, dd;
};

// Where the quintic Hermite interpolant on [a, b] of the values, slopes and second
// derivatives f0 (at a) and f1 (at b) (order 0), or its derivative (order 1), changes sign:
// the cubic's start refined by safeguarded Newton on the quintic.
inline double hermite5(double a, double b, Jet f0, Jet f1, idx order) {
    const double p0 = f0.v, p1 = f1.v, d0 = f0.d, d1 = f1.d, e0 = f0.dd, e1 = f1.dd;
    double x0 = hermite(a, b, p0, p1, d0, d1, order);
    double h = b - a;
    double m0 = d0 * h;
    double m1 = d1 * h;
    double k0 = e0 * h * h;
    double k1 = e1 * h * h;
    // p(x) = p0 + m0 x + k0 x^2 / 2 + c3 x^3 + c4 x^4 + c5 x^5 on [0, 1]
    double c3 = -10.0 * p0 - 6.0 * m0 - 1.5 * k0 + 0.5 * k1 - 4.0 * m1 + 10.0 * p1;
    double c4 = 15.0 * p0 + 8.0 * m0 + 1.5 * k0 - k1 + 7.0 * m1 - 15.0 * p1;
    double c5 = -6.0 * p0 - 3.0 * m0 - 0.5 * k0 + 0.5 * k1 - 3.0 * m1 + 6.0 * p1;
    double flo = order == 0 ? p0 : m0;
    double lo = 0.0;
    double hi = 1.0;
    double x = (x0 - a) / h;
    for (int it = 0; it < 6; ++it) {
        if (!(lo < x && x < hi)) x = 0.5 * (lo + hi);
        double dp = m0 + x * (k0 + x * (3.0 * c3 + x * (4.0 * c4 + x * 5.0 * c5)));
        double f, df;
        if (order == 0) {
            f = p0 + x * (m0 + x * (0.5 * k0 + x * (c3 + x * (c4 + x * c5))));
            df = dp;
        } else {
            f = dp;
            df = k0 + x * (6.0 * c3 + x * (12.0 * c4 + x * 20.0 * c5));
        }
        if ((f > 0.0) == (flo > 0.0))
            lo = x;
        else
            hi = x;
        double xn = df != 0.0 ? x - f / df : 0.5 * (lo + hi);
        if (std::fabs(xn - x) <= 1e-15) {
            x = xn;
            break;
        }
        x = xn;
    }
    if (!(0.0 < x && x < 1.0)) return x0;
    return a + x * h;
}

// The root of event function ``kind`` in [a, b], where it changes sign (or ga = 0): Newton
// with the exact derivative, kept inside the shrinking bracket, to a bracket of 4 ulp of t
// Returns the end on gb's side.  X and Xd are seen with length
// nz.
inline double _root_body(idx kind, double a, double ga, double b, double gb,
                         const SegView& s, double c0, idx nz) {
    SegView sn = s;
    sn.X = Vec{s.X.d, nz};
    sn.Xd = Vec{s.Xd.d, nz};
    double ts = s.seg.ts;
    bool pos = gb > 0.0;
    double c = c0;
    if (!(a < c && c < b)) c = gb != ga ? (a * gb - b * ga) / (gb - ga) : 0.5 * (a + b);
    double w_ref = b - a;
    int slow = 0;
    for (int it = 0; it < 100; ++it) {
        double tol = 4.4e-16 * (std::fabs(ts) + std::fabs(b)) + 1e-300;
        if (b - a <= tol) break;
        if (slow >= 3 || !(a < c && c < b)) {
            c = 0.5 * (a + b);
            slow = 0;
            if (!(a < c && c < b)) break;
        }
        auto [g, dg, ddg] = _gd(kind, c, sn);
        if (g == 0.0) return c;
        if ((g > 0.0) == pos)
            b = c;
        else
            a = c;
        if (b - a <= 0.5 * w_ref) {
            w_ref = b - a;
            slow = 0;
        } else {
            slow += 1;
        }
        double cn = 0.5 * (a + b);
        if (dg != 0.0) {
            cn = c - g / dg;
            if (std::fabs(cn - c) <= tol && a <= cn && cn <= b)
                return pos == (g > 0.0) ? b : pymin(b, cn + tol);
            // the root is within |g''| s^2 / (2 |g'|) < tol / 4 of cn (NaN: not known)
            double s_ = cn - c;
            if (a <= cn && cn <= b && std::fabs(ddg) * s_ * s_ <= 0.5 * tol * std::fabs(dg))
                return pymin(b, cn + tol);
        }
        c = cn;
    }
    return b;
}

// _root_body for any bar.
inline double find_root(idx kind, double a, double ga, double b, double gb, const SegView& s,
                        double c0) {
    return _root_body(kind, a, ga, b, gb, s, c0, s.X.n);
}

// The copies with constant sizes are flattened (everything they call inlined into them,
// _root_body and state_at among them): only then does the compiler see the sizes as the
// constants they are; a call to the shared _root_body kept its loops generic
// (BB_FLATTEN, compiler.hpp).

// _root_body for one mode and its conjugate pair (n = 1, nz = 2, ks = 2).
BB_FLATTEN inline double find_root_1(idx kind, double a, double ga, double b, double gb,
                                     const SegView& s, double c0) {
    return _root_body(kind, a, ga, b, gb, s.with_sizes(2, 1), c0, 2);
}

// _root_body for two modes in conjugate pairs (n = 2, nz = 4, ks = 2).
BB_FLATTEN inline double find_root_2(idx kind, double a, double ga, double b, double gb,
                                     const SegView& s, double c0) {
    return _root_body(kind, a, ga, b, gb, s.with_sizes(2, 2), c0, 4);
}

// find_root, or its copy with the sizes constant where they fit (see const_sizes).
inline double find_root_any(idx kind, double a, double ga, double b, double gb,
                            const SegView& s, double c0) {
    idx sz = const_sizes(s.ks, s.n, s.X.n);
    if (sz == 1) return find_root_1(kind, a, ga, b, gb, s, c0);
    if (sz == 2) return find_root_2(kind, a, ga, b, gb, s, c0);
    return find_root(kind, a, ga, b, gb, s, c0);
}

// W at its extremum in [a, b], where W' changes sign (ga, gb: W' at a, b): Newton on W'
// from c0 inside the shrinking bracket until the step is below 2e-5 h, then W plus the
// step's quadratic correction.
inline double _w_extremum_body(double a, double ga, double b, double gb, double c0, double h,
                               const SegView& s, idx nz) {
    (void)ga;
    [[maybe_unused]] const auto& [seg, r, q0, cf, ks, q, X, Xd, n, mk, f0, om] = s;
    Vec Xn{X.d, nz};
    Vec Xdn{Xd.d, nz};
    SegView sn = s;
    sn.X = Xn;
    sn.Xd = Xdn;
    bool pos = gb > 0.0;
    double c = (a < c0 && c0 < b) ? c0 : 0.5 * (a + b);
    double tol = 2e-5 * h;
    double w = 0.0;
    for (int it = 0; it < 100; ++it) {
        state_at2(sn, c);
        w = 0.0;
        double wd = 0.0;
        double wdd = 0.0;
        for (idx i = 0; i < n; ++i) {
            w += mk(MK_PSI_L, i) * Xn[i];
            wd += mk(MK_PSI_L, i) * Xn[n + i];
            wdd += mk(MK_PSI_L, i) * Xdn[n + i];
        }
        if (wd == 0.0) return w;
        double step = wdd != 0.0 ? -wd / wdd : b - a;
        if (std::fabs(step) <= tol) return w + 0.5 * wd * step;
        if ((wd > 0.0) == pos)
            b = c;
        else
            a = c;
        if (b - a <= tol) return w;
        double cn = c + step;
        c = (a < cn && cn < b) ? cn : 0.5 * (a + b);
    }
    return w;
}

// _w_extremum_body for any bar.
inline double w_extremum(double a, double ga, double b, double gb, double c0, double h,
                         const SegView& s) {
    return _w_extremum_body(a, ga, b, gb, c0, h, s, s.X.n);
}

// _w_extremum_body for n = 1, nz = 2, ks = 2.
BB_FLATTEN inline double w_extremum_1(double a, double ga, double b, double gb, double c0,
                                      double h, const SegView& s) {
    return _w_extremum_body(a, ga, b, gb, c0, h, s.with_sizes(2, 1), 2);
}

// _w_extremum_body for n = 2, nz = 4, ks = 2.
BB_FLATTEN inline double w_extremum_2(double a, double ga, double b, double gb, double c0,
                                      double h, const SegView& s) {
    return _w_extremum_body(a, ga, b, gb, c0, h, s.with_sizes(2, 2), 4);
}

// w_extremum, or its copy with the sizes constant (see find_root_any).
inline double w_extremum_any(double a, double ga, double b, double gb, double c0, double h,
                             const SegView& s) {
    idx sz = const_sizes(s.ks, s.n, s.X.n);
    if (sz == 1) return w_extremum_1(a, ga, b, gb, c0, h, s);
    if (sz == 2) return w_extremum_2(a, ga, b, gb, c0, h, s);
    return w_extremum(a, ga, b, gb, c0, h, s);
}

// (lowest, highest) value of p + d x + dd x^2 / 2 on [0, s].
inline std::tuple<double, double> quad_range(double p, double d, double dd, double s) {
    double p1 = p + s * (d + 0.5 * dd * s);
    double lo = pymin(p, p1);
    double hi = pymax(p, p1);
    if (dd != 0.0) {
        double x = -d / dd;
        if (0.0 < x && x < s) {
            double v = p + 0.5 * d * x;
            lo = pymin(lo, v);
            hi = pymax(hi, v);
        }
    }
    return {lo, hi};
}

// sub-steps of a grid step in which the bound on y^(4) allows an undetected graze
constexpr int NSUB = 16;

// (lowest, highest) value on (0, 1] of the cubic Hermite interpolant of values p0, p1 and
// slopes m0, m1 (per unit of s): the end s = 1 and the interior zeros of its derivative.
inline std::tuple<double, double> _cubic_range(double p0, double p1, double m0, double m1) {
    double hi = p1;
    double lo = p1;
    // p'(s) = qa s^2 + qb s + qc on (0, 1)
    double qa = 6.0 * p0 + 3.0 * m0 - 6.0 * p1 + 3.0 * m1;
    double qb = -6.0 * p0 - 4.0 * m0 + 6.0 * p1 - 2.0 * m1;
    double qc = m0;
    double r0 = -1.0;
    double r1 = -1.0;
    if (std::fabs(qa) > 1e-300) {
        double disc = qb * qb - 4.0 * qa * qc;
        if (disc >= 0.0) {
            double sq = std::sqrt(disc);
            r0 = (-qb - sq) / (2.0 * qa);
            r1 = (-qb + sq) / (2.0 * qa);
        }
    } else if (std::fabs(qb) > 1e-300) {
        r0 = -qc / qb;
    }
    for (double x : {r0, r1}) {
        if (0.0 < x && x < 1.0) {
            double s2 = x * x;
            double v = ((2.0 * s2 * x - 3.0 * s2 + 1.0) * p0 + (s2 * x - 2.0 * s2 + x) * m0 +
                        (-2.0 * s2 * x + 3.0 * s2) * p1 + (s2 * x - s2) * m1);
            hi = pymax(hi, v);
            lo = pymin(lo, v);
        }
    }
    return {lo, hi};
}

// Whether y may reach a wall inside [a, b]: the cubic Hermite interpolant of y from y, y'
// at the ends, widened by twice its error bound b4 h^4 / 384, comes within reach of a wall.
inline bool may_graze(double a, double b, Vec ev_a, Vec ev_b, double half, double b4) {
    double h = b - a;
    double p0 = ev_a[EV_PLUS] + half;
    double p1 = ev_b[EV_PLUS] + half;
    double m0 = ev_a[EV_YEXT] * h;
    double m1 = ev_b[EV_YEXT] * h;
    double margin = b4 * ipow(h, 4) / 192.0;
    // |p| <= max(|p0|, |p1|) + 4/27 (|m0| + |m1|) on [0, 1]: far from both walls, done
    if (pymax(std::fabs(p0), std::fabs(p1)) + 0.15 * (std::fabs(m0) + std::fabs(m1)) +
            margin < half)
        return false;
    auto [lo, hi] = _cubic_range(p0, p1, m0, m1);
    return hi + margin >= half || lo - margin <= -half;
}

// The segment's running extremes, kept in locals (registers) during the search
struct Extremes {
    double max_abs_w, max_w, min_w, max_aux, max_aux_all, max_force;
};

// W, W' and W'' at a grid point (W'' NaN where not evaluated).
struct TipW {
    double w, wd, wdd;
};

// Whether W may go above max_w, below min_w or beyond max_abs_w in magnitude inside a step
// of length h from wa to wb (the cubic Hermite of W, W' widened by twice its error bound,
// bw4 bounding |W^(4)|).  The extremes come as values: the search keeps its own in
// registers.
inline bool w_may_exceed(double h, TipW wa, TipW wb, double bw4, double max_w, double min_w,
                         double max_abs_w) {
    double margin = bw4 * ipow(h, 4) / 192.0;
    auto [lo, hi] = _cubic_range(wa.w, wb.w, wa.wd * h, wb.wd * h);
    hi += margin;
    lo -= margin;
    return hi >= max_w || lo <= min_w || pymax(hi, -lo) >= max_abs_w;
}

// A step [a, b] of a segment (times from its start, length h 2^lev) and what is known at
// its ends: the event functions and a free ball's y'' (NaN: not known).  Passed by value.
struct StepEnds {
    double a, b;
    idx lev;
    Vec ev_a, ev_b;
    double ydd_a, ydd_b;
};

// The first wall or friction-switch event of a FREE ball in the step st, from the event
// functions at its ends and y'' there: (kind, time), kind -1 if none.  watch_v: the y' = 0
// switch of a sliding ball is an event; watch_ext: an extremum of y that may reach a wall
// is looked for.
inline std::tuple<idx, double> wall_step(StepEnds st, bool watch_v, bool watch_ext,
                                         const SegView& s) {
    const double a = st.a, b = st.b, ydd_a = st.ydd_a, ydd_b = st.ydd_b;
    const Vec ev_a = st.ev_a, ev_b = st.ev_b;
    const double half = s.seg.half;
    double best = b;
    idx kind = -1;
    double lo = a;
    double hi = b;
    const idx walls[2] = {EV_PLUS, EV_MINUS};
    // without friction, split the step at an extremum of y, if the extremum can reach a
    // wall: y' changes sign inside, so |y'| <= |y'(a)| + |y'(b)| there to first order
    bool near = false;
    if (watch_ext && ev_a[EV_YEXT] * ev_b[EV_YEXT] < 0.0) {
        double reach = (b - a) * (std::fabs(ev_a[EV_YEXT]) + std::fabs(ev_b[EV_YEXT]));
        double dmin = -pymax(ev_a[EV_PLUS], ev_a[EV_MINUS], ev_b[EV_PLUS], ev_b[EV_MINUS]);
        near = dmin <= reach;
    }
    if (near) {
        double te = find_root_any(EV_YEXT, a, ev_a[EV_YEXT], b, ev_b[EV_YEXT], s,
                                  hermite(a, b, ev_a[EV_PLUS], ev_b[EV_PLUS], ev_a[EV_YEXT],
                                          ev_b[EV_YEXT], 1));
        double gp = g_value(EV_PLUS, te, s);
        double gm = -2.0 * half - gp;
        for (idx kk : walls) {
            double ge = kk == EV_PLUS ? gp : gm;
            if (ev_a[kk] <= 0.0 && 0.0 < ge) {
                double sg = kk == EV_PLUS ? 1.0 : -1.0;
                double tr = find_root_any(kk, a, ev_a[kk], te, ge, s,
                                          hermite(a, te, ev_a[kk], ge, sg * ev_a[EV_YEXT],
                                                  0.0, 0));
                if (kind < 0 || tr < best) {
                    best = tr;
                    kind = kk;
                }
            }
        }
        if (kind < 0) {
            for (idx kk : walls) {
                double ge = kk == EV_PLUS ? gp : gm;
                if (ge <= 0.0 && 0.0 < ev_b[kk]) {
                    double sg = kk == EV_PLUS ? 1.0 : -1.0;
                    double tr = find_root_any(kk, te, ge, b, ev_b[kk], s,
                                              hermite(te, b, ge, ev_b[kk], 0.0,
                                                      sg * ev_b[EV_YEXT], 0));
                    if (kind < 0 || tr < best) {
                        best = tr;
                        kind = kk;
                    }
                }
            }
        }
        lo = hi;  // handled
    }
    if (lo < hi) {
        // with friction, y is monotone only up to the y' = 0 switch: if the switch falls in
        // this step, look for the walls on [a, switch] only
        double bend = b;
        double gpe = ev_b[EV_PLUS];
        double gme = ev_b[EV_MINUS];
        double yde = ev_b[EV_YEXT];
        if (watch_v && ev_a[EV_VSTOP] <= 0.0 && 0.0 < ev_b[EV_VSTOP]) {
            best = find_root_any(EV_VSTOP, a, ev_a[EV_VSTOP], b, ev_b[EV_VSTOP], s, -1.0);
            kind = EV_VSTOP;
            bend = best;
            gpe = g_value(EV_PLUS, bend, s);
            gme = -2.0 * half - gpe;
            yde = 0.0;
        }
        for (idx kk : walls) {
            double ge = kk == EV_PLUS ? gpe : gme;
            if (ev_a[kk] <= 0.0 && 0.0 < ge) {
                double sg = kk == EV_PLUS ? 1.0 : -1.0;
                double c0;
                if (bend == b && ydd_a == ydd_a && ydd_b == ydd_b)  // y'' known at both ends
                    c0 = hermite5(a, b, Jet{ev_a[kk], sg * ev_a[EV_YEXT], sg * ydd_a},
                                  Jet{ge, sg * yde, sg * ydd_b}, 0);
                else
                    c0 = hermite(a, bend, ev_a[kk], ge, sg * ev_a[EV_YEXT], sg * yde, 0);
                double tr = find_root_any(kk, a, ev_a[kk], bend, ge, s, c0);
                if (kind < 0 || tr <= best) {
                    best = tr;
                    kind = kk;
                }
            }
        }
    }
    return {kind, best};
}

}  // namespace bb::exact
