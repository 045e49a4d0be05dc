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

struct StepMap {
    double Pd[NX_MAX][NZ_MAX];
    double Yr[3][NZ_MAX];
    double Vr[3][NV_MAX][NZ_MAX];
    double Wv[4][NV_MAX];
    double Fs[NZ_MAX];
    double Fc[NZ_MAX];
    double Kr[4][NZ_MAX];
};

// The roll law's stage after a sliding ball's (derivative_with): out of line, because
// inlined into build_map's loops, GCC 12 stops with the internal error noted there.
BB_NOINLINE inline double map_roll(const Params& q, Shape<0, -1> sh, const double* Xs,
                                   double* Kd, StageTerms& t) {
    return roll_stage(q, sh, Xs, Kd, Kd[sh.iyd()], t.sfree - q.kappa1 * t.fb, t);
}

// The tables of the step of dt for the first n modes of the packed parameters p: the
// stage recursion of rk4.hpp's step with the stage derivative of dynamics.hpp, F_b a
// column of z (a unit friction force, F_b = -F_c sgn(y') with F_c = 1 and y' < 0, in its
// column; none, y' = 0, in the others).  rolled: a rolling ball's rolled regime (else a
// sliding ball's step, which a slipping ball takes too).
inline void build_map(int n, const double* p, double dt, StepMap& mp, bool rolled) {
    Params q = unpack(p, dt);
    q.n = n;
    q.hold = false;  // the map is the sgn() law's step
    q.hertz = false;  // off the walls: a run with a compliant contact steps by stages
    q.roll = q.roll && rolled;
    if (q.roll) {  // the roll law as rolling throughout (the kernel checks that it does)
        q.mus_n = INFINITY;
        q.roll_band = INFINITY;
    }
    set_friction(q, 1.0);
    const Shape<0, -1> sh(q);
    const bool ball = sh.ball(), tmd = sh.tmd();
    const int nxs = sh.nx(), nx = sh.nxm(), nz = nx + 3, iyd = sh.iyd();
    // the forcing at the stage times t + c_s dt is F0 (alpha_s S + beta_s C)
    const double ch = std::cos(q.om * 0.5 * dt), shh = std::sin(q.om * 0.5 * dt);
    const double c1 = std::cos(q.om * dt), s1 = std::sin(q.om * dt);
    const double alpha[4] = {1.0, ch, ch, c1};
    const double beta[4] = {0.0, shh, shh, s1};
    const double cst[4] = {0.0, 0.5 * dt, 0.5 * dt, dt};
    const double wst[4] = {dt / 6.0, dt / 3.0, dt / 3.0, dt / 6.0};
    for (int s = 0; s < 4; ++s) {
        for (int i = 0; i < n; ++i) mp.Wv[s][i] = wst[s] * q.C[i];
        mp.Wv[s][n] = tmd ? wst[s] * q.ca : 0.0;
    }

    double X[NX_MAX + 1], Xs[NX_MAX + 1], Kd[NX_MAX + 1], acc[NX_MAX + 1];
    for (int col = 0; col < nz; ++col) {  // the response to the basis vector e_col of z
        for (int j = 0; j < nxs; ++j) {
            X[j] = j == col ? 1.0 : 0.0;
            Kd[j] = 0.0;
            acc[j] = 0.0;
        }
        if (sh.rolls()) X[sh.is()] = X[iyd];
        const double S = col == nx ? 1.0 : 0.0;
        const double Cz = col == nx + 1 ? 1.0 : 0.0;
        const double ysign = col == nx + 2 ? -1.0 : 0.0;  // F_b = 1 in its column
        double fs = 0.0, fc = 0.0;
        for (int s = 0; s < 4; ++s) {
            for (int j = 0; j < nxs; ++j) Xs[j] = X[j] + cst[s] * Kd[j];
            const double f = q.f0 * (alpha[s] * S + beta[s] * Cz);
            StageTerms t = derivative_with<0, -1>(q, sh, Xs, f, Kd, ysign);
            // the roll law after it (compiled into derivative_with's copy here, GCC 12
            // stops with the internal error noted there)
            if (sh.rolls()) Kd[iyd] = map_roll(q, sh, Xs, Kd, t);
            mp.Kr[s][col] = t.floor;
            if (s > 0) {
                mp.Yr[s - 1][col] = ball ? Xs[iyd] : 0.0;
                double reld = tmd ? Xs[iyd] : 0.0;  // the absorber's stroke rate
                for (int i = 0; i < n; ++i) {
                    mp.Vr[s - 1][i][col] = Xs[n + i];
                    if (tmd) reld -= q.pA[i] * Xs[n + i];
                }
                mp.Vr[s - 1][n][col] = reld;
            }
            for (int j = 0; j < nxs; ++j) acc[j] += wst[s] * Kd[j];
            fs += wst[s] * q.f0 * alpha[s] * t.wf;
            fc += wst[s] * q.f0 * beta[s] * t.wf;
        }
        for (int j = 0; j < nx; ++j) mp.Pd[j][col] = acc[j];
        // sum_s b_s f_s W'_s with f_s = F0 (alpha_s S + beta_s C) is S (Fs . z) + C (Fc . z)
        mp.Fs[col] = fs;
        mp.Fc[col] = fc;
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

struct VecMap {
    // the increment: row pairs (i, n + i) for mode i < n, and (iy, iyd) as pair n
    v2 dS[NV_MAX], dC[NV_MAX], dF[NV_MAX], dP[NV_MAX][NX_MAX];
    // y' at stages 2-4 in lanes 0-2 (lane 3 unused)
    v4 yS, yC, yF, yP[NX_MAX];
    // bounds of |y'_s - y'_0| over the stages: max_s |Yr[s][c]| per column c of z, with
    // Yr[s][iyd] - 1 in column iyd (the step's own y')
    double yb[NZ_MAX];
    // the damped velocities at stages 2-4 in lanes 0-2: modes k < n, the absorber k = n
    v4 vS[NV_MAX], vC[NV_MAX], vF[NV_MAX], vP[NV_MAX][NX_MAX];
    v4 wv[NV_MAX];      // their weights Wv[1 + lane][k]
    double w0[NV_MAX];  // the weights of the stage-1 velocities, Wv[0][k]
    // the force's work: lanes (Fs, Fc)
    v2 fS, fC, fF, fP[NX_MAX];
    // a rolling ball's floor friction at stages 1-4 in lanes 0-3
    v4 kS, kC, kF, kP[NX_MAX];
};

inline VecMap pack_map(int n, const StepMap& mp) {
    VecMap vm = {};
    const int nx = 2 * n + 2, iS = nx, iC = nx + 1, iF = nx + 2;
    for (int pr = 0; pr <= n; ++pr) {
        const int a0 = pr < n ? pr : 2 * n, a1 = pr < n ? n + pr : 2 * n + 1;
        vm.dS[pr] = v2{mp.Pd[a0][iS], mp.Pd[a1][iS]};
        vm.dC[pr] = v2{mp.Pd[a0][iC], mp.Pd[a1][iC]};
        vm.dF[pr] = v2{mp.Pd[a0][iF], mp.Pd[a1][iF]};
        for (int j = 0; j < nx; ++j) vm.dP[pr][j] = v2{mp.Pd[a0][j], mp.Pd[a1][j]};
    }
    auto lanes = [](const double* a, const double* b, const double* c) {
        return v4{v2{*a, *b}, v2{*c, 0.0}};
    };
    vm.yS = lanes(&mp.Yr[0][iS], &mp.Yr[1][iS], &mp.Yr[2][iS]);
    vm.yC = lanes(&mp.Yr[0][iC], &mp.Yr[1][iC], &mp.Yr[2][iC]);
    vm.yF = lanes(&mp.Yr[0][iF], &mp.Yr[1][iF], &mp.Yr[2][iF]);
    for (int j = 0; j < nx; ++j) vm.yP[j] = lanes(&mp.Yr[0][j], &mp.Yr[1][j], &mp.Yr[2][j]);
    for (int c = 0; c < nx + 3; ++c) {
        double b = 0.0;
        for (int s3 = 0; s3 < 3; ++s3) {
            const double y = std::fabs(c == 2 * n + 1 ? mp.Yr[s3][c] - 1.0 : mp.Yr[s3][c]);
            b = (y > b || std::isnan(y)) ? y : b;  // a NaN entry makes the bound NaN
        }
        vm.yb[c] = b;
    }
    for (int k = 0; k <= n; ++k) {
        vm.vS[k] = lanes(&mp.Vr[0][k][iS], &mp.Vr[1][k][iS], &mp.Vr[2][k][iS]);
        vm.vC[k] = lanes(&mp.Vr[0][k][iC], &mp.Vr[1][k][iC], &mp.Vr[2][k][iC]);
        vm.vF[k] = lanes(&mp.Vr[0][k][iF], &mp.Vr[1][k][iF], &mp.Vr[2][k][iF]);
        for (int j = 0; j < nx; ++j)
            vm.vP[k][j] = lanes(&mp.Vr[0][k][j], &mp.Vr[1][k][j], &mp.Vr[2][k][j]);
        vm.wv[k] = lanes(&mp.Wv[1][k], &mp.Wv[2][k], &mp.Wv[3][k]);
        vm.w0[k] = mp.Wv[0][k];
    }
    vm.fS = v2{mp.Fs[iS], mp.Fc[iS]};
    vm.fC = v2{mp.Fs[iC], mp.Fc[iC]};
    vm.fF = v2{mp.Fs[iF], mp.Fc[iF]};
    for (int j = 0; j < nx; ++j) vm.fP[j] = v2{mp.Fs[j], mp.Fc[j]};
    auto stages = [&mp](int c) {
        return v4{v2{mp.Kr[0][c], mp.Kr[1][c]}, v2{mp.Kr[2][c], mp.Kr[3][c]}};
    };
    vm.kS = stages(iS);
    vm.kC = stages(iC);
    vm.kF = stages(iF);
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
