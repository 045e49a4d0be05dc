// A segment's integrals in closed form (segment_integrals): the energy flows, the steady
// sums of W and a free ball's int y^2 over the segment [ts, ts + T], from its start.
//
// On a segment every signal s that is a fixed row l of the state is a sum of exponentials,
// s(tau) = sum_k P_k c_k exp(mu_k tau), over the basis mu = (lambda_r, i Omega, -i Omega, 0):
//   c = (q0, ph2, conj ph2, fb), the segment's coefficients (its start in eigen-coordinates,
//       the forcing's phasor, the friction force);
//   P = l . [V | Z | conj Z | D], the regime's projection of the row (prepare's matrices).
// So int s^2 = sum_ab (c_a c_b G_ab) (P_a P_b), with G_ab = int exp((mu_a + mu_b) tau): the
// segment gives M_ab = c_a c_b G_ab, and the regime gives K_ab = P_a P_b once (FlowTables,
// built on a regime's first segment).  Both are symmetric, and when the eigenvalues come in
// conjugate pairs (ks = 2) the term of the conjugate pair of indices is the conjugate of
// the term, so the real sum takes one pair (a, b) of each such orbit, with the orbit's
// weight in K.
//
//   struct FlowTables     each regime's K of the quadratic forms and P of the linear ones
//   struct FlowsIn        what a segment's integrals read
//   void segment_integrals(const FlowsIn& in, idx n, idx ks, const FlowsScratch& sc,
//                          Vec out);
//   void segment_integrals_1(const FlowsIn& in, CVec phj, Vec out);   // n = 1, nz = 2, ks = 2
//   void segment_integrals_2(const FlowsIn& in, CVec phj, Vec out);   // n = 2, nz = 4, ks = 2
// and the helpers basis_exponents, _phi1s, _phij, _conj_index, _quad.
#pragma once

#include <array>
#include <cmath>
#include <vector>

#include "../arrays.hpp"
#include "../dynamics.hpp"
#include "consts.hpp"
#include "nmath.hpp"
#include "propagate.hpp"

namespace bb::exact {

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

// The quadratic forms of a segment's integrals: the work of the force (f psi_F . u'), the
// viscous loss (sum_d c_d (l_d . X)^2), W^2 and (psi_d . u)^2.
enum FlowForm : idx { FF_WORK = 0, FF_VISC = 1, FF_WW = 2, FF_UU = 3, FF_FORMS = 4 };

// One regime's tables: the pairs (a[o], b[o]) of its orbits, each form's weighted K there
// (and K times isum_ab), and the projections of W (PW) and of psi_d . u (Pd) for the
// linear terms.
struct FlowTable {
    idx norb;
    const idx* a;
    const idx* b;
    const ncplx* K;   // K[f * stride + o], f a FlowForm
    const ncplx* Ki;  // isum_ab K: where G_ab = (e^(mu_a T) e^(mu_b T) - 1) isum_ab
    idx stride;
    const ncplx* PW;
    const ncplx* Pd;
};

// The projection P = l . [VF | Z | conj Z | D] of the state row l (nz entries) in regime r.
inline void project(const double* l, idx r, CArr3 VF, CMat Z, Mat D, idx nz, ncplx* P) {
    for (idx k = 0; k < nz; ++k) {
        ncplx s(0.0, 0.0);
        for (idx j = 0; j < nz; ++j)
            if (l[j] != 0.0) s += l[j] * ncplx(VF(r, j, k));
        P[k] = s;
    }
    ncplx z(0.0, 0.0);
    double d = 0.0;
    for (idx j = 0; j < nz; ++j) {
        if (l[j] == 0.0) continue;
        z += l[j] * ncplx(Z(r, j));
        d += l[j] * D(r, j);
    }
    P[nz] = z;
    P[nz + 1] = z.conjugate();
    P[nz + 2] = promote(d);
}

// What a regime's tables are built from: prepare's eigenvectors (VF, its V), forced and
// friction responses, the basis exponents' inverse sums, the bar's rows and its dashpots.
struct FlowSources {
    CArr3 VF;
    CMat Z;
    Mat D;
    CArr3 isum;
    Mat mk;
    Dashpots dp;
};

// Every regime's FlowTable, built on its first segment (a run visits few of its regimes).
class FlowTables {
  public:
    // Room for R regimes of nz states, none built.
    void reset(idx R, idx nz) {
        nb_ = nz + 3;
        stride_ = nb_ * (nb_ + 1) / 2;
        norb_.assign(size_t(R), -1);
        ab_.resize(size_t(R) * 2 * size_t(stride_));
        K_.resize(size_t(R) * 2 * FF_FORMS * size_t(stride_));
        P_.resize(size_t(R) * 2 * size_t(nb_));
    }

    // Regime r's table (n modes; ks = 2 if its eigenvalues come in conjugate pairs).
    FlowTable of(idx r, const FlowSources& src, idx n, idx ks) {
        if (norb_[size_t(r)] < 0) build(r, src, n, ks);
        const idx* ab = ab_.data() + size_t(r) * 2 * size_t(stride_);
        const ncplx* K = K_.data() + size_t(r) * 2 * FF_FORMS * size_t(stride_);
        const ncplx* P = P_.data() + size_t(r) * 2 * size_t(nb_);
        return {norb_[size_t(r)], ab, ab + stride_, K, K + FF_FORMS * stride_, stride_, P, P + nb_};
    }

  private:
    idx nb_ = 0, stride_ = 0;
    std::vector<idx> norb_, ab_;
    std::vector<ncplx> K_, P_;

    void build(idx r, const FlowSources& src, idx n, idx ks);
};

inline void FlowTables::build(idx r, const FlowSources& src, idx n, idx ks) {
    const idx nb = nb_, nz = nb - 3, nd = src.dp.l.n0;
    std::array<double, NZ_MAX> l{};
    std::array<ncplx, NB_MAX> Pwork;
    std::array<std::array<ncplx, NB_MAX>, layout::NMAX + 1> Pvis;
    ncplx* PW = P_.data() + size_t(r) * 2 * size_t(nb);
    ncplx* Pd = PW + nb;
    auto row = [&](idx m, idx off, ncplx* P) {  // l = mk's row m at the state's [off, off + n)
        l.fill(0.0);
        for (idx i = 0; i < n; ++i) l[size_t(off + i)] = src.mk(m, i);
        project(l.data(), r, src.VF, src.Z, src.D, nz, P);
    };
    row(MK_PSI_F, n, Pwork.data());  // psi_F . u'
    row(MK_PSI_L, 0, PW);            // W = psi_L . u
    row(MK_PSI_D, 0, Pd);            // psi_d . u
    for (idx d = 0; d < nd; ++d) project(src.dp.l.row(d), r, src.VF, src.Z, src.D, nz,
                                         Pvis[size_t(d)].data());
    idx* oa = ab_.data() + size_t(r) * 2 * size_t(stride_);
    idx* ob = oa + stride_;
    ncplx* K = K_.data() + size_t(r) * 2 * FF_FORMS * size_t(stride_);
    ncplx* Ki = K + FF_FORMS * stride_;
    auto forcing = [&](idx k) { return k == nz || k == nz + 1 ? 1.0 : 0.0; };
    idx no = 0;
    for (idx a = 0; a < nb; ++a) {
        for (idx b = a; b < nb; ++b) {
            double wgt = a == b ? 1.0 : 2.0;  // (a, b) and (b, a)
            if (ks == 2) {  // the orbit {(a, b), (conj a, conj b)}: its first pair only
                idx ca = _conj_index(a, nz, ks), cb = _conj_index(b, nz, ks);
                idx lo = ca < cb ? ca : cb, hi = ca < cb ? cb : ca;
                if (lo < a || (lo == a && hi < b)) continue;
                if (lo != a || hi != b) wgt *= 2.0;
            }
            oa[no] = a;
            ob[no] = b;
            // f psi_F . u' with f = f0 (c_nz e^{..} + c_nz+1 e^{..}): the forcing's rows
            K[FF_WORK * stride_ + no] =
                0.5 * wgt * (forcing(a) * Pwork[size_t(b)] + forcing(b) * Pwork[size_t(a)]);
            ncplx v(0.0, 0.0);
            for (idx d = 0; d < nd; ++d)
                v += src.dp.c[d] * (Pvis[size_t(d)][size_t(a)] * Pvis[size_t(d)][size_t(b)]);
            K[FF_VISC * stride_ + no] = wgt * v;
            K[FF_WW * stride_ + no] = wgt * (PW[a] * PW[b]);
            K[FF_UU * stride_ + no] = wgt * (Pd[a] * Pd[b]);
            for (idx f = 0; f < FF_FORMS; ++f)
                Ki[f * stride_ + no] = ncplx(src.isum(r, a, b)) * K[f * stride_ + no];
            ++no;
        }
    }
    norb_[size_t(r)] = no;
}

// What segment_integrals integrates: the segment [ts, ts + T] (seg, its friction force
// seg.fb) from its start q0 in regime r, with the forcing phasor ph at ts; the regimes'
// eigenvalues lam and what their tables are built from (src: FlowSources, with isum,
// 1 / (mu_a + mu_b) of the basis exponents, and the bar's rows) and regime r's tables
// (tab); the forcing; a stuck ball's kappa (stick_k, 0 when not stuck) and the reaction's
// share sr; how much to integrate (level: 0 the energy flows, 1 also the steady W sums,
// 2 also a free ball's y^2); and exp(lambda_k T) (k = 0, ks, ...) if the search kept it,
// else null.
struct FlowsIn {
    const Segment& seg;
    idx r;
    CVec q0;
    ncplx ph;
    double T;
    CMat lam;
    FlowSources src;
    FlowTable tab;
    double f0, om;
    double stick_k, sr;
    idx level;
    const ncplx* exc;
};

// segment_integrals' scratch: the basis exponents mu and exp(mu T), the segment's
// coefficients c and c exp(mu T) (ce), and for a stuck ball's reaction the Gram matrix G
// of the basis functions and the state's coefficients Cx; two coefficient vectors and
// phj.  Their types are CVec / CMat
// views of the driver's scratch or (the constant sizes) local arrays (LocalArr) that the
// compiler knows alias nothing else.
template <class MuV, class GM, class CM, class V>
struct FlowsScratchOf {
    MuV& mu;
    MuV& em;
    GM& G;
    CM& Cx;
    V& c;
    V& ce;
    V& ca;
    V& cb;
    CVec phj;
};

// The driver's scratch views for segment_integrals (any size).
struct FlowsScratch {
    CMat me;  // (2, nb): the basis exponents and exp(mu T)
    CMat G, Cx;
    CVec c, ce, ca, cb, phj;
};

// A stuck ball's share of the reaction's work, (1 - sr) int F_stick psi_d . u', into out[5]:
// F_stick = psi_d . a_0 / kappa, a_0,i = (psi_F,i f - K_i u_i - C_i u_i') / M_i, from the
// state's coefficients Cx (the reaction is not a fixed row of the state).
template <class MuV, class GM, class CM, class V, class Gram>
inline void stick_work(const FlowsIn& in, const FlowsScratchOf<MuV, GM, CM, V>& sc, Vec out,
                       idx n, idx ks, idx nz, Gram&& gram) {
    const idx r = in.r, nb = nz + 3;
    GM& G = sc.G;
    for (idx a = 0; a < nb; ++a) {
        idx ja = _conj_index(a, nz, ks);
        for (idx b = a; b < nb; ++b) {
            idx jb = _conj_index(b, nz, ks);
            idx lo = ja < jb ? ja : jb, hi = ja < jb ? jb : ja;
            // G is conjugate-symmetric: an entry whose conjugate came first is its conjugate
            G(a, b) = (lo < a || (lo == a && hi < b)) ? ncplx(G(lo, hi)).conjugate() : gram(a, b);
            G(b, a) = G(a, b);
        }
    }
    const Mat mk = in.src.mk;
    CM& Cx = sc.Cx;
    V& c = sc.c;
    V& ca = sc.ca;
    V& cb = sc.cb;
    BB_UNROLL
    for (idx j = 0; j < nz; ++j) {
        BB_UNROLL
        for (idx k = 0; k < nz; ++k) Cx(j, k) = ncplx(in.src.VF(r, j, k)) * ncplx(c[k]);
        ncplx zz = ncplx(in.src.Z(r, j)) * ncplx(c[nz]);
        Cx(j, nz) = zz;
        Cx(j, nz + 1) = zz.conjugate();
        Cx(j, nz + 2) = promote(in.seg.fb * in.src.D(r, j));
    }
    for (idx k = 0; k < nb; ++k) {
        // the force's coefficients: f0 on the forcing's two terms
        ncplx fk = (k == nz || k == nz + 1) ? in.f0 * ncplx(c[k]) : promote(0.0);
        ncplx s(0.0, 0.0);
        ncplx pv(0.0, 0.0);
        for (idx i = 0; i < n; ++i) {
            s += mk(MK_PSI_D, i) *
                 dynamics::free_acceleration(mk(MK_FM, i), mk(MK_KM, i), mk(MK_CM, i), fk,
                                             ncplx(Cx(i, k)), ncplx(Cx(n + i, k)));
            pv += mk(MK_PSI_D, i) * ncplx(Cx(n + i, k));
        }
        ca[k] = s / in.stick_k;
        cb[k] = pv;
    }
    out[5] = (1.0 - in.sr) * _quad(ca, cb, G, nb);
}

// Closed-form integrals over a segment [ts, ts + T]: out = [int f psi_F.u',
// sum_d c_d int (l_d.X)^2, int W^2, int W, int f, (1-s) int F_stick psi_d.u', int y^2]
// (2-4 and 6 only if level >= 1; 6 only if level = 2, a free ball).  The sizes n, ks, nz
// are given (constants in the copies for one and two modes).
template <class MuV, class GM, class CM, class V>
BB_ALWAYS_INLINE void _integrals_impl(const FlowsIn& in, const FlowsScratchOf<MuV, GM, CM, V>& sc,
                                      Vec out, idx n, idx ks, idx nz) {
    const Segment& seg = in.seg;
    const idx r = in.r, level = in.level;
    const CVec q0 = in.q0;
    const ncplx ph = in.ph;
    const double T = in.T, fb = seg.fb, om = in.om, f0 = in.f0;
    const CMat lam = in.lam;
    const CArr3 isum = in.src.isum;
    const FlowTable& tab = in.tab;
    const ncplx* exc = in.exc;
    MuV& mu = sc.mu;
    MuV& em = sc.em;
    V& c = sc.c;
    V& ce = sc.ce;
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
    // G_ab = int_0^T exp((mu_a + mu_b) tau) dtau: in real arithmetic where mu_a + mu_b is
    // real (a conjugate pair, the forcing's two terms, or 0), by its series where
    // |mu_a + mu_b| T < 1/8, else (e^(mu_a T) e^(mu_b T) - 1) isum_ab
    auto gram = [&](idx a, idx b) {
        ncplx s = ncplx(mu[a]) + ncplx(mu[b]);
        if (s.im == 0.0) {
            double x = s.re * T;
            return (x != 0.0 ? T * std::expm1(x) / x : T) + ncplx(0.0, 0.0);
        }
        double z2 = s.re * s.re + s.im * s.im;
        if (z2 < lim) return _phi1s(s * T, T, z2 * T * T);
        return (ncplx(em[a]) * ncplx(em[b]) - 1.0) * ncplx(isum(r, a, b));
    };
    // the segment's coefficients c and c e^(mu T); a sine's phasors: Im(z e^{i Omega t}) =
    // (z ph2) e^{..} + conj, -0.5j the constant complex(-0.0, -0.5) in Python
    ncplx ph2 = ncplx(-0.0, -0.5) * ph;
    BB_UNROLL
    for (idx k = 0; k < nz; ++k) c[k] = q0[k];
    c[nz] = ph2;
    c[nz + 1] = ph2.conjugate();
    c[nz + 2] = promote(fb);
    BB_UNROLL
    for (idx k = 0; k < nb; ++k) ce[k] = ncplx(c[k]) * ncplx(em[k]);
    // the quadratic forms: Re sum_o M_o K_o over the orbits, M_o = c_a c_b G_ab, or
    // M_o K_o = (ce_a ce_b - c_a c_b) (isum_ab K_o) where G_ab is not special
    const idx st = tab.stride;
    double fw = 0.0, fv = 0.0, fww = 0.0, fuu = 0.0;
    for (idx o = 0; o < tab.norb; ++o) {
        idx a = tab.a[o], b = tab.b[o];
        const ncplx s = ncplx(mu[a]) + ncplx(mu[b]);
        ncplx m;
        const ncplx* K = tab.K;
        if (s.im != 0.0 && s.re * s.re + s.im * s.im >= lim) {  // gram's last case
            m = ncplx(ce[a]) * ncplx(ce[b]) - ncplx(c[a]) * ncplx(c[b]);
            K = tab.Ki;
        } else {
            m = ncplx(c[a]) * ncplx(c[b]) * gram(a, b);
        }
        auto re = [&](FlowForm f) {
            const ncplx& k = K[f * st + o];
            return m.re * k.re - m.im * k.im;
        };
        fw += re(FF_WORK);
        fv += re(FF_VISC);
        if (level >= 1) fww += re(FF_WW);
        if (level >= 2) fuu += re(FF_UU);
    }
    out[0] = f0 * fw;
    out[1] = fv;
    // int f: f has only the terms nz, nz + 1, conjugates
    out[4] = 2.0 * (f0 * ph2 * gram(nz, nb - 1)).re;
    out[5] = 0.0;
    if (in.stick_k != 0.0 && in.sr != 1.0) stick_work(in, sc, out, n, ks, nz, gram);
    if (level == 0) return;
    out[2] = fww;
    double w1 = 0.0;  // int W: one term of each conjugate pair, twice its real part
    BB_UNROLL
    for (idx k = 0; k < nb; ++k) {
        idx jk = _conj_index(k, nz, ks);
        if (jk < k) continue;
        double v = (tab.PW[k] * ncplx(c[k]) * gram(k, nb - 1)).re;
        w1 += jk == k ? v : 2.0 * v;
    }
    out[3] = w1;
    if (level == 1) return;
    // int y^2 = int P^2 - 2 int P psi_d.u + int (psi_d.u)^2, with
    // int_0^T tau^j exp(mu tau) = T^(j+1) phi_j(mu T), phi_j(z) = int_0^1 s^j e^(z s) ds;
    // a rolling ball's y follows cy psi_d . u
    const double cy = seg.rolls ? seg.cy : 1.0;
    BB_UNROLL
    for (idx k = 0; k < nb; ++k) cb[k] = cy * (tab.Pd[k] * ncplx(c[k]));
    double uu = cy * cy * fuu;
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
    CVec c = s.c, ce = s.ce, ca = s.ca, cb = s.cb;
    FlowsIn all = in;
    all.exc = nullptr;
    _integrals_impl(all,
                    FlowsScratchOf<CVec, CMat, CMat, CVec>{mu, em, G, Cx, c, ce, ca, cb, s.phj},
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
    LocalArr<1, NB> mu, em, c, ce, ca, cb;
    LocalArr<NB, NB> G;
    LocalArr<NZ, NB> Cx;
    using L1 = LocalArr<1, NB>;
    _integrals_impl(in,
                    FlowsScratchOf<L1, LocalArr<NB, NB>, LocalArr<NZ, NB>, L1>{
                        mu, em, G, Cx, c, ce, ca, cb, phj},
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
