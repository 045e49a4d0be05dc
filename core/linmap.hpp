// One RK4 step of the published scheme as an affine map, for steps without a friction
// switch (docs/model.md, section 5).
//
// Under harmonic forcing the equations between impacts are linear with a constant
// friction force, except that F_b = -F_c sgn(y') is re-evaluated at every stage.  When y'
// keeps one sign at all four stages, F_b is the same at every stage and the RK4 step is
// (in exact arithmetic) an affine function of z = [X (2n + 2 values), S, C, F_b], with
// S = sin(Omega t), C = cos(Omega t) at the step's start.  build_map() pushes the basis
// vectors of z through the stage recursion once per run and keeps:
//
// - Pd (nx, nz): the step's increment, X_new - X = Pd z;
// - Yr (3, nz): the ball's y' at stages 2-4, to check that F_b did not switch;
// - Vr (3, n + 1, nz): the velocities viscous damping acts on at stages 2-4 (modal
//   u_i', and the absorber's stroke rate in row n), Wv (4, n + 1) their weights b_s c_k;
// - Fs, Fc (nz): the force's work over the step is S (Fs . z) + C (Fc . z);
// - Kr (4, nz): a rolling ball's floor friction at the four stages.
//
// A rolling ball (docs/model.md, 2.7) has two linear steps.  Rolling without slip at
// every stage, its spin is its y' (each basis vector's spin is set to its y') and the
// floor's friction the one rolling needs: that map (rolled) is built with the roll law
// always rolling, and the kernel takes it where the ball rolls at the step's start and
// the friction at every stage stays within mu_s N (Kr); the spin then takes the step's
// y'.  Slipping at every stage, the floor's friction is a constant -mu_k N sgn(slip)
// beside F_b, and the step is the sliding ball's map with the two in F_b's column.
//
// A ball that friction holds under the sgn() law chatters: its y' changes sign from
// stage to stage (+ - + -, + + + -, ... relative to stage 1), and F_b with it.  Each such
// sign pattern is a linear step too, with F_b = -F_c sgn(y'_1) times the pattern's signs
// at the stages: only F_b's column differs, and it is built for each of the 8 patterns
// (fb), in a rolling ball's rolled map too; a slipping ball's floor friction, the same at
// every stage, takes the one-sign column beside it.  The kernel takes a pattern's step
// where the stages' y', computed from its rows, have that pattern's signs by more than
// their round-off (and a rolling ball rolls, or slips, at every stage as above).
//
// The tables are built by the stage recursion applied to the basis vectors, the same
// operations in the same order at every build, so the tables (and every step taken with
// them) have the same bits in every run, batch lane and instruction-set copy.
#pragma once

#include <cmath>

#include "compiler.hpp"
#include "dynamics.hpp"
#include "layout.hpp"

namespace bb::rk4 {

// the equations of motion (dynamics.hpp) are the scheme's
using namespace dynamics;

namespace L = layout;

constexpr int NZ_MAX = NX_MAX + 3;  // state, S, C, F_b
constexpr int NV_MAX = L::NMAX + 1;  // damped velocities: the modes and the absorber

// One column of the tables: the step's response to one basis vector of z.
struct Column {
    double Pd[NX_MAX], Yr[3], Vr[3][NV_MAX], Fs, Fc, Kr[4];
};

// the sign patterns of the stages' y' relative to stage 1's: bit k set where stage k + 2
// has the opposite sign
constexpr int NPAT = 8;

struct StepMap {
    double Pd[NX_MAX][NZ_MAX];
    double Yr[3][NZ_MAX];
    double Vr[3][NV_MAX][NZ_MAX];
    double Wv[4][NV_MAX];
    double Fs[NZ_MAX];
    double Fc[NZ_MAX];
    double Kr[4][NZ_MAX];
    // F_b's column for each sign pattern (fb[0] that of Pd, Yr, Vr, Fs, Fc, Kr): a
    // ball's (n_patterns = NPAT), else fb[0] alone
    Column fb[NPAT];
    int n_patterns;
    // a pattern's friction work (rows of z, and in column nz the one-sign F column's
    // entry): sum_s b_s sigma_s y'_s and sum_s b_s sigma_s psi_d u'_s, sigma_s = -1 at the
    // pattern's flipped stages
    double Gw[NPAT][2][NZ_MAX + 1];
};

// The roll law's stage after a sliding ball's (derivative_with): out of line, because
// inlined into build_map's loops, GCC 12 stops with the internal error noted there.
BB_NOINLINE inline double map_roll(const Params& q, Shape<0, -1> sh, const double* Xs,
                                   double* Kd, StageTerms& t) {
    return roll_stage(q, sh, Xs, Kd, Kd[sh.iyd()], t.sfree - q.kappa1 * t.fb, t);
}

// The step's stages: the forcing at the stage times t + c_s dt is F0 (alpha_s S +
// beta_s C); c_s dt and the weights b_s dt.
struct Stages {
    double alpha[4], beta[4], cst[4], wst[4];

    Stages(double om, double dt)
        : alpha{1.0, std::cos(om * 0.5 * dt), std::cos(om * 0.5 * dt), std::cos(om * dt)},
          beta{0.0, std::sin(om * 0.5 * dt), std::sin(om * 0.5 * dt), std::sin(om * dt)},
          cst{0.0, 0.5 * dt, 0.5 * dt, dt},
          wst{dt / 6.0, dt / 3.0, dt / 3.0, dt / 6.0} {}
};

// The stage recursion of rk4.hpp's step applied to the basis vector e_col of z, with the
// stage derivative of dynamics.hpp: F_b a column of z (a unit friction force, F_b =
// -F_c sgn(y') with F_c = 1, in its column; none, y' = 0, in the others).  flips: the
// stages 2-4 (bits 0-2) whose y' has the sign opposite to stage 1's, so that F_b is -1
// there in F_b's column (a sign pattern, below).
inline Column push_column(const Params& q, const Stages& st, int col, int flips) {
    const Shape<0, -1> sh(q);
    const bool ball = sh.ball(), tmd = sh.tmd();
    const int n = sh.n(), nxs = sh.nx(), nx = sh.nxm(), iyd = sh.iyd();
    const double *alpha = st.alpha, *beta = st.beta, *cst = st.cst, *wst = st.wst;
    Column c;
    double X[NX_MAX + 1], Xs[NX_MAX + 1], Kd[NX_MAX + 1], acc[NX_MAX + 1];
    for (int j = 0; j < nxs; ++j) {
        X[j] = j == col ? 1.0 : 0.0;
        Kd[j] = 0.0;
        acc[j] = 0.0;
    }
    if (sh.rolls()) X[sh.is()] = X[iyd];
    const double S = col == nx ? 1.0 : 0.0;
    const double Cz = col == nx + 1 ? 1.0 : 0.0;
    double fs = 0.0, fc = 0.0;
    for (int s = 0; s < 4; ++s) {
        // F_b = 1 in its column (-1 at a flipped stage)
        const bool flip = s > 0 && ((flips >> (s - 1)) & 1);
        const double ysign = col == nx + 2 ? (flip ? 1.0 : -1.0) : 0.0;
        for (int j = 0; j < nxs; ++j) Xs[j] = X[j] + cst[s] * Kd[j];
        const double f = q.force.f0 * (alpha[s] * S + beta[s] * Cz);
        StageTerms t = derivative_with<0, -1>(q, sh, Xs, f, Kd, ysign);
        // the roll law after it (compiled into derivative_with's copy here, GCC 12
        // stops with the internal error noted there)
        if (sh.rolls()) Kd[iyd] = map_roll(q, sh, Xs, Kd, t);
        c.Kr[s] = t.floor;
        if (s > 0) {
            c.Yr[s - 1] = ball ? Xs[iyd] : 0.0;
            double reld = tmd ? Xs[iyd] : 0.0;  // the absorber's stroke rate
            for (int i = 0; i < n; ++i) {
                c.Vr[s - 1][i] = Xs[n + i];
                if (tmd) reld -= q.modes.pA[i] * Xs[n + i];
            }
            c.Vr[s - 1][n] = reld;
        }
        for (int j = 0; j < nxs; ++j) acc[j] += wst[s] * Kd[j];
        fs += wst[s] * q.force.f0 * alpha[s] * t.wf;
        fc += wst[s] * q.force.f0 * beta[s] * t.wf;
    }
    for (int j = 0; j < nx; ++j) c.Pd[j] = acc[j];
    // sum_s b_s f_s W'_s with f_s = F0 (alpha_s S + beta_s C) is S (Fs . z) + C (Fc . z)
    c.Fs = fs;
    c.Fc = fc;
    return c;
}

// The rows StepMap::Gw of the sign pattern flips, from the stages' y' and velocities in
// the tables (stage 1's: the state's own).
inline void pattern_work(const Params& q, Shape<0, -1> sh, const Stages& st, StepMap& mp,
                         int flips) {
    const double* ws = st.wst;
    const int n = sh.n(), nx = sh.nxm(), nz = nx + 3;
    for (int c = 0; c <= nz; ++c) {
        const Column& fb = mp.fb[c == nz ? 0 : flips];
        const bool fcol = c >= nz - 1;
        double g = c == sh.iyd() ? ws[0] : 0.0;
        double h = c >= n && c < 2 * n ? ws[0] * q.modes.pD[c - n] : 0.0;
        for (int s3 = 0; s3 < 3; ++s3) {
            const double w = (flips >> s3) & 1 ? -ws[s3 + 1] : ws[s3 + 1];
            double pdv = 0.0;
            for (int i = 0; i < n; ++i)
                pdv += q.modes.pD[i] * (fcol ? fb.Vr[s3][i] : mp.Vr[s3][i][c]);
            g += w * (fcol ? fb.Yr[s3] : mp.Yr[s3][c]);
            h += w * pdv;
        }
        mp.Gw[flips][0][c] = g;
        mp.Gw[flips][1][c] = h;
    }
}

// The tables of the step of dt for the first n modes of the packed parameters p, column
// by column (push_column).  rolled: a rolling ball's rolled regime (else a sliding ball's
// step, which a slipping ball takes too).  A ball's F_b column is also built for each
// sign pattern of the stages' y' (StepMap::fb), in either regime, with the pattern's
// friction work.
inline void build_map(int n, const double* p, double dt, StepMap& mp, bool rolled) {
    Params q = unpack(p, dt);
    q.modes.n = n;
    q.fric.hold = false;  // the map is the sgn() law's step
    q.contact.on = false;  // off the walls: a run with a compliant contact steps by stages
    q.roll.on = q.roll.on && rolled;
    if (q.roll.on) {  // the roll law as rolling throughout (the kernel checks that it does)
        q.roll.mus_n = INFINITY;
        q.roll.band = INFINITY;
    }
    set_friction(q, 1.0);
    const Shape<0, -1> sh(q);
    const int nx = sh.nxm(), nz = nx + 3;
    const Stages st(q.force.om, dt);
    for (int s = 0; s < 4; ++s) {
        for (int i = 0; i < n; ++i) mp.Wv[s][i] = st.wst[s] * q.modes.C[i];
        mp.Wv[s][n] = sh.tmd() ? st.wst[s] * q.tmd.c : 0.0;
    }
    for (int col = 0; col < nz; ++col) {
        const Column c = push_column(q, st, col, 0);
        for (int j = 0; j < nx; ++j) mp.Pd[j][col] = c.Pd[j];
        for (int s3 = 0; s3 < 3; ++s3) {
            mp.Yr[s3][col] = c.Yr[s3];
            for (int k = 0; k <= n; ++k) mp.Vr[s3][k][col] = c.Vr[s3][k];
        }
        for (int s = 0; s < 4; ++s) mp.Kr[s][col] = c.Kr[s];
        mp.Fs[col] = c.Fs;
        mp.Fc[col] = c.Fc;
        if (col == nz - 1) mp.fb[0] = c;
    }
    mp.n_patterns = sh.ball() ? NPAT : 1;
    for (int flips = 1; flips < mp.n_patterns; ++flips) {
        mp.fb[flips] = push_column(q, st, nz - 1, flips);
        pattern_work(q, sh, st, mp, flips);
    }
}

// The tables regrouped for the kernels' step: what one step computes for several rows,
// stages or velocities at once sits side by side in a vector (v2, compiler.hpp: GCC/Clang
// vector extensions, SSE2 on any x86-64, the same on other targets), so one vector
// operation does what several scalar ones did.  Each lane does the scalar code's
// operations in its order, so the bits are those of the scalar sums.

// Four lanes as two native pairs (a 32-byte vector type without AVX went through memory).
struct v4 {
    v2 lo, hi;
    double operator[](int l) const { return l < 2 ? lo[l] : hi[l - 2]; }
};
#define BB_V4_OP BB_ALWAYS_INLINE v4
BB_V4_OP operator*(v4 a, double s) { return {a.lo * s, a.hi * s}; }
BB_V4_OP operator*(double s, v4 a) { return {s * a.lo, s * a.hi}; }
BB_V4_OP operator*(v4 a, v4 b) { return {a.lo * b.lo, a.hi * b.hi}; }
BB_V4_OP operator+(v4 a, v4 b) { return {a.lo + b.lo, a.hi + b.hi}; }
BB_V4_OP operator+(double s, v4 a) { return {s + a.lo, s + a.hi}; }
BB_V4_OP operator-(v4 a, double s) { return {a.lo - s, a.hi - s}; }
BB_V4_OP& operator+=(v4& a, v4 b) { return a = a + b; }
#undef BB_V4_OP

// F_b's column of the packed tables (VecMap's, one per sign pattern): d, y, v, f as
// VecMap's dS, yS, vS, fS, and yb its bound of |y'_s - y'_0|.
struct FbCol {
    v2 d[NV_MAX];
    v4 y;
    v4 v[NV_MAX];
    v2 f;
    double yb;
};

// Rows of z in lanes, as VecMap's fS, fC, fP with F_b's column F.
struct FbWork {
    v2 S, C, F, P[NX_MAX];
};

struct VecMap {
    // the increment: row pairs (i, n + i) for mode i < n, and (iy, iyd) as pair n
    v2 dS[NV_MAX], dC[NV_MAX], dP[NV_MAX][NX_MAX];
    // y' at stages 2-4 in lanes 0-2 (lane 3 unused)
    v4 yS, yC, yP[NX_MAX];
    // bounds of |y'_s - y'_0| over the stages: max_s |Yr[s][c]| per column c of z but
    // F_b's, with Yr[s][iyd] - 1 in column iyd (the step's own y')
    double yb[NZ_MAX];
    // the damped velocities at stages 2-4 in lanes 0-2: modes k < n, the absorber k = n
    v4 vS[NV_MAX], vC[NV_MAX], vP[NV_MAX][NX_MAX];
    v4 wv[NV_MAX];      // their weights Wv[1 + lane][k]
    double w0[NV_MAX];  // the weights of the stage-1 velocities, Wv[0][k]
    // the force's work: lanes (Fs, Fc)
    v2 fS, fC, fP[NX_MAX];
    // F_b's column by sign pattern (fb[0]: y' of one sign at every stage)
    FbCol fb[NPAT];
    int n_patterns;
    FbWork fw[NPAT];  // a pattern's friction work, lanes (F_b's travel, its reaction's)
    // a rolling ball's floor friction at stages 1-4 in lanes 0-3, kF by sign pattern
    v4 kS, kC, kP[NX_MAX], kF[NPAT];
    // a pattern's friction work's entry in the one-sign column (FbWork's lanes): that of
    // a slipping ball's floor friction beside F_b.  (Here at the end, with kF: in FbCol
    // and FbWork they moved the sliding ball's tables, and GCC's code for its kernels ran
    // 2-5 % longer.)
    v2 fwO[NPAT];
};

inline VecMap pack_map(int n, const StepMap& mp) {
    VecMap vm = {};
    const int nx = 2 * n + 2, iS = nx, iC = nx + 1, iF = nx + 2;
    for (int pr = 0; pr <= n; ++pr) {
        const int a0 = pr < n ? pr : 2 * n, a1 = pr < n ? n + pr : 2 * n + 1;
        vm.dS[pr] = v2{mp.Pd[a0][iS], mp.Pd[a1][iS]};
        vm.dC[pr] = v2{mp.Pd[a0][iC], mp.Pd[a1][iC]};
        for (int j = 0; j < nx; ++j) vm.dP[pr][j] = v2{mp.Pd[a0][j], mp.Pd[a1][j]};
    }
    auto lanes = [](const double* a, const double* b, const double* c) {
        return v4{v2{*a, *b}, v2{*c, 0.0}};
    };
    vm.yS = lanes(&mp.Yr[0][iS], &mp.Yr[1][iS], &mp.Yr[2][iS]);
    vm.yC = lanes(&mp.Yr[0][iC], &mp.Yr[1][iC], &mp.Yr[2][iC]);
    for (int j = 0; j < nx; ++j) vm.yP[j] = lanes(&mp.Yr[0][j], &mp.Yr[1][j], &mp.Yr[2][j]);
    // max_s |y_s| (y_s - 1 in column iyd), a NaN entry making the bound NaN
    auto bound = [n](const double* y, int c) {
        double b = 0.0;
        for (int s3 = 0; s3 < 3; ++s3) {
            const double a = std::fabs(c == 2 * n + 1 ? y[s3] - 1.0 : y[s3]);
            b = (a > b || std::isnan(a)) ? a : b;
        }
        return b;
    };
    for (int c = 0; c < nx + 2; ++c) {
        const double y[3] = {mp.Yr[0][c], mp.Yr[1][c], mp.Yr[2][c]};
        vm.yb[c] = bound(y, c);
    }
    vm.n_patterns = mp.n_patterns;
    for (int k = 1; k < mp.n_patterns; ++k) {
        auto row = [&mp, k](int c) { return v2{mp.Gw[k][0][c], mp.Gw[k][1][c]}; };
        FbWork& w = vm.fw[k];
        w.S = row(iS);
        w.C = row(iC);
        w.F = row(iF);
        for (int j = 0; j < nx; ++j) w.P[j] = row(j);
    }
    for (int k = 0; k < mp.n_patterns; ++k) {
        const Column& c = mp.fb[k];
        FbCol& f = vm.fb[k];
        for (int pr = 0; pr <= n; ++pr) {
            const int a0 = pr < n ? pr : 2 * n, a1 = pr < n ? n + pr : 2 * n + 1;
            f.d[pr] = v2{c.Pd[a0], c.Pd[a1]};
        }
        f.y = lanes(&c.Yr[0], &c.Yr[1], &c.Yr[2]);
        for (int m = 0; m <= n; ++m) f.v[m] = lanes(&c.Vr[0][m], &c.Vr[1][m], &c.Vr[2][m]);
        f.f = v2{c.Fs, c.Fc};
        f.yb = bound(c.Yr, iF);
    }
    for (int k = 0; k <= n; ++k) {
        vm.vS[k] = lanes(&mp.Vr[0][k][iS], &mp.Vr[1][k][iS], &mp.Vr[2][k][iS]);
        vm.vC[k] = lanes(&mp.Vr[0][k][iC], &mp.Vr[1][k][iC], &mp.Vr[2][k][iC]);
        for (int j = 0; j < nx; ++j)
            vm.vP[k][j] = lanes(&mp.Vr[0][k][j], &mp.Vr[1][k][j], &mp.Vr[2][k][j]);
        vm.wv[k] = lanes(&mp.Wv[1][k], &mp.Wv[2][k], &mp.Wv[3][k]);
        vm.w0[k] = mp.Wv[0][k];
    }
    vm.fS = v2{mp.Fs[iS], mp.Fc[iS]};
    vm.fC = v2{mp.Fs[iC], mp.Fc[iC]};
    for (int j = 0; j < nx; ++j) vm.fP[j] = v2{mp.Fs[j], mp.Fc[j]};
    auto stages = [&mp](int c) {
        return v4{v2{mp.Kr[0][c], mp.Kr[1][c]}, v2{mp.Kr[2][c], mp.Kr[3][c]}};
    };
    vm.kS = stages(iS);
    vm.kC = stages(iC);
    for (int k = 0; k < mp.n_patterns; ++k) {
        const double* kr = mp.fb[k].Kr;
        vm.kF[k] = v4{v2{kr[0], kr[1]}, v2{kr[2], kr[3]}};
        if (k > 0) vm.fwO[k] = v2{mp.Gw[k][0][iF + 1], mp.Gw[k][1][iF + 1]};
    }
    for (int j = 0; j < nx; ++j) vm.kP[j] = stages(j);
    return vm;
}

// The map of the step of dt for the first n modes of p, packed for the kernels.
inline VecMap step_map(int n, const double* p, double dt, bool rolled = false) {
    StepMap mp;
    build_map(n, p, dt, mp, rolled);
    return pack_map(n, mp);
}

}  // namespace bb::rk4
