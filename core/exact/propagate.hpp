// The closed form on a segment: the state at any
// time (state_at), the forces, and the segment's integrals of products of exponentials
// (segment_integrals), with complex arithmetic on ncplx (nmath.hpp) so that the rounding
// is this file's and not the compiler's.
//
// The closed form reads the segment through a SegView (the segment, its regime and start,
// the regimes' matrices, the sizes, the bar's rows, the forcing and the scratch):
//   ncplx state_at(const SegView& s, double tau, CVec q, Vec X);   // returns e^{i Omega t}
//   void state_at2(const SegView& s, double tau);                   // s.X and s.Xd
//   void from_q(const ClosedForm& cf, idx r, idx ks, CVec q, ncplx ph, double fb, Vec X);
//   double cut_force(const Segment& seg, double tau, Vec X, idx n, Mat mk, double f0,
//                    double om);
//   double freq_rhs(Vec X, double f, idx n, Mat mk, double kappa);
//   void segment_integrals(const FlowsIn& in, idx n, idx ks, const FlowsScratch& sc,
//                          Vec out);
//   void segment_integrals_1(const FlowsIn& in, CVec phj, Vec out);   // n = 1, nz = 2, ks = 2
//   void segment_integrals_2(const FlowsIn& in, CVec phj, Vec out);   // n = 2, nz = 4, ks = 2
// and the helpers nq, phis, surface_at, const_sizes, basis_exponents, _phi1s, _phij,
// _conj_index, _integrals_impl, _psi_dot, _quad_sym, _quad.
//
// X, Xd are seen with their own length (X.n): pass views of length nz.
#pragma once

#include <cmath>
#include <tuple>

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

// X from the eigen-coordinates q of regime r and the forcing phasor ph = e^{i Omega t}.
inline void from_q(const ClosedForm& cf, idx r, idx ks, CVec q, ncplx ph, double fb, Vec X) {
    idx nz = X.n;
    for (idx j = 0; j < nz; ++j) {
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
// keep (if not null, and only outside a cut): receives exp(lambda_k tau), k = kq ks.
inline ncplx state_at(const SegView& s, double tau, CVec q, Vec X, ncplx* keep = nullptr) {
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
    from_q(s.cf, r, ks, q, ph, fb, X);
    return ph;
}

// The tip's displacement W and velocity W' of the modal state X (psi_L . u, psi_L . u'):
// the sums in index order, as every caller had them.
inline std::tuple<double, double> tip_w_wd(Mat mk, Vec X, idx n) {
    double w = 0.0;
    double wd = 0.0;
    for (idx i = 0; i < n; ++i) {
        w += mk(3, i) * X[i];
        wd += mk(3, i) * X[n + i];
    }
    return {w, wd};
}

// The force at the tip at ts + tau: F0 sin(Omega t), or Kr b (S(tau) - W) in a cut.
// sn: sin(Omega (ts + tau)) if the caller has it (else NaN: computed here).
inline double cut_force(const Segment& seg, double tau, Vec X, idx n, Mat mk, double f0,
                        double om, double sn = NAN) {
    double f = f0 * (sn == sn ? sn : std::sin(om * (seg.ts + tau)));
    if (seg.krb != 0.0) {
        double w = 0.0;
        for (idx i = 0; i < n; ++i) w += mk(3, i) * X[i];
        f += seg.krb * (std::get<0>(surface_at(seg, tau)) - w);
    }
    return f;
}

// The force that carries the ball with the bar, psi_d . a_0 / kappa (N), under the tip
// force f.
inline double freq_rhs(Vec X, double f, idx n, Mat mk, double kappa) {
    double s = 0.0;
    for (idx i = 0; i < n; ++i)
        s += mk(4, i) *
             dynamics::free_acceleration(mk(6, i), mk(7, i), mk(8, i), f, X[i], X[n + i]);
    return s / kappa;
}

// X and X' at ts + tau on the segment of s (see state_at), into s.X and s.Xd (and the
// eigen-coordinates into s.q); in a cut q' = lambda q + bq Kr b S.
inline void state_at2(const SegView& s, double tau) {
    const idx r = s.r, ks = s.ks;
    const CVec q = s.q;
    const Vec Xd = s.Xd;
    const ClosedForm& cf = s.cf;
    idx nz = s.X.n;
    ncplx ph = state_at(s, tau, q, s.X);
    double sin_ = s.seg.krb * std::get<0>(surface_at(s.seg, tau));
    for (idx j = 0; j < nz; ++j) {
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

// mu = (lambda_r, i Omega, -i Omega, 0): the exponents of a segment's basis functions
// (-i is the constant complex(-0.0, -1.0), the negation of i).
template <class MuV>
inline void basis_exponents(CMat lam, idx r, double om, idx nz, MuV&& mu) {
    for (idx k = 0; k < nz; ++k) mu[k] = lam(r, k);
    mu[nz] = ncplx(0.0, 1.0) * om;
    mu[nz + 1] = ncplx(-0.0, -1.0) * om;
    mu[nz + 2] = promote(0.0);
}

// int_0^T exp(z tau / T) dtau = T (e^z - 1) / z by its series, for |z|^2 = z2 < 1/64.
inline ncplx _phi1s(ncplx z, double T, double z2) {
    int top = z2 > 9e-4 ? 11 : (z2 > 2.5e-5 ? 8 : 6);
    ncplx s(0.0, 0.0);
    for (int k = top; k > 1; --k) s = (s * z + 1.0) * RECIP[k];
    s = s * z + 1.0;
    return T * s;
}

// phj[j] = phi_j(z) = int_0^1 s^j exp(z s) ds, j = 0, 1, 2, for |z| < 1, by the series
// sum_m z^m / (m! (m + j + 1)), to the first term below 1e-18.
template <class PV>
inline void _phij(ncplx z, PV&& phj) {
    ncplx term(1.0, 0.0);
    ncplx f0(0.0, 0.0);
    ncplx f1(0.0, 0.0);
    ncplx f2(0.0, 0.0);
    for (int mm = 0; mm < 20; ++mm) {
        f0 += term * RECIP[mm + 1];
        f1 += term * RECIP[mm + 2];
        f2 += term * RECIP[mm + 3];
        term = term * z * RECIP[mm + 1];
        if (term.re * term.re + term.im * term.im < 1e-36) break;
    }
    phj[0] = f0;
    phj[1] = f1;
    phj[2] = f2;
}

// The basis function conjugate to exp(mu_k tau) when every eigenvalue has its conjugate
// beside it (ks = 2); with ks = 1 every function is its own.
inline idx _conj_index(idx k, idx nz, idx ks) {
    if (ks != 2) return k;
    if (k < nz) return k ^ 1;
    if (k == nz) return nz + 1;
    if (k == nz + 1) return nz;
    return k;
}

// dst[k] = sum_i mk[row, i] Cx[off + i, k]: the basis coefficients of psi . u (off 0) or
// psi . u' (off n).
template <class CM, class DV>
inline void _psi_dot(Mat mk, idx row, CM& Cx, idx off, idx n, idx nb, DV& dst) {
    BB_UNROLL
    for (idx k = 0; k < nb; ++k) {
        ncplx s(0.0, 0.0);
        for (idx i = 0; i < n; ++i) s += mk(row, i) * ncplx(Cx(off + i, k));
        dst[k] = s;
    }
}

// Re(a^T G a) for a symmetric G.
template <class AV, class GM>
inline double _quad_sym(AV& a, GM& G, idx nb) {
    double s = 0.0;
    BB_UNROLL
    for (idx i = 0; i < nb; ++i) {
        ncplx t = 0.5 * ncplx(G(i, i)) * ncplx(a[i]);
        BB_UNROLL
        for (idx j = i + 1; j < nb; ++j) t += ncplx(G(i, j)) * ncplx(a[j]);
        s += (ncplx(a[i]) * t).re;
    }
    return 2.0 * s;
}

// Re(a^T G b).
template <class AV, class GM>
inline double _quad(AV& a, AV& b, GM& G, idx nb) {
    double s = 0.0;
    BB_UNROLL
    for (idx i = 0; i < nb; ++i) {
        ncplx t(0.0, 0.0);
        BB_UNROLL
        for (idx j = 0; j < nb; ++j) t += ncplx(G(i, j)) * ncplx(b[j]);
        s += (ncplx(a[i]) * t).re;
    }
    return s;
}

// What segment_integrals integrates: the segment [ts, ts + T] (seg, its friction force
// seg.fb) from its start q0 in regime r, with the forcing phasor ph at ts; the regimes'
// matrices (VF: the full eigenvectors, prepare's V; isum: 1 / (mu_a + mu_b) of the basis
// exponents); the bar's rows and its dashpots; the forcing; a
// stuck ball's kappa (stick_k, 0 when not stuck) and the reaction's share sr; how much to
// integrate (level: 0 the energy flows, 1 also the steady W sums, 2 also a free ball's
// y^2); and exp(lambda_k T) (k = 0, ks, ...) if the search kept it, else null.
struct FlowsIn {
    const Segment& seg;
    idx r;
    CVec q0;
    ncplx ph;
    double T;
    CMat lam;
    CArr3 VF;
    CMat Z;
    Mat D;
    CArr3 isum;
    Mat mk;
    Dashpots dp;
    double f0, om;
    double stick_k, sr;
    idx level;
    const ncplx* exc;
};

// segment_integrals' scratch: the basis exponents mu and exp(mu T), the Gram matrix G of
// the basis functions, the state's coefficients Cx, three coefficient vectors and phj.
// Their types are CVec / CMat views of the driver's scratch or (the constant sizes) local
// arrays (LocalArr) that the compiler knows alias nothing else.
template <class MuV, class GM, class CM, class V>
struct FlowsScratchOf {
    MuV& mu;
    MuV& em;
    GM& G;
    CM& Cx;
    V& cf;
    V& ca;
    V& cb;
    CVec phj;
};

// The driver's scratch views for segment_integrals (any size).
struct FlowsScratch {
    CMat me;  // (2, nb): the basis exponents and exp(mu T)
    CMat G, Cx;
    CVec cf, ca, cb, phj;
};

// Closed-form integrals over a segment [ts, ts + T]: out = [int f psi_L.u',
// sum_d c_d int (l_d.X)^2, int W^2, int W, int f, (1-s) int F_stick psi_d.u', int y^2]
// (2-4 and 6 only if level >= 1; 6 only if level = 2, a free ball): the state and the
// forces are sums of exponentials exp(mu_a tau), so each integral is a quadratic form in
// their coefficients with the Gram matrix G_ab = int exp((mu_a + mu_b) tau).  The sizes n,
// ks, nz are given (constants in the copies for one and two modes).
template <class MuV, class GM, class CM, class V>
BB_ALWAYS_INLINE void _integrals_impl(const FlowsIn& in, const FlowsScratchOf<MuV, GM, CM, V>& sc,
                                      Vec out, idx n, idx ks, idx nz) {
    const Segment& seg = in.seg;
    const idx r = in.r, level = in.level;
    const CVec q0 = in.q0;
    const ncplx ph = in.ph;
    const double T = in.T, fb = seg.fb, om = in.om, f0 = in.f0;
    const double stick_k = in.stick_k, sr = in.sr;
    const CMat lam = in.lam, Z = in.Z;
    const CArr3 VF = in.VF, isum = in.isum;
    const Mat D = in.D, mk = in.mk, lvis = in.dp.l;
    const Vec cvis = in.dp.c;
    const ncplx* exc = in.exc;
    MuV& mu = sc.mu;
    MuV& em = sc.em;
    GM& G = sc.G;
    CM& Cx = sc.Cx;
    V& cf = sc.cf;
    V& ca = sc.ca;
    V& cb = sc.cb;
    const CVec phj = sc.phj;
    double p0 = seg.ud0;  // a free ball's absolute position P = p0 + p1 tau + p2 tau^2
    double p1 = seg.vd0;
    double p2 = 0.5 * seg.acc;
    idx nb = nz + 3;
    basis_exponents(lam, r, om, nz, mu);
    // exp(conj z) = conj(exp(z)) exactly: a conjugate pair's second exponential and the
    // forcing's -i Omega are conjugates, exp(0) = 1
    BB_UNROLL
    for (idx k = 0; k < nz; ++k) {
        if (k > 0 && ncplx(mu[k]) == ncplx(mu[k - 1]).conjugate())
            em[k] = ncplx(em[k - 1]).conjugate();
        else if (exc && k % ks == 0)  // state_at's exp(lambda_k T), the same operations
            em[k] = exc[k / ks];
        else
            em[k] = cexp(ncplx(mu[k]) * T);
    }
    em[nz] = cexp(ncplx(mu[nz]) * T);
    em[nz + 1] = ncplx(em[nz]).conjugate();
    em[nz + 2] = promote(1.0);
    double lim = 0.015625 / (T * T);  // |mu_m + mu_l| T < 1/8: the series
    BB_UNROLL
    for (idx a = 0; a < nb; ++a) {
        idx ja = _conj_index(a, nz, ks);
        BB_UNROLL
        for (idx b = a; b < nb; ++b) {
            idx jb = _conj_index(b, nz, ks);
            idx lo = ja < jb ? ja : jb;
            idx hi = ja < jb ? jb : ja;
            ncplx g;
            if (lo < a || (lo == a && hi < b)) {
                // the conjugate entry, already computed: G is conjugate-symmetric
                g = ncplx(G(lo, hi)).conjugate();
            } else {
                ncplx s = ncplx(mu[a]) + ncplx(mu[b]);
                if (s.im == 0.0) {
                    // a conjugate pair, or the forcing's two terms, or 0: real
                    double x = s.re * T;
                    g = (x != 0.0 ? T * std::expm1(x) / x : T) + ncplx(0.0, 0.0);
                } else {
                    double z2 = s.re * s.re + s.im * s.im;
                    if (z2 < lim)
                        g = _phi1s(s * T, T, z2 * T * T);
                    else
                        g = (ncplx(em[a]) * ncplx(em[b]) - 1.0) * ncplx(isum(r, a, b));
                }
            }
            G(a, b) = g;
            G(b, a) = g;
        }
    }
    // a sine's phasors: Im(z e^{i Omega t}) = (z ph2) e^{..} + conj; -0.5j is the constant
    // complex(-0.0, -0.5) in Python
    ncplx ph2 = ncplx(-0.0, -0.5) * ph;
    BB_UNROLL
    for (idx j = 0; j < nz; ++j) {
        BB_UNROLL
        for (idx k = 0; k < nz; ++k) Cx(j, k) = ncplx(VF(r, j, k)) * ncplx(q0[k]);
        ncplx zz = ncplx(Z(r, j)) * ph2;
        Cx(j, nz) = zz;
        Cx(j, nz + 1) = zz.conjugate();
        Cx(j, nz + 2) = promote(fb * D(r, j));
    }
    BB_UNROLL
    for (idx k = 0; k < nb; ++k) cf[k] = promote(0.0);
    cf[nz] = f0 * ph2;
    cf[nz + 1] = ncplx(cf[nz]).conjugate();
    // work of the force: f psi_L . u' (f has only the terms nz, nz + 1)
    _psi_dot(mk, 3, Cx, n, n, nb, ca);
    double w = 0.0;
    BB_UNROLL
    for (idx i = nz; i < nz + 2; ++i) {
        ncplx t(0.0, 0.0);
        BB_UNROLL
        for (idx j = 0; j < nb; ++j) t += ncplx(G(i, j)) * ncplx(ca[j]);
        w += (ncplx(cf[i]) * t).re;
    }
    out[0] = w;
    out[4] = (ncplx(cf[nz]) * ncplx(G(nz, nb - 1))).re +
             (ncplx(cf[nz + 1]) * ncplx(G(nz + 1, nb - 1))).re;
    out[5] = 0.0;
    if (stick_k != 0.0 && sr != 1.0) {
        // F_stick = psi_d . a_0 / kappa, a_0,i = (psi_L,i f - K_i u_i - C_i u_i') / M_i
        for (idx k = 0; k < nb; ++k) {
            ncplx s(0.0, 0.0);
            ncplx pv(0.0, 0.0);
            for (idx i = 0; i < n; ++i) {
                s += mk(4, i) * dynamics::free_acceleration(mk(6, i), mk(7, i), mk(8, i),
                                                            ncplx(cf[k]), ncplx(Cx(i, k)),
                                                            ncplx(Cx(n + i, k)));
                pv += mk(4, i) * ncplx(Cx(n + i, k));
            }
            ca[k] = s / stick_k;
            cb[k] = pv;
        }
        out[5] = (1.0 - sr) * _quad(ca, cb, G, nb);
    }
    // viscous loss
    double dv = 0.0;
    for (idx d = 0; d < lvis.n0; ++d) {
        BB_UNROLL
        for (idx k = 0; k < nb; ++k) {
            ncplx s(0.0, 0.0);
            BB_UNROLL
            for (idx j = 0; j < nz; ++j)
                if (lvis(d, j) != 0.0) s += lvis(d, j) * ncplx(Cx(j, k));
            ca[k] = s;
        }
        dv += cvis[d] * _quad_sym(ca, G, nb);
    }
    out[1] = dv;
    if (level == 0) return;
    // W = psi_L . u
    _psi_dot(mk, 3, Cx, 0, n, nb, ca);
    out[2] = _quad_sym(ca, G, nb);
    double w1 = 0.0;
    BB_UNROLL
    for (idx k = 0; k < nb; ++k) w1 += (ncplx(ca[k]) * ncplx(G(k, nb - 1))).re;
    out[3] = w1;
    if (level == 1) return;
    // int y^2 = int P^2 - 2 int P psi_d.u + int (psi_d.u)^2, with
    // int_0^T tau^j exp(mu tau) = T^(j+1) phi_j(mu T), phi_j(z) = int_0^1 s^j e^(z s) ds
    _psi_dot(mk, 4, Cx, 0, n, nb, cb);  // psi_d . u
    if (seg.rolls && seg.cy != 1.0) {  // a rolling ball's y follows cy psi_d . u
        BB_UNROLL
        for (idx k = 0; k < nb; ++k) cb[k] = seg.cy * ncplx(cb[k]);
    }
    double uu = _quad_sym(cb, G, nb);
    // mu = 0 (the last basis function): phi_j = 1 / (j + 1)
    double cross = (ncplx(cb[nb - 1]) * T * (p0 + T * (0.5 * p1 + T * p2 / 3.0))).re;
    BB_UNROLL
    for (idx k = 0; k < nb - 1; ++k) {
        idx jk = _conj_index(k, nz, ks);
        if (jk < k) continue;  // the conjugate of an earlier term: counted there
        ncplx z = ncplx(mu[k]) * T;
        ncplx acc_;
        if (z.re * z.re + z.im * z.im >= 1.0) {
            // upward recurrence phi_j = (e^z - j phi_(j-1)) / z; 1 / mu_k = 2 isum[r, k, k]
            ncplx iz = 2.0 * ncplx(isum(r, k, k)) / T;
            ncplx ez = em[k];
            ncplx f0_ = (ez - 1.0) * iz;
            ncplx f1_ = (ez - f0_) * iz;
            acc_ = p0 * f0_ + T * p1 * f1_;
            if (p2 != 0.0) acc_ += T * T * p2 * ((ez - 2.0 * f1_) * iz);
        } else {
            _phij(z, phj);
            acc_ = p0 * ncplx(phj[0]) + T * (p1 * ncplx(phj[1]) + T * p2 * ncplx(phj[2]));
        }
        double v = (ncplx(cb[k]) * acc_).re * T;
        cross += jk == k ? v : 2.0 * v;
    }
    double pp = T * (p0 * p0 +
                     T * (p0 * p1 + T * ((p1 * p1 + 2.0 * p0 * p2) / 3.0 +
                                         T * (0.5 * p1 * p2 + 0.2 * T * p2 * p2))));
    out[6] = pp - 2.0 * cross + uu;
}

// _integrals_impl for any bar, regime and basis (nz = lam's second dimension; in.exc is
// not used).
inline void segment_integrals(const FlowsIn& in, idx n, idx ks, const FlowsScratch& s,
                              Vec out) {
    CVec mu = s.me[0];  // the basis exponents
    CVec em = s.me[1];  // exp(mu T)
    CMat G = s.G, Cx = s.Cx;
    CVec cf = s.cf, ca = s.ca, cb = s.cb;
    FlowsIn all = in;
    all.exc = nullptr;
    _integrals_impl(all, FlowsScratchOf<CVec, CMat, CMat, CVec>{mu, em, G, Cx, cf, ca, cb, s.phj},
                    out, n, ks, in.lam.n1);
}

// A (rows x cols) scratch array on the stack, left uninitialised (every entry that
// _integrals_impl reads it has written first in the same call), indexed as the views are.
template <int R, int C>
struct LocalArr {
    union {
        ncplx d[R * C];
    };
    LocalArr() {}
    ncplx& operator()(idx i, idx j) { return d[i * C + j]; }
    ncplx& operator[](idx i) { return d[i]; }
};

// _integrals_impl with the constant sizes NZ (n = NZ / 2, ks = 2) and its scratch local.
template <int NZ>
BB_NOINLINE void _integrals_fixed(const FlowsIn& in, CVec phj, Vec out) {
    constexpr int NB = NZ + 3;
    LocalArr<1, NB> mu, em, cf, ca, cb;
    LocalArr<NB, NB> G;
    LocalArr<NZ, NB> Cx;
    using L1 = LocalArr<1, NB>;
    _integrals_impl(in,
                    FlowsScratchOf<L1, LocalArr<NB, NB>, LocalArr<NZ, NB>, L1>{
                        mu, em, G, Cx, cf, ca, cb, phj},
                    out, NZ / 2, 2, NZ);
}

// One mode and its conjugate pair (n = 1, nz = 2, ks = 2): the same operations.
inline void segment_integrals_1(const FlowsIn& in, CVec phj, Vec out) {
    _integrals_fixed<2>(in, phj, out);
}

// Two modes in conjugate pairs (n = 2, nz = 4, ks = 2): the same operations.
inline void segment_integrals_2(const FlowsIn& in, CVec phj, Vec out) {
    _integrals_fixed<4>(in, phj, out);
}

}  // namespace bb::exact
