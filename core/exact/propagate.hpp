// The closed form on a segment: the state at any time (state_at) and the forces, with
// complex arithmetic on ncplx (nmath.hpp) so that the rounding is this file's and not the
// compiler's; the segment's integrals are flows.hpp's.
//
// The closed form reads the segment through a SegView (the segment, its regime and start,
// the regimes' matrices, the sizes, the bar's rows, the forcing and the scratch):
//   ncplx state_at(const SegView& s, double tau, CVec q, Vec X);   // returns e^{i Omega t}
//   void state_at2(const SegView& s, double tau, Rows rows = {});   // s.X and s.Xd
//   void from_q(const ClosedForm& cf, idx r, idx ks, CVec q, ncplx ph, double fb, Vec X);
//   double cut_force(const Segment& seg, double tau, Vec X, idx n, Mat mk, double f0,
//                    double om);
//   double freq_rhs(Vec X, double f, idx n, Mat mk, double kappa);
// and the helpers nq, phis, surface_at, const_sizes.
//
// X, Xd are seen with their own length (X.n): pass views of length nz.
#pragma once

#include <cmath>
#include <tuple>
#include <utility>

#include "../arrays.hpp"
#include "consts.hpp"
#include "nmath.hpp"

namespace bb::exact {

// full unrolling of segment_integrals' short loops (the constant sizes): the same operations
#define BB_UNROLL _Pragma("GCC unroll 8")

// How many eigen-coordinates are evaluated: nz, or nz / 2 when ks = 2 (conjugate pairs,
// the first of each).
inline idx nq(idx nz, idx ks) { return ks == 1 ? nz : nz >> 1; }

// (e^x, phi_1(x), .., phi_4(x)), phi_k(x) = sum_m x^m / (m + k)!: the Taylor series of phi_4
// then phi_k = 1/k! + x phi_{k+1} for |x| < 1, the recurrence phi_{k+1} = (phi_k - 1/k!) / x
// from e^x otherwise.
inline std::tuple<ncplx, ncplx, ncplx, ncplx, ncplx> phis(ncplx x) {
    if (x.re * x.re + x.im * x.im < 1.0) {
        ncplx p4(0.0, 0.0);
        for (int m = 14; m >= 0; --m) p4 = p4 * x + RFACT[m + 4];
        ncplx p3 = 1.0 / 6.0 + x * p4;
        ncplx p2 = 0.5 + x * p3;
        ncplx p1 = 1.0 + x * p2;
        return {1.0 + x * p1, p1, p2, p3, p4};
    }
    ncplx ex = cexp(x);
    ncplx p1 = (ex - 1.0) / x;
    ncplx p2 = (p1 - 1.0) / x;
    ncplx p3 = (p2 - 0.5) / x;
    return {ex, p1, p2, p3, (p3 - 1.0 / 6.0) / x};
}

// S(tau) and S'(tau): the cut surface's cubic on the segment.
inline std::tuple<double, double> surface_at(const Segment& seg, double tau) {
    double s1 = seg.s[1];
    double s2 = seg.s[2];
    double s3 = seg.s[3];
    return {seg.s[0] + tau * (s1 + tau * (s2 + tau * s3)),
            s1 + tau * (2.0 * s2 + 3.0 * tau * s3)};
}

// The regimes' closed form: prepare's matrices, each indexed by the regime r first.
struct ClosedForm {
    CMat lam;  // (R, nz) the eigenvalues
    CArr3 V;   // (R, nz, nz) the eigenvectors, halved where a conjugate pair is evaluated once
               // (prepare's Vh)
    CMat Z;    // (R, nz) the forced response to F0 e^{i Omega t}: X_p = Im(Z e^{i Omega t})
    Mat D;     // (R, nz) the response to a unit friction force on the ball
    CMat bq;   // (R, nz) a cut's input Kr b S(t) in eigen-coordinates (per unit of Kr b S)
};

// The bar's dashpots: row d of l gives the velocity dashpot d acts on (l_d . X), c[d] its
// constant; the power they dissipate is sum_d c_d (l_d . X)^2.
struct Dashpots {
    Mat l;
    Vec c;
};

// A segment's closed form as the event functions read it: the segment, its regime r and
// its start q0 in eigen-coordinates; the regimes' matrices; the sizes (n modes; ks = 2
// where only the first of each conjugate pair is evaluated); the bar's rows mk (M, K, C,
// psi_L, psi_d, psi_a); the harmonic forcing (f0, om); and the scratch the state is
// evaluated into (q, X and X', each seen with its own length).
struct SegView {
    const Segment& seg;
    idx r;
    CVec q0;
    ClosedForm cf;
    idx ks;
    CVec q;
    Vec X;
    Vec Xd;
    idx n;
    Mat mk;
    double f0;
    double om;

    // the same view with ks and n given (the copies with constant sizes)
    SegView with_sizes(idx ks_, idx n_) const {
        return {seg, r, q0, cf, ks_, q, X, Xd, n_, mk, f0, om};
    }
};

// Rows to evaluate of a state: [j0, j1), j1 < 0 for all of them.
struct Rows {
    idx j0 = 0, j1 = -1;
    idx end(idx nz) const { return j1 < 0 ? nz : j1; }
};

// X from the eigen-coordinates q of regime r and the forcing phasor ph = e^{i Omega t}
// (its rows rows only; the others are left as they were).
inline void from_q(const ClosedForm& cf, idx r, idx ks, CVec q, ncplx ph, double fb, Vec X,
                   Rows rows = {}) {
    idx nz = X.n;
    for (idx j = rows.j0; j < rows.end(nz); ++j) {
        double s = (ncplx(cf.Z(r, j)) * ph).im + fb * cf.D(r, j);
        for (idx kq = 0; kq < nq(nz, ks); ++kq) {
            idx k = kq * ks;
            s += (ncplx(cf.V(r, j, k)) * ncplx(q[k])).re;
        }
        X[j] = s;
    }
}

// X = X(ts + tau) on the segment of s (regime s.r, eigen-coordinates s.q0 at ts = seg.ts),
// with its eigen-coordinates into q; returns the forcing phasor e^{i Omega (ts + tau)}.  In
// a cut the input Kr b S(tau) adds bq Kr b sum_j S_j j! tau^(j+1) phi_(j+1)(lambda tau) to
// each eigen-coordinate.
//
// keep (if not null, and only outside a cut): receives exp(lambda_k tau), k = kq ks; rows:
// the rows of X to evaluate.
inline ncplx state_at(const SegView& s, double tau, CVec q, Vec X, ncplx* keep = nullptr,
                      Rows rows = {}) {
    const Segment& seg = s.seg;
    const idx r = s.r, ks = s.ks;
    const CVec q0 = s.q0;
    const CMat lam = s.cf.lam, bq = s.cf.bq;
    const double om = s.om;
    idx nz = X.n;
    double ts = seg.ts;
    double fb = seg.fb;
    ncplx ph = cexp(ncplx(0.0, 1.0) * om * (ts + tau));
    double krb = seg.krb;
    if (krb != 0.0) {
        double c0 = seg.s[0] * tau;
        double c1 = seg.s[1] * tau * tau;
        double c2 = 2.0 * seg.s[2] * ipow(tau, 3);
        double c3 = 6.0 * seg.s[3] * ipow(tau, 4);
        for (idx kq = 0; kq < nq(nz, ks); ++kq) {
            idx k = kq * ks;
            auto [ex, p1, p2, p3, p4] = phis(ncplx(lam(r, k)) * tau);
            q[k] = ncplx(q0[k]) * ex +
                   krb * ncplx(bq(r, k)) * (c0 * p1 + c1 * p2 + c2 * p3 + c3 * p4);
        }
    } else {
        for (idx kq = 0; kq < nq(nz, ks); ++kq) {
            idx k = kq * ks;
            ncplx ex = cexp(ncplx(lam(r, k)) * tau);
            if (keep) keep[kq] = ex;
            q[k] = ncplx(q0[k]) * ex;
        }
    }
    from_q(s.cf, r, ks, q, ph, fb, X, rows);
    return ph;
}

// X[i] and X[n + i] weighed by row ``row`` of mk: psi . u and psi . u' (MK_PSI_L: the
// tip's W and W'; MK_PSI_D: the ball's seat), the sums in index order.
inline std::pair<double, double> psi_dot(Mat mk, idx row, Vec X, idx n) {
    double u = 0.0;
    double v = 0.0;
    for (idx i = 0; i < n; ++i) {
        u += mk(row, i) * X[i];
        v += mk(row, i) * X[n + i];
    }
    return {u, v};
}

// The force at the tip at ts + tau: F0 sin(Omega t), or Kr b (S(tau) - W) in a cut.
// sn: sin(Omega (ts + tau)) if the caller has it (else NaN: computed here).
inline double cut_force(const Segment& seg, double tau, Vec X, idx n, Mat mk, double f0,
                        double om, double sn = NAN) {
    double f = f0 * (sn == sn ? sn : std::sin(om * (seg.ts + tau)));
    if (seg.krb != 0.0) {
        const double w = psi_dot(mk, MK_PSI_L, X, n).first;
        f += seg.krb * (std::get<0>(surface_at(seg, tau)) - w);
    }
    return f;
}

// The force that carries the ball with the bar, psi_d . a_0 / kappa (N), under the tip
// force f.
inline double freq_rhs(Vec X, double f, idx n, Mat mk, double kappa) {
    double s = 0.0;
    for (idx i = 0; i < n; ++i)
        s += mk(MK_PSI_D, i) * dynamics::free_acceleration(mk(MK_FM, i), mk(MK_KM, i),
                                                           mk(MK_CM, i), f, X[i], X[n + i]);
    return s / kappa;
}

// X and X' at ts + tau on the segment of s (see state_at), into s.X and s.Xd (their rows
// rows only; and the eigen-coordinates into s.q); in a cut q' = lambda q + bq Kr b S.
inline void state_at2(const SegView& s, double tau, Rows rows = {}) {
    const idx r = s.r, ks = s.ks;
    const CVec q = s.q;
    const Vec Xd = s.Xd;
    const ClosedForm& cf = s.cf;
    idx nz = s.X.n;
    ncplx ph = state_at(s, tau, q, s.X, nullptr, rows);
    double sin_ = s.seg.krb * std::get<0>(surface_at(s.seg, tau));
    for (idx j = rows.j0; j < rows.end(nz); ++j) {
        double sd = s.om * (ncplx(cf.Z(r, j)) * ph).re;
        for (idx kq = 0; kq < nq(nz, ks); ++kq) {
            idx k = kq * ks;
            sd += (ncplx(cf.V(r, j, k)) *
                   (ncplx(q[k]) * ncplx(cf.lam(r, k)) + sin_ * ncplx(cf.bq(r, k))))
                      .re;
        }
        Xd[j] = sd;
    }
}

// Which compilation with constant sizes fits a regime: 1 (one mode, nz = 2) or 2 (two
// modes, nz = 4), each in conjugate pairs (ks = 2); 0 for any other.
inline idx const_sizes(idx ks, idx n, idx nz) {
    if (ks == 2 && nz == 2 * n && n <= 2) return n;
    return 0;
}

}  // namespace bb::exact
