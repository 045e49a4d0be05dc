// boringbar.core.regime_matrix, impact_matrix, regime_stack, dashpots and carried_kappa:
// the equations of motion as matrices, for the periodic orbits' shooting
// (src/boringbar/orbits/shooting.py) and the exact integrator's regimes
// (src/boringbar/simulate/regimes.py), and the ball's carrying term, whose inverse the
// packing stores as the impact's effective mass (simulate/engine.py).  Each is built
// from the definitions RK4 steps with, so none writes the dynamics again: the regime
// matrices from the stage derivative (dynamics.hpp's derivative_with) at unit vectors of
// the state, which is exact because the equations are linear in it between impacts and
// with the friction force held; the impact matrix from the wall's impact law (model.hpp's
// impact_law and dynamics.hpp's jump_modes) applied to a unit relative velocity; the
// dashpots from dynamics.hpp's rows of the stage's dissipated power; carried_kappa is
// dynamics.hpp's, which the integrators hold and roll the ball with.
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
#include "dynamics.hpp"
#include "rk4.hpp"

namespace bb::bind {
namespace {

namespace L = bb::layout;
namespace R = bb::rk4;
using P = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Matrix = nb::ndarray<nb::numpy, double, nb::ndim<2>>;
using Stack = nb::ndarray<nb::numpy, double, nb::ndim<3>>;

// p's entries, once its length, mode count and case are checked (unpack indexes the mode
// blocks by the count, and the stage derivative branches on the case).
const double* shaped(const P& p) {
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
    return d;
}

// The unpacked parameters of p, once it is shaped (above) and has regimes.
R::Params params_of(const P& p, bool sliding_law = true) {
    const double* d = shaped(p);
    // a regime's matrix is the sliding law's of its direction (sdir), not the stick law's
    require(!sliding_law || d[L::STICK_BAND] == 0.0,
            "p[STICK_BAND] must be 0 for a regime's matrix");
    // the regimes are those between rigid walls: a compliant contact has none
    // (slots a regime does not read may be NaN: only a positive K is a contact)
    require(!(d[L::CONTACT_K] > 0.0), "p[CONTACT_K] must be 0: the regime matrices are the "
                                      "impact law's, and a Hertz contact is not linear");
    return R::unpack(d, 1e-6);  // the step only sets the forcing's rotation, unused here
}

// NumPy arrays of zeros that own their memory.
Matrix zeros(size_t rows, size_t cols) {
    return owned_array<double, 2>(std::vector<double>(rows * cols, 0.0), {rows, cols});
}
Stack zeros3(size_t n0, size_t rows, size_t cols) {
    return owned_array<double, 3>(std::vector<double>(n0 * rows * cols, 0.0), {n0, rows, cols});
}

// A rolling ball's rolled regime: the roll law rolling whatever the friction it needs (the
// exact kernel's events end the regime where it may not), so that the floor's friction is
// the one rolling needs and the bar carries cy of the ball (docs/model.md, 2.7).
R::Params rolled(R::Params q) {
    q.roll.on = true;
    q.roll.mus_n = INFINITY;
    q.roll.band = INFINITY;
    return q;
}

// A rolling ball's regime for a matrix (fdir: -1, 1 slipping with the slip y' - s of that
// sign, 0 rolled).  Rolled, the roll law rolls whatever the friction it needs (rolled());
// slipping, it never rolls (a zero band) and the floor's friction is -mu_k N sgn(slip).
R::Params roll_regime(R::Params q, double fdir) {
    if (fdir == 0.0) return rolled(q);
    q.roll.band = 0.0;
    return q;
}

Matrix regime_matrix(const P& p, double sdir, double fdir) {
    require(sdir == -1.0 || sdir == 0.0 || sdir == 1.0, "sdir must be -1, 0 or 1");
    require(fdir == -1.0 || fdir == 0.0 || fdir == 1.0, "fdir must be -1, 0 or 1");
    R::Params q = params_of(p);
    require(q.roll.on || fdir == 0.0, "fdir must be 0 for a ball that does not roll");
    if (q.roll.on) q = roll_regime(q, fdir);
    const bool slipping = q.roll.on && fdir != 0.0;
    const R::Shape<0, -1> sh(q);
    const int nx = sh.nx(), nz = nx + 3;
    Matrix A = zeros(size_t(nz), size_t(nz));
    auto a = A.view();
    double X[R::NX_MAX], Kd[R::NX_MAX];
    // (a slipping ball's floor friction, constant, enters its constant column alone: the
    // state's columns are taken with mu_k N = 0)
    R::Params q_state = q;
    if (slipping) q_state.roll.muk_n = 0.0;
    auto column = [&](const R::Params& qc, int j, double f, double ysign) {
        R::StageTerms t = R::derivative_with<0, -1>(qc, sh, X, f, Kd, ysign);
        if (sh.rolls()) Kd[sh.iyd()] = R::map_roll(qc, sh, X, Kd, t);
        for (int i = 0; i < nx; ++i) a(i, j) = Kd[i];
    };
    for (int j = 0; j < nx; ++j) {
        for (int i = 0; i < nx; ++i) X[i] = i == j ? 1.0 : 0.0;
        column(q_state, j, 0.0, 0.0);  // no friction force: the linear part
    }
    for (int i = 0; i < nx; ++i) X[i] = 0.0;
    column(q_state, nx, q.force.f0, 0.0);  // the force F0 sin(Omega t) at the tip
    if (slipping) X[sh.is()] = -fdir;  // a slip y' - s of fdir's sign, X's only entry
    column(q, nx + 2, 0.0, sdir);  // F_b = -F_c sdir held (and the floor's friction)
    a(nx, nx + 1) = q.force.om;          // (sin Omega t)' = Omega cos Omega t
    a(nx + 1, nx) = -q.force.om;
    return A;
}

Matrix impact_matrix(const P& p) {
    const R::Params q = params_of(p);  // a rolling ball's spin: unchanged
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

// The exact integrator's regimes, z' = A z + B f + c F_b on its state z: the bar's 2n
// entries (u, u'), with the absorber's 2 for a tuned bar.  A free ball is not in z (its
// flight is solved in closed form) and acts on the bar through F_b alone (c); a ball
// held by friction or carried on a wall moves with the bar.
struct ExactRegime {
    R::Params q;
    double ysign;  // picks F_b: 0 none, -1 a unit force (q's F_c is 1)
    bool friction_input;  // c is the response to F_b = 1
};

// One regime's rows of A, B and c, from the stage derivative at the unit vectors of the
// state's first nz entries (the ball's y, y' zero).  In the cut (krb > 0) the tip force
// is Kr b (S - W) with W = psi_L . u: its -Kr b W joins A, and B takes Kr b S.
void fill_regime(const ExactRegime& g, int nz, double krb, double* A, double* B, double* c) {
    const R::Shape<0, -1> sh(g.q);
    double X[R::NX_MAX + 1] = {}, Kd[R::NX_MAX + 1];  // (a rolling ball's spin last)
    auto derive = [&](double f, double ysign) {
        R::StageTerms t = R::derivative_with<0, -1>(g.q, sh, X, f, Kd, ysign);
        if (sh.rolls()) Kd[sh.iyd()] = R::map_roll(g.q, sh, X, Kd, t);  // the rolled regime
    };
    for (int j = 0; j < nz; ++j) {
        X[j] = 1.0;
        const double w = j < sh.n() ? g.q.modes.pL[j] : 0.0;
        derive(-krb * w, g.ysign);
        for (int i = 0; i < nz; ++i) A[i * nz + j] = Kd[i];
        X[j] = 0.0;
    }
    derive(1.0, g.ysign);
    for (int i = 0; i < nz; ++i) B[i] = Kd[i];
    if (g.friction_input) derive(0.0, -1.0);
    for (int i = 0; i < nz; ++i) c[i] = g.friction_input ? Kd[i] : 0.0;
}

// The unpacked parameters with the ball held by friction, whatever the force: y'' = 0,
// the force that carries it on the bar with the reaction's share sr.
R::Params held(R::Params q) {
    q.fric.hold = true;
    q.fric.band = INFINITY;
    q.fric.fs = INFINITY;
    return q;
}

// The regimes of p: a ball bar's free, stuck (reaction share sr) and on a wall (share 1),
// and a rolling ball's rolled regime; one regime for the others; a cut doubles them (out
// of the cut, then in it).  A rolling ball's free regime is the sliding ball's: slipping,
// the floor's friction joins F_b.
// The length of the exact integrator's state z: the bar's u, u', and the absorber's x_a,
// x_a' (a ball's y, y' and spin are its own, outside z).
int exact_state_size(const R::Shape<0, -1>& sh) {
    return sh.tmd() ? 2 * sh.n() + 2 : 2 * sh.n();
}

nb::tuple regime_stack(const P& p) {
    R::Params q = params_of(p, false);  // each regime sets its own friction law
    const bool roll = q.roll.on;
    q.roll.on = false;
    q.fric.hold = false;
    R::set_friction(q, 1.0);
    const R::Shape<0, -1> sh(q);
    const int nz = exact_state_size(sh);
    std::vector<ExactRegime> regimes{{q, 0.0, sh.ball()}};
    if (sh.ball()) {
        regimes.push_back({held(q), 0.0, false});
        std::vector<double> p1(p.data(), p.data() + L::P_SIZE);
        p1[L::REACTION] = 1.0;  // on a wall the bar carries the whole ball
        R::Params q1 = R::unpack(p1.data(), 1e-6);
        q1.roll.on = false;  // held on a wall, a rolling ball's law is out as on the bore
        regimes.push_back({held(q1), 0.0, false});
        if (roll) regimes.push_back({rolled(q), 0.0, true});
    }
    const int nreg = int(regimes.size());
    const bool cut = int(p.data()[L::FORCING]) == L::REGENERATIVE;
    const int R_ = cut ? 2 * nreg : nreg;
    Stack A = zeros3(size_t(R_), size_t(nz), size_t(nz));
    Matrix B = zeros(size_t(R_), size_t(nz)), c = zeros(size_t(R_), size_t(nz));
    for (int r = 0; r < R_; ++r) {
        const double krb = r >= nreg ? p.data()[L::KR_B] : 0.0;
        fill_regime(regimes[size_t(r % nreg)], nz, krb, A.data() + size_t(r) * nz * nz,
                    B.data() + size_t(r) * nz, c.data() + size_t(r) * nz);
    }
    return nb::make_tuple(A, B, c, nreg);
}

// The bar's dashpots on the exact integrator's state (regime_stack's z): (l, c).
nb::tuple dashpot_rows(const P& p) {
    const R::Params q = params_of(p, false);
    const R::Shape<0, -1> sh(q);
    const int nz = exact_state_size(sh), nd = R::dashpot_count(sh);
    Matrix l = zeros(size_t(nd), size_t(nz));
    std::vector<double> c(size_t(nd), 0.0);
    R::dashpots(q, sh, nz, l.data(), c.data());
    return nb::make_tuple(l, owned_array<double, 1>(std::move(c), {size_t(nd)}));
}

// kappa of the ball the bar carries with the share s of the reaction (dynamics.hpp): the
// one definition of the carrying term, whose inverse at the full share is the impact's
// effective mass.
double carried_kappa_of(const P& p, double share) {
    const double* d = shaped(p);
    require(std::isfinite(share), "share must be finite");
    require(d[L::BALL_MASS] > 0.0, "p[BALL_MASS] must be > 0: the carried ball's mass");
    return R::carried_kappa(R::unpack(d, 1e-6), share);
}

}  // namespace

void bind_dynamics(nb::module_& m) {
    m.def("regime_matrix", &regime_matrix, nb::arg("p"), nb::arg("sdir"),
          nb::arg("fdir") = 0.0,
          "A of z' = A z between impacts, z = [X, sin Omega t, cos Omega t, 1] (X as the "
          "integrators keep it, 2n + 2 entries and a rolling ball's spin), the ball sliding "
          "in direction sdir (-1, 0, 1: F_b = -F_c sdir held); a rolling ball slipping with "
          "the slip's sign fdir (-1, 1: its floor's friction -mu_k N fdir held) or rolled "
          "(fdir = 0); built from RK4's stage derivative.");
    m.def("impact_matrix", &impact_matrix, nb::arg("p"),
          "R, X+ = R X- at an impact of a ball bar (the identity for the other bars): "
          "y' -> -e y', u_i' -> u_i' + (1 + e) m_eff psi_d,i y' / M_i, from the wall's "
          "impact law.");
    m.def("regime_stack", &regime_stack, nb::arg("p"),
          "(A, B, c, nreg): the exact integrator's regimes z' = A z + B f + c F_b, stacked "
          "(R, nz, nz), (R, nz), (R, nz); z the bar's u, u' (and the absorber's x_a, x_a'); "
          "a ball bar's free (F_b its input c), stuck and wall regimes, one for the others; "
          "a cut's R = 2 nreg, the regimes in the cut (f = Kr b (S - W)) after those out of "
          "it; built from RK4's stage derivative.");
    m.def("carried_kappa", &carried_kappa_of, nb::arg("p"), nb::arg("share"),
          "kappa = 1/m + share sum psi_d,i^2 / M_i of the ball of p carried with the bar, "
          "the force that moves it per unit of relative acceleration, with the share of the "
          "reaction on the bar (1: reciprocal; its inverse is the impact's effective mass "
          "m_eff).");
    m.def("dashpots", &dashpot_rows, nb::arg("p"),
          "(l, c): the bar's dashpots on regime_stack's state z, the power they dissipate "
          "sum_d c_d (l_d . z)^2 (RK4's stage power): each mode's on its velocity u_i', a "
          "tuned absorber's on x_a' - psi_a . u'; l (nd, nz), c (nd).");
}

}  // namespace bb::bind
