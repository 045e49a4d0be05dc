// A regenerative cut's delay history: the history step, the knots of W, the surface as one
// cubic per segment and the Gauss-Legendre flows.  cut_tables (run once per run) is
// computed in Python, in boringbar/simulate/regimes.py, with history_step (the same
// operations as history_step here, so both sides take the same H).
//
// Signatures:
//   double history_step(double tau, double dt);
//   std::tuple<double, double, double, double> hermite_at(double t0, double p0, double d0,
//                  double t1, double p1, double d1, double x0, bool cubic);
//   constexpr double GL_X[4], GL_W[4];
//   double quad_cut(double a, double b, const SegView& s, const Dashpots& dp, bool stick,
//                   const System& sys, Vec acc, bool steady);
//   struct Knots, struct History
//   void add_knot(History& hs, double t, Vec Xm, Vec Xp, Mat mk, double ttol, double node);
//   double surface_piece(double t, double t_end, History& hs, const CutConsts& cq,
//                   idx nr_eff, Segment& seg, idx j_now);
//
// The knot store grows: a Knots owns its rows and doubles them in place when full (in
// add_knot).  A Knots converts to a Mat view (kn.n0 rows, 5 columns), valid until it next
// grows.
#pragma once

#include <algorithm>
#include <cmath>
#include <tuple>
#include <vector>

#include "../arrays.hpp"
#include "consts.hpp"
#include "nmath.hpp"
#include "propagate.hpp"

namespace bb::exact {

// H = tau / ceil(tau / dt), at least two per revolution: a cut's knot spacing.
inline double history_step(double tau, double dt) {
    idx m = static_cast<idx>(std::ceil(tau / dt - 1e-9));
    return tau / static_cast<double>(std::max<idx>(2, m));
}

// The cubic Hermite interpolant on [t0, t1] of values p0, p1 and slopes d0 (right of t0),
// d1 (left of t1), as a cubic in x - x0: its 4 coefficients.  ``cubic`` false: the straight
// line through p0, p1.
inline std::tuple<double, double, double, double> hermite_at(double t0, double p0, double d0,
                                                             double t1, double p1, double d1,
                                                             double x0, bool cubic) {
    double ln = t1 - t0;
    double c2, c3;
    if (cubic) {
        c2 = (3.0 * (p1 - p0) / ln - 2.0 * d0 - d1) / ln;
        c3 = (2.0 * (p0 - p1) / ln + d0 + d1) / (ln * ln);
    } else {
        d0 = (p1 - p0) / ln;
        c2 = 0.0;
        c3 = 0.0;
    }
    return {p0 + x0 * (d0 + x0 * (c2 + x0 * c3)), d0 + x0 * (2.0 * c2 + 3.0 * c3 * x0),
            c2 + 3.0 * c3 * x0, c3};
}

// Gauss-Legendre nodes and weights on [0, 1], 4 points (the nodes as 0.5 -+ the nodes on
// [-1, 1] halved, each one rounding)
constexpr double GL_X[4] = {0.5 - 0.4305681557970263, 0.5 - 0.16999052179242816,
                            0.5 + 0.16999052179242816, 0.5 + 0.4305681557970263};
constexpr double GL_W[4] = {0.17392742256872692, 0.3260725774312731, 0.3260725774312731,
                            0.17392742256872692};

// Adds the flows over [a, b] of the cut segment of s (evaluated into s.q and s.X) to ``acc``
// (the slots of segment_integrals' ``out``) by 4-point Gauss-Legendre; returns the largest
// force at the nodes.  stick: the ball is stuck (its friction's work on the bar counted).
inline double quad_cut(double a, double b, const SegView& s, const Dashpots& dp, bool stick,
                       const System& sys, Vec acc, bool steady) {
    const Segment& seg = s.seg;
    const CVec q = s.q;
    const Vec X = s.X;
    const idx n = s.n;
    const Mat mk = s.mk, lvis = dp.l;
    const Vec cvis = dp.c;
    const double kappa = sys.carry.kstick, sr = sys.q.fric.sr;
    double fmax = 0.0;
    double hh = b - a;
    for (int g = 0; g < 4; ++g) {
        double tau = a + GL_X[g] * hh;
        double wg = GL_W[g] * hh;
        state_at(s, tau, q, X);
        double f = cut_force(seg, tau, X, n, mk, s.f0, s.om);
        fmax = pymax(fmax, f);
        auto [w, wd] = psi_dot(mk, MK_PSI_L, X, n);
        // psi_F . u', where the force works (W' but in an oriented cut)
        const double wdf = psi_dot(mk, MK_PSI_F, X, n).second;
        acc[0] += wg * f * wdf;
        double dv = 0.0;
        for (idx d = 0; d < lvis.n0; ++d) {
            double v = 0.0;
            for (idx j = 0; j < X.n; ++j) v += lvis(d, j) * X[j];
            dv += cvis[d] * v * v;
        }
        acc[1] += wg * dv;
        if (steady) {
            acc[2] += wg * w * w;
            acc[3] += wg * w;
            acc[4] += wg * f;
        }
        if (stick && sr != 1.0) {
            const double pdv = psi_dot(mk, MK_PSI_D, X, n).second;
            acc[5] += wg * (1.0 - sr) * freq_rhs(X, f, n, mk, kappa) * pdv;
        }
    }
    return fmax;
}

// The knot store: rows (t, W, W'-, W'+, node index or -1), owned, growing in place.
struct Knots {
    static constexpr idx NCOL = 5;
    std::vector<double> buf;
    idx n0 = 0;  // rows allocated
    idx n1 = NCOL;

    Knots() = default;
    explicit Knots(idx rows) : buf(static_cast<size_t>(rows * NCOL), 0.0), n0(rows) {}

    double& operator()(idx i, idx j) { return buf[static_cast<size_t>(i * NCOL + j)]; }
    double operator()(idx i, idx j) const { return buf[static_cast<size_t>(i * NCOL + j)]; }
    Mat view() { return {buf.data(), n0, NCOL}; }
    operator Mat() { return view(); }

    // twice the rows, the first nk kept, the rest zero
    void grow(idx nk) {
        std::vector<double> big(static_cast<size_t>(2 * n0 * NCOL), 0.0);
        std::copy(buf.begin(), buf.begin() + nk * NCOL, big.begin());
        buf.swap(big);
        n0 = 2 * n0;
    }
};

// A cut's delay history as the run keeps it: the knot store kn and the knots in use nk;
// for each past revolution k = 1 .. nrev, ip[k], the knot at or before t - k tau (-1:
// before the cut, where W = HIST_W0), and sc[k], its surface's cubic (surface_piece's
// scratch).
struct History {
    Knots kn;
    idx nk = 0;
    std::vector<idx> ip_buf;
    std::vector<double> sc_buf;
    Span1<idx> ip;
    Mat sc;

    History(idx rows, idx nrev)
        : kn(rows),
          ip_buf(static_cast<size_t>(nrev + 1), -1),
          sc_buf(static_cast<size_t>(nrev + 1) * 4, 0.0),
          ip{ip_buf.data(), nrev + 1},
          sc{sc_buf.data(), nrev + 1, 4} {}
    History(const History&) = delete;
    History& operator=(const History&) = delete;
};

// Store the knot (t, W, W'- from Xm, W'+ from Xp, node index or -1) in hs (mk: the bar's
// rows); one closer than ttol to the last knot replaces its value and W'+.  Drops knots no
// revolution needs any more when the store is full, and doubles it if that frees less than
// half.
inline void add_knot(History& hs, double t, Vec Xm, Vec Xp, Mat mk, double ttol, double node) {
    Knots& kn = hs.kn;
    idx nk = hs.nk;
    const Span1<idx> ip = hs.ip;
    const idx n = mk.n1;
    double w = 0.0;
    double wdm = 0.0;
    double wdp = 0.0;
    for (idx i = 0; i < n; ++i) {
        w += mk(MK_PSI_L, i) * Xp[i];
        wdm += mk(MK_PSI_L, i) * Xm[n + i];
        wdp += mk(MK_PSI_L, i) * Xp[n + i];
    }
    if (nk > 0 && t <= kn(nk - 1, 0) + ttol) {
        kn(nk - 1, 1) = w;
        kn(nk - 1, 3) = wdp;
        kn(nk - 1, 4) = pymax(kn(nk - 1, 4), node);
        return;
    }
    if (nk == kn.n0) {
        idx lo = nk;
        for (idx k = 1; k < ip.n; ++k) lo = ip[k] < lo ? ip[k] : lo;
        if (lo > 0) {
            for (idx i = lo; i < nk; ++i)
                for (idx c = 0; c < 5; ++c) kn(i - lo, c) = kn(i, c);
            nk -= lo;
            for (idx k = 1; k < ip.n; ++k) ip[k] -= lo;
        }
        if (nk > kn.n0 / 2) kn.grow(nk);
    }
    kn(nk, 0) = t;
    kn(nk, 1) = w;
    kn(nk, 2) = wdm;
    kn(nk, 3) = wdp;
    kn(nk, 4) = node;
    hs.nk = nk + 1;
}

// The surface min_k [k h_m + W(t + tau - k tau_d)] from t as one cubic in tau, into seg.s,
// and the time (<= t_end) up to which it is one cubic: the next delayed knot of any
// revolution, or where another revolution becomes the minimum.  Advances the pointers
// hs.ip[k]; hs.sc[k] receives revolution k's cubic.  Revolutions beyond nr_eff are followed
// but not compared.  j_now: the node t is on (-1: none).
inline double surface_piece(double t, double t_end, History& hs, const CutConsts& cq,
                            idx nr_eff, Segment& seg, idx j_now) {
    const Mat kn = hs.kn.view(), sc = hs.sc;
    const idx nk = hs.nk;
    const Span1<idx> ip = hs.ip;
    const double ttol = cq.ttol, feed = cq.feed, w_before = cq.w0, tau_d = cq.tau;
    const idx nrev = cq.nrev, m_rev = cq.mrev;
    const bool cubic = cq.cubic;
    double t_piece = t_end;
    for (idx k = 1; k < nrev + 1; ++k) {
        double kt = static_cast<double>(k) * tau_d;
        idx i = ip[k];
        while (i + 1 < nk && kn(i + 1, 0) + kt <= t + ttol) i += 1;
        ip[k] = i;
        if (k > nr_eff) continue;
        if (i < 0) {  // before the cut: the surface W = HIST_W0
            sc(k, 0) = static_cast<double>(k) * feed + w_before;
            sc(k, 1) = 0.0;
            sc(k, 2) = 0.0;
            sc(k, 3) = 0.0;
        } else {
            double x0 = (t - kt) - kn(i, 0);
            if (j_now >= 0 && kn(i, 4) == static_cast<double>(j_now - k * m_rev)) x0 = 0.0;
            auto [c0, c1, c2, c3] = hermite_at(kn(i, 0), kn(i, 1), kn(i, 3), kn(i + 1, 0),
                                               kn(i + 1, 1), kn(i + 1, 2), x0, cubic);
            sc(k, 0) = static_cast<double>(k) * feed + c0;
            sc(k, 1) = c1;
            sc(k, 2) = c2;
            sc(k, 3) = c3;
        }
        if (i + 1 < nk) {
            double tn = kn(i + 1, 0) + kt;
            if (t + ttol < tn && tn < t_piece - ttol) t_piece = tn;
        }
    }
    // the minimising revolution at t (a tie goes to the one falling faster)
    idx km = 1;
    double tie = 1e-12 * feed;
    for (idx k = 2; k < nr_eff + 1; ++k) {
        if (sc(k, 0) < sc(km, 0) - tie ||
            (std::fabs(sc(k, 0) - sc(km, 0)) <= tie && sc(k, 1) < sc(km, 1)))
            km = k;
    }
    // where another revolution drops below it: 16 samples, then bisection on the cubic
    double T = t_piece - t;
    for (idx k = 1; k < nr_eff + 1; ++k) {
        if (k == km) continue;
        double lo = 0.0;
        for (int j = 1; j < 17; ++j) {
            double x = T * static_cast<double>(j) / 16.0;
            double d = 0.0;
            for (int c = 3; c >= 0; --c) d = d * x + (sc(k, c) - sc(km, c));
            if (d < 0.0) {
                double hi = x;
                for (int it = 0; it < 60; ++it) {
                    double mid = 0.5 * (lo + hi);
                    d = 0.0;
                    for (int c = 3; c >= 0; --c) d = d * mid + (sc(k, c) - sc(km, c));
                    if (d < 0.0)
                        hi = mid;
                    else
                        lo = mid;
                    if (hi - lo <= ttol) break;
                }
                if (hi > ttol && hi < T) T = hi;
                break;
            }
            lo = x;
        }
    }
    for (int c = 0; c < 4; ++c) seg.s[c] = sc(km, c);
    return T < t_piece - t ? t + T : t_piece;
}

}  // namespace bb::exact
