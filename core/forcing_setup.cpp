// boringbar.core.forcing_setup: the part of the exact integrator's per-run setup that
// depends on the forcing (src/boringbar/simulate/regimes.py's prepare keeps the rest per
// system): each regime's forced response Z, the basis exponents' inverse sums with
// +-i Omega, the forcing's column of the derivative bounds and the longest grid step worth
// trying.  Complex arithmetic is nmath.hpp's, as the kernel's.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cmath>
#include <complex>
#include <string>
#include <utility>
#include <vector>

#include "bind_util.hpp"
#include "exact/nmath.hpp"

namespace bb::bind {
namespace {

using exact::ncplx;
using cd = std::complex<double>;
template <int D>
using Real = nb::ndarray<const double, nb::ndim<D>, nb::c_contig, nb::device::cpu>;
template <int D>
using Cplx = nb::ndarray<const cd, nb::ndim<D>, nb::c_contig, nb::device::cpu>;

// z = (i Omega I - A)^-1 b f0 for one regime (nz x nz, row-major), by Gaussian
// elimination with partial pivoting on |.|; false if a pivot is zero.
bool forced_response(const double* A, const double* b, int nz, double om, double f0,
                     ncplx* z) {
    std::vector<ncplx> M(size_t(nz) * nz);
    for (int i = 0; i < nz; ++i) {
        for (int j = 0; j < nz; ++j) M[size_t(i) * nz + j] = ncplx(-A[i * nz + j], 0.0);
        M[size_t(i) * nz + i].im += om;
        z[i] = ncplx(b[i] * f0, 0.0);
    }
    for (int k = 0; k < nz; ++k) {
        int piv = k;
        for (int i = k + 1; i < nz; ++i)
            if (exact::abs(M[size_t(i) * nz + k]) > exact::abs(M[size_t(piv) * nz + k])) piv = i;
        if (exact::abs(M[size_t(piv) * nz + k]) == 0.0) return false;
        if (piv != k) {
            for (int j = 0; j < nz; ++j) std::swap(M[size_t(k) * nz + j], M[size_t(piv) * nz + j]);
            std::swap(z[k], z[piv]);
        }
        for (int i = k + 1; i < nz; ++i) {
            const ncplx l = M[size_t(i) * nz + k] / M[size_t(k) * nz + k];
            for (int j = k; j < nz; ++j) M[size_t(i) * nz + j] -= l * M[size_t(k) * nz + j];
            z[i] -= l * z[k];
        }
    }
    for (int i = nz - 1; i >= 0; --i) {
        ncplx s = z[i];
        for (int j = i + 1; j < nz; ++j) s -= M[size_t(i) * nz + j] * z[j];
        z[i] = s / M[size_t(i) * nz + i];
    }
    return true;
}

// isum of one regime: the per-system entries (mode_sums) with those of +-i Omega,
// 1 / (mu_a + mu_b) over mu = (lambda, i Omega, -i Omega, 0), 0 where the sum is 0.
void inverse_sums(const cd* msum, const cd* lam, int nz, double om, cd* out) {
    const int nb = nz + 3;
    std::vector<ncplx> mu(static_cast<size_t>(nb));
    for (int k = 0; k < nz; ++k) mu[k] = lam[k];
    mu[nz] = ncplx(0.0, om);
    mu[nz + 1] = ncplx(0.0, -om);
    mu[nz + 2] = ncplx(0.0, 0.0);
    for (int i = 0; i < nb * nb; ++i) out[i] = msum[i];
    auto put = [&](int a, int b) {
        const ncplx s = mu[a] + mu[b];
        if (s.re != 0.0 || s.im != 0.0) out[a * nb + b] = out[b * nb + a] = 1.0 / s;
    };
    for (int b = nz; b <= nz + 1; ++b)
        for (int a = 0; a <= b; ++a) put(a, b);
    put(nz, nz + 2);
    put(nz + 1, nz + 2);
}

// The longest step worth trying, 2^levmax h, from the regime's largest and smallest
// nonzero |lambda|.
std::int64_t level(double hi, double lo, double om, int levels) {
    const double ratio = hi / (om > lo ? om : lo);
    std::int64_t lv = 0;
    while (lv < levels - 1 && ratio >= std::ldexp(1.0, int(lv + 1))) ++lv;
    return lv;
}

// A system's regimes as the forcing's setup reads them (boringbar.core.Regimes; the
// per-system part that regimes.py's system_regimes keeps): each regime's state matrix A,
// forcing input B and eigenvalues lam, the inverse sums and derivative bounds without the
// forcing's entries, the bar's (psi_d, psi_L), and each regime's largest and smallest
// nonzero |lambda|.  Its arrays are checked against each other where it is used.
struct Regimes {
    Real<3> A;
    Real<2> B;
    Cplx<2> lam;
    Cplx<3> mode_sums;
    Real<3> mode_bounds;
    Real<2> psis;
    Real<1> hi, lo;
};

nb::tuple forcing_setup(const Regimes& g, double om, double f0, int levels) {
    const size_t R = g.A.shape(0), nz = g.A.shape(1), nb = nz + 3;
    require(g.A.shape(2) == nz && nz >= 1, "A must be (R, nz, nz)");
    require(g.B.shape(0) == R && g.B.shape(1) == nz, "B must be (R, nz) as A");
    require(g.lam.shape(0) == R && g.lam.shape(1) == nz, "lam must be (R, nz) as A");
    const Cplx<3>& msum = g.mode_sums;
    require(msum.shape(0) == R && msum.shape(1) == nb && msum.shape(2) == nb,
            "mode_sums must be (R, nz + 3, nz + 3)");
    const Real<3>& bnd0 = g.mode_bounds;
    require(bnd0.shape(0) == R && bnd0.shape(1) == 4 && bnd0.shape(2) == nz + 1,
            "mode_bounds must be (R, 4, nz + 1)");
    require(g.psis.shape(0) == 2 && g.psis.shape(1) <= nz, "psis must be (2, n), n <= nz");
    require(g.hi.shape(0) == R && g.lo.shape(0) == R, "hi and lo must have R entries");
    require(std::isfinite(om) && om >= 0.0 && std::isfinite(f0), "Omega >= 0 and F0 finite");
    require(levels >= 1 && levels <= 62, "levels must be in [1, 62]");
    const size_t n = g.psis.shape(1);
    std::vector<cd> Z(R * nz), isum(R * nb * nb);
    std::vector<double> bnd(bnd0.data(), bnd0.data() + R * 4 * (nz + 1));
    std::vector<std::int64_t> levmax(R);
    std::vector<ncplx> z(nz);
    for (size_t r = 0; r < R; ++r) {
        require(forced_response(g.A.data() + r * nz * nz, g.B.data() + r * nz, int(nz), om, f0,
                                z.data()),
                "regime " + std::to_string(r) + ": i Omega I - A is singular");
        for (size_t k = 0; k < nz; ++k) Z[r * nz + k] = z[k];
        inverse_sums(msum.data() + r * nb * nb, g.lam.data() + r * nz, int(nz), om,
                     isum.data() + r * nb * nb);
        for (size_t row = 0; row < 2; ++row) {  // psi_d . Z, then psi_L . Z
            ncplx s(0.0, 0.0);
            for (size_t i = 0; i < n; ++i) s += exact::promote(g.psis(row, i)) * z[i];
            const double a = exact::abs(s);
            bnd[(r * 4 + row) * (nz + 1) + nz] = om * om * om * om * a;
            bnd[(r * 4 + row + 2) * (nz + 1) + nz] = om * om * om * a;
        }
        levmax[r] = level(g.hi(r), g.lo(r), om, levels);
    }
    return nb::make_tuple(owned_array<cd, 2>(std::move(Z), {R, nz}),
                          owned_array<cd, 3>(std::move(isum), {R, nb, nb}),
                          owned_array<double, 3>(std::move(bnd), {R, 4, nz + 1}),
                          owned_array<std::int64_t, 1>(std::move(levmax), {R}));
}

}  // namespace

void bind_forcing_setup(nb::module_& m) {
    nb::class_<Regimes>(m, "Regimes",
                        "A system's regimes as forcing_setup reads them: each regime's A "
                        "(R, nz, nz), B (R, nz) and eigenvalues lam (R, nz), the per-system "
                        "mode_sums (R, nz + 3, nz + 3) and mode_bounds (R, 4, nz + 1) "
                        "(simulate/regimes.py), psis = (psi_d, psi_L) (2, n), and hi, lo (R,) "
                        "the regimes' largest and smallest nonzero |lambda|.")
        .def(nb::init<Real<3>, Real<2>, Cplx<2>, Cplx<3>, Real<3>, Real<2>, Real<1>, Real<1>>(),
             nb::arg("A"), nb::arg("B"), nb::arg("lam"), nb::arg("mode_sums"),
             nb::arg("mode_bounds"), nb::arg("psis"), nb::arg("hi"), nb::arg("lo"));
    m.def("forcing_setup", &forcing_setup, nb::arg("regimes"), nb::arg("omega"), nb::arg("f0"),
          nb::arg("levels"),
          "(Z, isum, bnd, levmax): the exact integrator's setup that depends on the forcing "
          "F0 sin(Omega t), for a system's regimes (Regimes) and the forcing's Omega and F0; "
          "levels: the grid's levels (GRID_LEVELS).");
}

}  // namespace bb::bind
