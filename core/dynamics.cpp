// boringbar.core.regime_matrix and impact_matrix: the equations of motion as matrices, for
// the periodic orbits' shooting (src/boringbar/orbits/shooting.py).  Each is built from the
// definitions RK4 steps with, so shooting does not write the dynamics again: the regime
// matrix from the stage derivative (rk4.hpp's derivative_with) at the unit vectors of the
// augmented state, which is exact because the equations are linear in it between impacts
// and with the friction force held; the impact matrix from the wall's impact law
// (model.hpp's impact_law and rk4.hpp's jump_modes) applied to a unit relative velocity.
//
// The augmented state is z = [X, sin Omega t, cos Omega t, 1], X = [u_1..u_n, u_1'..u_n',
// aux, aux'] as the integrators keep it (aux: the ball's y or the absorber's x_a; zero
// rows and columns for the solid and the locked bar).
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cmath>
#include <string>
#include <vector>

#include "bind_util.hpp"
#include "rk4.hpp"

namespace bb::bind {
namespace {

namespace L = bb::layout;
namespace R = bb::rk4;
using P = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Matrix = nb::ndarray<nb::numpy, double, nb::ndim<2>>;

// The unpacked parameters of p, once its length, mode count and case are checked (the
// stage derivative indexes the mode blocks by the count and branches on the case).
R::Params params_of(const P& p) {
    require(p.shape(0) == size_t(L::P_SIZE),
            "p must have " + std::to_string(L::P_SIZE) + " entries, got " +
                std::to_string(p.shape(0)));
    const double* d = p.data();
    const double n = d[L::N_MODES], kase = d[L::CASE];
    require(std::isfinite(n) && n == std::floor(n) && n >= 1 && n <= L::NMAX,
            "p[N_MODES] must be an integer in [1, " + std::to_string(L::NMAX) + "]");
    require(std::isfinite(kase) && kase == std::floor(kase) && kase >= L::SOLID &&
                kase <= L::LOCKED,
            "p[CASE] must be one of SOLID, BALL, TMD, LOCKED");
    // a regime's matrix is the sliding law's of its direction (sdir), not the stick law's
    require(d[L::STICK_BAND] == 0.0, "p[STICK_BAND] must be 0 for a regime's matrix");
    return R::unpack(d, 1e-6);  // the step only sets the forcing's rotation, unused here
}

// A NumPy (rows, cols) array of zeros that owns its memory.
Matrix zeros(size_t rows, size_t cols) {
    auto* data = new std::vector<double>(rows * cols, 0.0);
    nb::capsule owner(data, [](void* v) noexcept { delete static_cast<std::vector<double>*>(v); });
    return Matrix(data->data(), {rows, cols}, owner);
}

Matrix regime_matrix(const P& p, double sdir) {
    require(sdir == -1.0 || sdir == 0.0 || sdir == 1.0, "sdir must be -1, 0 or 1");
    const R::Params q = params_of(p);
    const R::Shape<0, -1> sh(q);
    const int nx = sh.nx(), nz = nx + 3;
    Matrix A = zeros(size_t(nz), size_t(nz));
    auto a = A.view();
    double X[R::NX_MAX], Kd[R::NX_MAX];
    auto column = [&](int j, double f, double ysign) {
        R::derivative_with<0, -1>(q, sh, X, f, Kd, ysign);
        for (int i = 0; i < nx; ++i) a(i, j) = Kd[i];
    };
    for (int j = 0; j < nx; ++j) {
        for (int i = 0; i < nx; ++i) X[i] = i == j ? 1.0 : 0.0;
        column(j, 0.0, 0.0);  // no friction force: the linear part
    }
    for (int i = 0; i < nx; ++i) X[i] = 0.0;
    column(nx, q.f0, 0.0);      // the force F0 sin(Omega t) at the tip
    column(nx + 2, 0.0, sdir);  // F_b = -F_c sdir, held
    a(nx, nx + 1) = q.om;       // (sin Omega t)' = Omega cos Omega t
    a(nx + 1, nx) = -q.om;
    return A;
}

Matrix impact_matrix(const P& p) {
    const R::Params q = params_of(p);
    const R::Shape<0, -1> sh(q);
    const int nx = sh.nx(), iyd = sh.iyd();
    Matrix Rm = zeros(size_t(nx), size_t(nx));
    auto r = Rm.view();
    double X[R::NX_MAX];
    for (int j = 0; j < nx; ++j) {
        for (int i = 0; i < nx; ++i) X[i] = i == j ? 1.0 : 0.0;
        if (j == iyd && sh.ball()) {  // the law is linear in the arriving velocity
            const ImpactJump jump = impact_law(X[iyd], q.ball.e, q.ball.meff);
            X[iyd] = jump.yd;
            R::jump_modes(q, sh.n(), X, jump.g);
        }
        for (int i = 0; i < nx; ++i) r(i, j) = X[i];
    }
    return Rm;
}

}  // namespace

void bind_dynamics(nb::module_& m) {
    m.def("regime_matrix", &regime_matrix, nb::arg("p"), nb::arg("sdir"),
          "A of z' = A z between impacts, z = [X, sin Omega t, cos Omega t, 1] (X as the "
          "integrators keep it, 2n + 2 entries), the ball sliding in direction sdir (-1, 0, "
          "1: F_b = -F_c sdir held); built from RK4's stage derivative.");
    m.def("impact_matrix", &impact_matrix, nb::arg("p"),
          "R, X+ = R X- at an impact of a ball bar (the identity for the other bars): "
          "y' -> -e y', u_i' -> u_i' + (1 + e) m_eff psi_d,i y' / M_i, from the wall's "
          "impact law.");
}

}  // namespace bb::bind
