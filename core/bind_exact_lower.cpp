// boringbar._core._exact_lower: a TEST HOOK, not an API.  It exposes the exact kernel's lower
// layer (exact/nmath.hpp, propagate.hpp, events.hpp, cut.hpp) function by function, with
// the numba functions' parameters, so that tests/test_exact_lower.py can compare each with
// its numba original bit for bit on inputs taken from real runs.  Arrays are checked for
// dtype, shape and contiguity (bind_util.hpp); sizes that the functions index with (n, nz,
// the regime r) are the caller's to get right, as in the numba functions.  ``seg`` is the
// numba layout, 18 floats (SEG_SIZE), converted to and from exact::Segment.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/complex.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <complex>
#include <tuple>
#include <vector>

#include "bind_util.hpp"
#include "exact/consts.hpp"
#include "exact/cut.hpp"
#include "exact/events.hpp"
#include "exact/nmath.hpp"
#include "exact/propagate.hpp"

namespace bb::bind {

namespace {

namespace E = bb::exact;
using E::ncplx;
using E::Segment;

template <class A>
Segment seg_in(const A& a) {
    const double* d = checked<double>(a, "seg", {E::SEG_SIZE});
    Segment s;
    for (int i = 0; i < E::SEG_SIZE; ++i) s.at(i) = d[i];
    return s;
}

void seg_out(Segment& s, const Out& a) {
    double* d = checked<double>(a, "seg", {E::SEG_SIZE});
    for (int i = 0; i < E::SEG_SIZE; ++i) d[i] = s.at(i);
}

Vec vec(const In& a, const char* name) { return span1<double>(a, name); }
Mat mat(const In& a, const char* name) { return span2<double>(a, name); }
CVec cvec(const In& a, const char* name) { return span1<cplx>(a, name); }
CMat cmat(const In& a, const char* name) { return span2<cplx>(a, name); }
CArr3 carr3(const In& a, const char* name) { return span3<cplx>(a, name); }

// prepare's arrays of a regime set, as the kernel takes them
struct Prep {
    CMat lam;
    CArr3 V;
    CMat Z;
    Mat D;
    CMat bq;
};

Prep prep(const In& lam, const In& V, const In& Z, const In& D, const In& bq) {
    return {cmat(lam, "lam"), carr3(V, "V"), cmat(Z, "Z"), mat(D, "D"), cmat(bq, "bq")};
}

cplx out(ncplx z) { return cplx(z.re, z.im); }

}  // namespace

void bind_exact_lower(nb::module_& m) {
    nb::module_ t = m.def_submodule(
        "_exact_lower",
        "Test hook (tests/test_exact_lower.py): the exact kernel's lower layer, function by "
        "function, for bit-for-bit comparisons with the numba originals.  Not an API.");

    // --- constants and numba's arithmetic (nmath.hpp) -------------------------------------
    t.def("constants", [] {
        std::vector<double> recip(E::RECIP, E::RECIP + 24), rfact(E::RFACT, E::RFACT + 20);
        std::vector<double> glx(E::GL_X, E::GL_X + 4), glw(E::GL_W, E::GL_W + 4);
        return std::make_tuple(recip, rfact, glx, glw, E::GRID_PER_PERIOD);
    });
    // (z * w, z / w, z + w, z - w, z * x, x * z, z + x, x + z, z - x, x - z, z / x, x / z,
    //  -z, conj z, exp z, |z|)
    t.def("complex_ops", [](cplx z, cplx w, double x) {
        ncplx a = z, b = w;
        auto div = [](ncplx p, ncplx q) {
            try {
                return out(p / q);
            } catch (const E::ComplexZeroDivision&) {
                return cplx(-7.0, -7.0);  // the marker the test expects for numba's raise
            }
        };
        auto divx = [](ncplx p, double q) {
            try {
                return out(p / q);
            } catch (const E::ComplexZeroDivision&) {
                return cplx(-7.0, -7.0);
            }
        };
        auto xdiv = [](double p, ncplx q) {
            try {
                return out(p / q);
            } catch (const E::ComplexZeroDivision&) {
                return cplx(-7.0, -7.0);
            }
        };
        return std::vector<cplx>{out(a * b),      out(div(a, b)),   out(a + b),
                                 out(a - b),      out(a * x),       out(x * a),
                                 out(a + x),      out(x + a),       out(a - x),
                                 out(x - a),      divx(a, x),       xdiv(x, a),
                                 out(-a),         out(a.conjugate()), out(E::cexp(a)),
                                 cplx(E::abs(a), 0.0)};
    });
    t.def("ipow", [](double x, int k) { return E::ipow(x, k); });

    // --- propagate.hpp -----------------------------------------------------------------
    t.def("phis", [](cplx x) {
        auto [e, p1, p2, p3, p4] = E::phis(ncplx(x));
        return std::make_tuple(out(e), out(p1), out(p2), out(p3), out(p4));
    });
    t.def("surface_at", [](const In& seg, double tau) { return E::surface_at(seg_in(seg), tau); });
    t.def("state_at", [](idx r, const In& q0, const In& seg, double tau, double om, const In& lam,
                         const In& V, idx ks, const In& Z, const In& D, const In& bq,
                         const Out& q, const Out& X) {
        Prep P = prep(lam, V, Z, D, bq);
        return out(E::state_at(r, cvec(q0, "q0"), seg_in(seg), tau, om, P.lam, P.V, ks, P.Z,
                               P.D, P.bq, span1<cplx>(q, "q"), span1<double>(X, "X")));
    });
    t.def("state_at2", [](idx r, const In& q0, const In& seg, double tau, double om,
                          const In& lam, const In& V, idx ks, const In& Z, const In& D,
                          const In& bq, const Out& q, const Out& X, const Out& Xd) {
        Prep P = prep(lam, V, Z, D, bq);
        E::state_at2(r, cvec(q0, "q0"), seg_in(seg), tau, om, P.lam, P.V, ks, P.Z, P.D, P.bq,
                     span1<cplx>(q, "q"), span1<double>(X, "X"), span1<double>(Xd, "Xd"));
    });
    t.def("cut_force", [](const In& seg, double tau, const In& X, idx n, const In& mk, double f0,
                          double om) {
        return E::cut_force(seg_in(seg), tau, vec(X, "X"), n, mat(mk, "mk"), f0, om);
    });
    t.def("freq_rhs", [](const In& X, double f, idx n, const In& mk, double kappa) {
        return E::freq_rhs(vec(X, "X"), f, n, mat(mk, "mk"), kappa);
    });
    // variant: 0 segment_integrals (n, ks given), 1 segment_integrals_1, 2 _2
    t.def("segment_integrals",
          [](int variant, idx r, const In& q0, cplx ph, double T, double fb, double om, double f0,
             const In& lam, const In& VF, const In& Z, const In& D, idx n, const In& mk,
             const In& lvis, const In& cvis, double stick_k, double sr, const Out& me,
             const Out& G, const Out& Cx, const Out& cf, const Out& ca, const Out& cb,
             const Out& outv, const In& isum, idx level, idx ks, const In& seg, const Out& phj) {
              CMat lamv = cmat(lam, "lam"), Zv = cmat(Z, "Z");
              CArr3 Vv = carr3(VF, "VF");
              Mat Dv = mat(D, "D");
              CVec q0v = cvec(q0, "q0");
              Segment s = seg_in(seg);
              CMat mev = span2<cplx>(me, "me"), Gv = span2<cplx>(G, "G"),
                   Cxv = span2<cplx>(Cx, "Cx");
              CVec cfv = span1<cplx>(cf, "cf"), cav = span1<cplx>(ca, "ca"),
                   cbv = span1<cplx>(cb, "cb"), phjv = span1<cplx>(phj, "phj");
              Vec ov = span1<double>(outv, "out");
              CArr3 is = carr3(isum, "isum");
              Mat mkv = mat(mk, "mk"), lv = mat(lvis, "lvis");
              Vec cv = vec(cvis, "cvis");
              if (variant == 1)
                  E::segment_integrals_1(r, q0v, ph, T, fb, om, f0, lamv, Vv, Zv, Dv, mkv, lv,
                                         cv, stick_k, sr, mev, Gv, Cxv, cfv, cav, cbv, ov, is,
                                         level, s, phjv);
              else if (variant == 2)
                  E::segment_integrals_2(r, q0v, ph, T, fb, om, f0, lamv, Vv, Zv, Dv, mkv, lv,
                                         cv, stick_k, sr, mev, Gv, Cxv, cfv, cav, cbv, ov, is,
                                         level, s, phjv);
              else
                  E::segment_integrals(r, q0v, ph, T, fb, om, f0, lamv, Vv, Zv, Dv, n, mkv,
                                       lv, cv, stick_k, sr, mev, Gv, Cxv, cfv, cav, cbv, ov, is,
                                       level, ks, s, phjv);
          });

    // --- events.hpp --------------------------------------------------------------------
    t.def("g_value", [](idx kind, double tau, const In& seg, idx r, const In& q0, const In& lam,
                        const In& V, idx ks, const In& Z, const In& D, const In& bq,
                        const Out& q, const Out& X, idx n, const In& mk, double f0, double om) {
        Prep P = prep(lam, V, Z, D, bq);
        return E::g_value(kind, tau, seg_in(seg), r, cvec(q0, "q0"), P.lam, P.V, ks, P.Z, P.D,
                          P.bq, span1<cplx>(q, "q"), span1<double>(X, "X"), n, mat(mk, "mk"),
                          f0, om);
    });
    t.def("gd", [](idx kind, double tau, const In& seg, idx r, const In& q0, const In& lam,
                   const In& V, idx ks, const In& Z, const In& D, const In& bq, const Out& q,
                   const Out& X, const Out& Xd, idx n, const In& mk, double f0, double om) {
        Prep P = prep(lam, V, Z, D, bq);
        return E::_gd(kind, tau, seg_in(seg), r, cvec(q0, "q0"), P.lam, P.V, ks, P.Z, P.D, P.bq,
                      span1<cplx>(q, "q"), span1<double>(X, "X"), span1<double>(Xd, "Xd"), n,
                      mat(mk, "mk"), f0, om);
    });
    t.def("hermite", &E::hermite);
    t.def("hermite5", &E::hermite5);
    // variant: 0 find_root, 1 find_root_1, 2 find_root_2, 3 find_root_any
    t.def("find_root",
          [](int variant, idx kind, double a, double ga, double b, double gb, const In& seg, idx r,
             const In& q0, const In& lam, const In& V, idx ks, const In& Z, const In& D,
             const In& bq, const Out& q, const Out& X, const Out& Xd, idx n, const In& mk,
             double f0, double om, double c0) {
              Prep P = prep(lam, V, Z, D, bq);
              Segment s = seg_in(seg);
              CVec q0v = cvec(q0, "q0"), qv = span1<cplx>(q, "q");
              Vec Xv = span1<double>(X, "X"), Xdv = span1<double>(Xd, "Xd");
              Mat mkv = mat(mk, "mk");
              if (variant == 1)
                  return E::find_root_1(kind, a, ga, b, gb, s, r, q0v, P.lam, P.V, P.Z, P.D, P.bq,
                                        qv, Xv, Xdv, mkv, f0, om, c0);
              if (variant == 2)
                  return E::find_root_2(kind, a, ga, b, gb, s, r, q0v, P.lam, P.V, P.Z, P.D, P.bq,
                                        qv, Xv, Xdv, mkv, f0, om, c0);
              if (variant == 3)
                  return E::find_root_any(kind, a, ga, b, gb, s, r, q0v, P.lam, P.V, ks, P.Z, P.D,
                                          P.bq, qv, Xv, Xdv, n, mkv, f0, om, c0);
              return E::find_root(kind, a, ga, b, gb, s, r, q0v, P.lam, P.V, ks, P.Z, P.D, P.bq,
                                  qv, Xv, Xdv, n, mkv, f0, om, c0);
          });
    // variant: 0 w_extremum, 1 w_extremum_1, 2 w_extremum_2, 3 w_extremum_any
    t.def("w_extremum",
          [](int variant, double a, double ga, double b, double gb, double c0, double h,
             const In& seg, idx r, const In& q0, const In& lam, const In& V, idx ks, const In& Z,
             const In& D, const In& bq, const Out& q, const Out& X, const Out& Xd, idx n,
             const In& mk, double om) {
              Prep P = prep(lam, V, Z, D, bq);
              Segment s = seg_in(seg);
              CVec q0v = cvec(q0, "q0"), qv = span1<cplx>(q, "q");
              Vec Xv = span1<double>(X, "X"), Xdv = span1<double>(Xd, "Xd");
              Mat mkv = mat(mk, "mk");
              if (variant == 1)
                  return E::w_extremum_1(a, ga, b, gb, c0, h, s, r, q0v, P.lam, P.V, P.Z, P.D,
                                         P.bq, qv, Xv, Xdv, mkv, om);
              if (variant == 2)
                  return E::w_extremum_2(a, ga, b, gb, c0, h, s, r, q0v, P.lam, P.V, P.Z, P.D,
                                         P.bq, qv, Xv, Xdv, mkv, om);
              if (variant == 3)
                  return E::w_extremum_any(a, ga, b, gb, c0, h, s, r, q0v, P.lam, P.V, ks, P.Z,
                                           P.D, P.bq, qv, Xv, Xdv, n, mkv, om);
              return E::w_extremum(a, ga, b, gb, c0, h, s, r, q0v, P.lam, P.V, ks, P.Z, P.D,
                                   P.bq, qv, Xv, Xdv, n, mkv, om);
          });
    t.def("quad_range", &E::quad_range);
    t.def("cubic_range", &E::_cubic_range);
    t.def("may_graze", [](double a, double b, const In& ev_a, const In& ev_b, double half,
                          double b4) {
        return E::may_graze(a, b, vec(ev_a, "ev_a"), vec(ev_b, "ev_b"), half, b4);
    });
    t.def("w_may_exceed", &E::w_may_exceed);
    t.def("wall_step",
          [](double a, double b, const In& ev_a, const In& ev_b, bool watch_v, bool watch_ext,
             double half, const In& seg, idx r, const In& q0, const In& lam, const In& V, idx ks,
             const In& Z, const In& D, const In& bq, const Out& qs, const Out& dX, const Out& Xd,
             idx n, const In& mk, double f0, double om, double ydd_a, double ydd_b) {
              Prep P = prep(lam, V, Z, D, bq);
              return E::wall_step(a, b, vec(ev_a, "ev_a"), vec(ev_b, "ev_b"), watch_v, watch_ext,
                                  half, seg_in(seg), r, cvec(q0, "q0"), P.lam, P.V, ks, P.Z, P.D,
                                  P.bq, span1<cplx>(qs, "qs"), span1<double>(dX, "dX"),
                                  span1<double>(Xd, "Xd"), n, mat(mk, "mk"), f0, om, ydd_a,
                                  ydd_b);
          });

    // --- cut.hpp -----------------------------------------------------------------------
    t.def("history_step", &E::history_step);
    t.def("hermite_at", &E::hermite_at);
    t.def("quad_cut",
          [](double a, double b, const In& seg, idx r, const In& q0, const In& lam, const In& V,
             idx ks, const In& Z, const In& D, const In& bq, const Out& q, const Out& X, idx n,
             const In& mk, const In& lvis, const In& cvis, bool stick, double kappa, double sr,
             const Out& acc, bool steady) {
              Prep P = prep(lam, V, Z, D, bq);
              return E::quad_cut(a, b, seg_in(seg), r, cvec(q0, "q0"), P.lam, P.V, ks, P.Z, P.D,
                                 P.bq, span1<cplx>(q, "q"), span1<double>(X, "X"), n,
                                 mat(mk, "mk"), mat(lvis, "lvis"), vec(cvis, "cvis"), stick,
                                 kappa, sr, span1<double>(acc, "acc"), steady);
          });
    // add_knot on a copy of kn: returns (the store's rows, nk); ip is updated in place
    t.def("add_knot", [](const In& kn, idx nk, const Out& ip, double t, const In& Xm,
                         const In& Xp, idx n, const In& mk, double ttol, double node) {
        Mat k0 = span2<double>(kn, "kn", -1, 5);
        E::Knots store(k0.n0);
        std::copy(k0.d, k0.d + k0.n0 * 5, store.buf.begin());
        auto [ks, nk1] = E::add_knot(store, nk, span1<idx>(ip, "ip"), t, vec(Xm, "Xm"),
                                     vec(Xp, "Xp"), n, mat(mk, "mk"), ttol, node);
        return std::make_tuple(ks.buf, ks.n0, nk1);
    });
    t.def("surface_piece",
          [](double t, double t_end, double ttol, const In& kn, idx nk, const Out& ip,
             const Out& sc, idx nrev, idx nr_eff, double feed, double w_before, double tau_d,
             const Out& seg, idx j_now, idx m_rev, bool cubic) {
              Segment s = seg_in(seg);
              double r = E::surface_piece(t, t_end, ttol, span2<double>(kn, "kn", -1, 5), nk,
                                          span1<idx>(ip, "ip"), span2<double>(sc, "sc", -1, 4),
                                          nrev, nr_eff, feed, w_before, tau_d, s, j_now, m_rev,
                                          cubic);
              seg_out(s, seg);
              return r;
          });
}

}  // namespace bb::bind
