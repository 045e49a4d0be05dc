// The published scheme: classical RK4 at a fixed step, impacts at step ends
// (docs/model.md, sections 2 and 5).  Per step:
//
// 1. four RK4 stages of the smooth equations, with F_b = -F_c sgn(y') (sgn(0) = 0) and
//    the forcing evaluated at every stage; or, under harmonic forcing when y' keeps one
//    sign at all four stages or changes it in a known pattern (a ball that friction
//    holds), the same step as one affine map (linmap.hpp);
// 2. the wall rule at the step's end (model.hpp);
// 3. the streamed metrics (RMS, impacts, contact and stick, energy flows).
//
// The state is X = [u_1..u_n, u_1'..u_n', aux, aux'], aux the ball's relative
// displacement y (BALL, LOCKED) or the absorber's displacement x_a (TMD).
//
// This header holds the scheme's rules, each written once: the stage's energy flows, the
// map step, the strobe, the walls and the streamed metrics (the equations of motion, the
// stage derivative, are dynamics.hpp's); rk4_run.hpp is the run (compiled once per
// instruction set, in rk4.cpp and rk4_avx2.cpp), and rk4_batch.cpp runs a batch's rows
// with it.  The helpers
// are force-inlined: with the mode count a compile-time constant their loops unroll and
// the step's state stays in registers.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "arrays.hpp"
#include "compiler.hpp"
#include "dynamics.hpp"
#include "layout.hpp"
#include "linmap.hpp"
#include "model.hpp"


// On x86-64 (GCC, Clang) the specialised kernels are compiled for AVX2 (rk4_avx2.cpp,
// rk4_avx2_many.cpp) and run where the CPU has it: the same IEEE operations in the same
// order as the baseline ISA's, so the same bits on every CPU (FMA, which would round
// differently, is not enabled; -ffp-contract=off).  AVX2 gives 3-operand instructions:
// 1.09-1.14x through bb.simulate and bb.lobes (benchmarks/bench_isa.py); and 4 lanes in
// one register, which the one-mode ball's mapped step takes (WideMap: the paper preset's
// map step 1.04x).  The kernel of a run-time shape is compiled for the
// baseline ISA alone (SSE2, rk4.cpp), on every x86-64 CPU: its AVX2 copy gave 1.01-1.12x
// for 9 s of compile (docs/performance.md, "Instruction-set copies").  An x86-64 CPU
// without AVX2 (x86-64 CPUs have had it since 2013-2015, bar some low-end Pentiums and
// Celerons) runs that kernel for every shape, with the same bits, 2-3.5x slower than the
// AVX2 kernels: the specialised kernels compiled a second time for it took a third of
// the build's CPU time.  An AVX-512 copy (32 vector registers, which hold the staged step
// without spills) gave 1.0-1.1x over AVX2 through the same calls and was the dearest of
// the copies to compile, so it is not built.  Other targets (aarch64, MSVC) build the
// specialised kernels for the baseline ISA (rk4.cpp, rk4_many.cpp).
// (-DBB_NO_AVX2_CLONE builds those, to test them on an AVX2 CPU.)
#if defined(__x86_64__) && defined(__GNUC__) && !defined(BB_NO_AVX2_CLONE)
#define BB_AVX2_CLONE 1
#define BB_TARGET_AVX2 __attribute__((target("avx2")))
#endif

namespace bb::rk4 {

// most past revolutions in the chip-thickness minimum
constexpr int NREV_MAX = 50;
// the forcing phase is rotated step by step and recomputed exactly this often
constexpr int RESYNC = 256;
// most runs in one batch (run_rk4_batch)
constexpr int BMAX = 16;

// The stage times and weights of classical RK4 as fractions of dt.
constexpr double C_FRAC[4] = {0.0, 0.5, 0.5, 1.0};
constexpr double B_MULT[4] = {1.0, 2.0, 2.0, 1.0};

// sin, cos of the forcing phase at the half step and the full step from (sn, cn)
struct Phase {
    double s_h, c_h, s_1, c_1;
};

BB_INLINE Phase rotate(double sn, double cn, double chh, double shh) {
    Phase r;
    r.s_h = sn * chh + cn * shh;
    r.c_h = cn * chh - sn * shh;
    r.s_1 = r.s_h * chh + r.c_h * shh;
    r.c_1 = r.c_h * chh - r.s_h * shh;
    return r;
}


// A stage's energy flows with the RK4 weight w_s: friction, the non-reciprocal reaction's
// work, the force's work and the dashpots' loss.
template <int N, int CASE>
BB_INLINE void stage_flows(const Params& q, Shape<N, CASE> sh, Flows& fl, const StageTerms& s,
                           double w_s, double f) {
    if (sh.ball()) {
        fl.d_fric -= w_s * s.fb * s.yds;
        fl.w_nr += w_s * (1.0 - q.fric.sr) * s.fb * s.pdv;
    }
    fl.w_force += w_s * f * s.wf;
    fl.d_visc += w_s * s.pvisc;
    if (sh.ball() && sh.hertz(q)) fl.d_con += w_s * s.pcon;
    if (sh.rolls()) fl.d_fric += w_s * s.pfloor;
}

// |v| lane by lane (the sign bit cleared, as fabs)
BB_INLINE v2 vabs(v2 v) {
    const i2 mask = {0x7fffffffffffffffLL, 0x7fffffffffffffffLL};
    return as_v2(as_bits(v) & mask);
}
BB_INLINE v4 vabs(v4 v) { return {vabs(v.lo), vabs(v.hi)}; }

// F_b of a mapped step: the sign y' has at the step's start.
BB_INLINE double map_friction(const Params& q, double yd0) {
    return yd0 > 0.0 ? -q.fric.fc : q.fric.fc;
}

// Whether a step's stages may take their short forms (rk4_stages, FAST): stage 1
// (c = 0) at X itself and each sum of b_s dt Kd from its first term.  With c0 Kd = +-0
// and X neither zero nor NaN, X + c0 Kd is X, and sums that differ only in the sign of
// a zero give X + sum the same bits.  Tested before the stages (a predicted branch), so
// the test is off their chain, which then starts one addition earlier.
// (in pairs: GCC tested the values one by one, branch-free but through integer flags)
template <int N, int CASE>
BB_INLINE bool stages_fast(Shape<N, CASE> sh, const double* X, const double* Kd, double c0) {
    const v2 zero = {0.0, 0.0};
    i2 ok = {-1, -1};
    for (int p = 0; p < sh.nx() / 2; ++p) {
        const v2 x = {X[2 * p], X[2 * p + 1]}, k = {Kd[2 * p], Kd[2 * p + 1]};
        ok &= (c0 * k == zero) & (vabs(x) > zero);
    }
    return (ok[0] & ok[1]) != 0;
}

// A step's four RK4 stages: their times c_s dt after the step's start and their weights
// b_s dt (the run's own arrays, computed once), and the tip force at each,
// force(s, Xs) (the harmonic forcing, or the cutting law at the stage's chip thickness).
// (c and w point to the run's arrays and force is a reference: a table of values, or
// rk4_stages returning held and rolled together, changed GCC's code for the kernels, its
// registers and spills, where this leaves it instruction for instruction as before.)
template <class Force>
struct StepStages {
    const double *c, *w;
    Force& force;
};
template <class Force>
StepStages(const double*, const double*, Force&) -> StepStages<Force>;

// The four RK4 stages of a step, X advanced in place: the stage derivative Kd (carried
// over from the previous staged step, where only 0 * Kd enters) updated, and the stages'
// energy flows.  Returns whether the stick law held the ball at every stage.
// FAST: stage 1 at X, the sums from their first terms (stages_fast) and the
// derivative's FAST form (ydd_sum_from_first).
// The stage values are scalars sized by the mode count, so with N a template constant
// they stay in registers (the kernel files are built without GCC's auto-vectoriser,
// which packed them in vectors through memory, where the loads stalled on store
// forwarding).
// hold_max: the largest |F_b| of a stage the stick law held, raised in place; rolled: a
// rolling ball rolled without slip at every stage (set in place).
template <int N, int CASE, bool FAST, class Force>
BB_INLINE bool rk4_stages(const Params& q, Shape<N, CASE> sh, double* X, double* Kd,
                          const StepStages<Force>& stages, Flows& fl, double& hold_max,
                          bool& rolled) {
    const int nx = sh.nx();
    constexpr int NXC = Shape<N, CASE>::NXC;
    const double *cst = stages.c, *wst = stages.w;
    double sum[NXC], xs[NXC];
    bool held = true;
#pragma GCC unroll 4
    for (int s = 0; s < 4; ++s) {
        for (int j = 0; j < nx; ++j) xs[j] = (FAST && s == 0) ? X[j] : X[j] + cst[s] * Kd[j];
        const double f = stages.force(s, xs);
        const StageTerms terms = derivative<N, CASE, FAST>(q, sh, xs, f, Kd);
        for (int j = 0; j < nx; ++j) {
            if (s == 0)
                sum[j] = FAST ? wst[0] * Kd[j] : 0.0 + wst[0] * Kd[j];
            else
                sum[j] += wst[s] * Kd[j];
        }
        stage_flows(q, sh, fl, terms, wst[s], f);
        held = held && terms.held;
        rolled = rolled && terms.rolled;
        // (only the stick law holds: the sgn() law's stages leave hold_max, off the chain)
        if (q.fric.hold) hold_max = Steady::pymax(hold_max, terms.held ? std::fabs(terms.fb) : 0.0);
    }
    for (int j = 0; j < nx; ++j) X[j] += sum[j];
    return held;
}

// The affine step map's inputs beyond the state X (linmap.hpp's z): the forcing phase's
// sine and cosine at the step's start and the ball's friction force F_b.
// flips: the stages' sign pattern (linmap.hpp; bit k: stage k + 2's y' against stage
// 1's), which picks F_b's column (VecMap::fb); 0: F_b the same at every stage.
struct MapIn {
    double sn, cn, fz;
    int flips = 0;
};

// E = sum_c max_s |Yr[s][c]| |z_c| (Yr[s][iyd] - 1 for y' itself) >= max_s |y'_s - y'_0|
// in exact arithmetic: how far y' may move over a step's stages.
template <int N, int CASE>
BB_INLINE double y_spread(Shape<N, CASE> sh, const VecMap& vm, const double* X, MapIn z) {
    const int nx = sh.nxm();
    double e = vm.yb[nx] * std::fabs(z.sn) + vm.yb[nx + 1] * std::fabs(z.cn) +
               vm.fb[z.flips].yb * std::fabs(z.fz);
    for (int j = 0; j < nx; ++j) e += vm.yb[j] * std::fabs(X[j]);
    return e;
}

// y' at stages 2-4 of the mapped step (lanes 0-2), from the map's rows Yr.
template <int N, int CASE>
BB_INLINE v4 stage_ys(Shape<N, CASE> sh, const VecMap& vm, const double* X, MapIn z) {
    v4 ys = vm.yS * z.sn + vm.yC * z.cn + vm.fb[z.flips].y * z.fz;
    for (int j = 0; j < sh.nxm(); ++j) ys += vm.yP[j] * X[j];
    return ys;
}

// A cheap sufficient condition for map_fits' stage test, a = |y'_0| and spread =
// y_spread = E: E <= 0.2 |y'_0| puts every computed y'_s within |y'_0| / 4 of
// y'_0 (the sums' rounding is below 1e-14 of their terms), so ys y'_0 >= 0.75 y'_0^2,
// far above 1e-12 (y'_0^2 + |y'_0 (ys - y'_0)|) <= 1.3e-12 y'_0^2: the test passes for
// every stage, as the full computation would find.  The limits on |y'_0| keep y'_0^2
// normal and finite; a NaN or infinite state fails the comparison and takes the full
// test, so the decision is always the full test's.
BB_INLINE bool surely_fits(double a, double spread) {
    return a >= 1e-150 && a <= 1e150 && spread <= 0.2 * a;
}

// y' at stages 2-4 of a mapped step (lanes 0-2), once computed (map_fits, map_slips).
struct YStages {
    v4 ys;
    bool have = false;
};

// May a ball with friction take the map this step: y' outside the chattering band and of
// y0's sign at stages 2-4 (the vector's lanes 0-2) by more than their round-off.  The
// single run and the batch wrote the test with opposite comparisons, which differ only
// for a NaN state (nan_maps: the single run's, under which a NaN takes the map).
// spread: set to y_spread where the test gets that far (map_slips reads it); yst, if
// given: the stages' y' where the test computed them (map_slips reads them too).
template <int N, int CASE>
BB_INLINE bool map_fits(const Params& q, Shape<N, CASE> sh, const VecMap& vm, const double* X,
                        MapIn z, bool nan_maps, double& spread, YStages* yst = nullptr) {
    const double yd0 = X[sh.iyd()];
    const bool ok = nan_maps ? !(std::fabs(yd0) < q.fric.vstick) : std::fabs(yd0) >= q.fric.vstick;
    if (!ok) return false;
    spread = y_spread(sh, vm, X, z);
    if (surely_fits(std::fabs(yd0), spread)) return true;
    const v4 ys = stage_ys(sh, vm, X, z);
    if (yst) *yst = YStages{ys, true};
    const v4 lhs = ys * yd0;
    const v4 rhs = 1e-12 * (yd0 * yd0 + vabs(yd0 * (ys - yd0)));
    for (int s3 = 0; s3 < 3; ++s3) {
        if (nan_maps ? lhs[s3] <= rhs[s3] : !(lhs[s3] > rhs[s3])) return false;
    }
    return true;
}

// May a rolling ball take its map this step (linmap.hpp): it rolls at the step's start
// (the spin is its y', as a rolled step or a map leaves it) and the floor's friction
// that rolling needs stays within mu_s N at the four stages (lanes 0-3).
template <int N, int CASE>
BB_INLINE bool map_rolls(const Params& q, Shape<N, CASE> sh, const VecMap& vm, const double* X,
                         MapIn z) {
    if (X[sh.is()] != X[sh.iyd()]) return false;
    v4 k = vm.kS * z.sn + vm.kC * z.cn + vm.kF[z.flips] * z.fz;
    for (int j = 0; j < sh.nxm(); ++j) k += vm.kP[j] * X[j];
    const v4 a = vabs(k);
    // (a NaN friction fails each comparison and takes the stages)
    const double mus = q.roll.mus_n;
    return a[0] <= mus && a[1] <= mus && a[2] <= mus && a[3] <= mus;
}

// May a slipping ball take the sliding ball's map this step, its floor friction ffl =
// -mu_k N sgn(y' - s) beside F_b in z.fz: the slip y'_s - s_s keeps its sign at the
// four stages and stays outside the roll band (so that the roll law slips there), with
// s_s = s - kroll ffl c_s dt (cst) and y'_s from the map's rows (lanes 0-2: stages 2-4).
// The floor's friction and F_b share F_b's column only where both react on the bar as
// -psi_d F (sr = 1).  First a sufficient test (as surely_fits'): each stage's slip is
// within y_spread + kroll mu_k N dt of the step's (plus round-off far below the margin
// of 2x it asks for).
// spread: map_fits' y_spread, or NaN where it did not run; yst: the stages' y' where
// map_fits computed them (with the same z).
template <int N, int CASE>
BB_INLINE bool map_slips(const Params& q, Shape<N, CASE> sh, const VecMap& vm, const double* X,
                         MapIn z, double ffl, const double* cst, double spread,
                         const YStages& yst) {
    const double s0 = X[sh.is()], slip0 = X[sh.iyd()] - s0;
    if (q.fric.sr != 1.0 || !(std::fabs(slip0) >= q.roll.band)) return false;
    if (std::isnan(spread)) spread = y_spread(sh, vm, X, z);
    spread += std::fabs(q.roll.kroll * ffl * cst[3]);
    if (std::fabs(slip0) >= q.roll.band + 2.0 * spread) return true;
    const v4 ys = yst.have ? yst.ys : stage_ys(sh, vm, X, z);
    for (int s3 = 0; s3 < 3; ++s3) {
        const double slip = ys[s3] - (s0 - q.roll.kroll * ffl * cst[s3 + 1]);
        if (!(slip * slip0 > 0.0 && std::fabs(slip) >= q.roll.band)) return false;
    }
    return true;
}

// May a ball that the sgn() law turns within the step take a sign pattern's map
// (linmap.hpp): y'_1 = y'_0 != 0 sets F_b at stage 1, and the stages' y' computed from
// the pattern's rows have the pattern's signs, each farther from 0 than 1e-12 of the
// terms it sums (|y'_0| + y_spread: their round-off is below 1e-14 of that), so that the
// stages in exact arithmetic would pick the same F_b.  Only F_b's column differs between
// the patterns, and stage k + 2's y' only by the pattern's bits below k, so the pattern
// is found stage by stage from the rest of the sums (a slipping rolling ball's floor
// friction ffl, the same at every stage, among them).  Sets z.flips to it, and where
// given, yst to the stages' y' and spread to their y_spread (map_slips reads both).
template <int N, int CASE>
BB_INLINE bool map_pattern(Shape<N, CASE> sh, const VecMap& vm, const double* X, MapIn& z,
                           double ffl = 0.0, YStages* yst = nullptr,
                           double* spread = nullptr) {
    const double yd0 = X[sh.iyd()];
    if (!(std::fabs(yd0) > 0.0)) return false;  // F_b = 0 at stage 1 (or a NaN state)
    const double s1 = yd0 > 0.0 ? 1.0 : -1.0;
    // the stages' y' and the size of their terms, F_b's column aside
    const MapIn rest{z.sn, z.cn, ffl};
    const v4 ys = stage_ys(sh, vm, X, rest);
    const double e = y_spread(sh, vm, X, rest), size = std::fabs(yd0) + e;
    int flips = 0;
    for (int s3 = 0; s3 < 3; ++s3) {
        const FbCol& col = vm.fb[flips];
        const double y = s1 * (ys[s3] + col.y[s3] * z.fz);
        if (!(std::fabs(y) > 1e-12 * (size + col.yb * std::fabs(z.fz))))
            return false;  // too near 0 (or NaN): the stages
        if (y < 0.0) flips |= 1 << s3;
    }
    z.flips = flips;
    if (yst) {
        *yst = YStages{ys + vm.fb[flips].y * z.fz, true};
        *spread = e + vm.fb[flips].yb * std::fabs(z.fz);
    }
    return true;
}

// A rolling ball on the floor through a step of dt: it rolls (its spin is its y' as the
// step begins, ffl = 0) or it slips, the floor's friction ffl = -mu_k N sgn(y' - s)
// acting on it the whole step, which turns its spin by -kroll ffl dt.
struct FloorStep {
    bool rolls;
    double ffl, dt;
};

// May a rolling ball that the sgn() law turns within the step take a sign pattern's map
// (map_pattern's, with its floor friction as it slips): rolling at every stage
// (map_rolls, with the pattern's floor friction) or slipping (map_slips, with the
// pattern's y'; cst: the stage times).  Sets z.flips to the pattern.
template <int N, int CASE>
BB_INLINE bool roll_pattern(const Params& q, Shape<N, CASE> sh, const VecMap& vm,
                            const double* X, MapIn& z, const FloorStep& fls,
                            const double* cst) {
    YStages yst;
    double spread = NAN;
    if (!map_pattern(sh, vm, X, z, fls.ffl, &yst, &spread)) return false;
    if (fls.rolls) return map_rolls(q, sh, vm, X, z);
    return map_slips(q, sh, vm, X, z, fls.ffl, cst, spread, yst);
}

// The increment dX of a mapped step, two rows at a time: (u_i, u_i') and (aux, aux').
// decoupled: a mode's rows involve only its own u, u' (the modes coupled through F_b
// alone), as in the solid and sliding ball bars' maps and a rolling ball's as it slips
// (the sliding ball's map); the rolled map couples them.  Skipping the other columns'
// zeros leaves every sum's bits.
template <int N, int CASE>
BB_INLINE void map_increment(Shape<N, CASE> sh, const VecMap& vm, const double* X, MapIn z,
                             double* dX, bool decoupled) {
    const double sn = z.sn, cn = z.cn, fz = z.fz;
    const FbCol& fbc = vm.fb[z.flips];
    const int n = sh.n(), nx = sh.nxm();
    auto full = [&](int pr) {
        v2 d = vm.dS[pr] * sn + vm.dC[pr] * cn + fbc.d[pr] * fz;
        for (int j = 0; j < nx; ++j) d += vm.dP[pr][j] * X[j];
        return d;
    };
    for (int i = 0; i < n; ++i) {
        v2 d;
        if (decoupled) {
            d = vm.dS[i] * sn + vm.dC[i] * cn + fbc.d[i] * fz;
            d += vm.dP[i][i] * X[i];
            d += vm.dP[i][n + i] * X[n + i];
        } else {
            d = full(i);
        }
        dX[i] = d[0];
        dX[n + i] = d[1];
    }
    if (sh.diag() && !sh.ball()) {
        dX[sh.iy()] = 0.0;
        dX[sh.iyd()] = 0.0;
    } else {
        const v2 d = full(n);
        dX[sh.iy()] = d[0];
        dX[sh.iyd()] = d[1];
    }
}

// Four lanes as one 32-byte vector, for the AVX2 copy's mapped step (WideMap): one
// instruction where v4's two pairs take two.  Its lanes do v4's operations in v4's order,
// so the same bits.  (Built from v4 through memory, by reference: a 32-byte vector passed
// by value outside AVX code would change the calling convention.)
#ifdef BB_AVX2_CLONE
typedef double v4w __attribute__((vector_size(32)));
#else
using v4w = v4;  // (WideMap's arithmetic as v4's, where no AVX2 copy is built)
#endif
BB_INLINE void widen(v4w& w, const v4& a) { std::memcpy(&w, &a, sizeof w); }

// The one-mode ball's mapped step in lanes (u, u', y, y'), the order of X: the map's
// increment rows and the damped velocity's stages, packed once per run from its VecMap.
// The mode's row has zeros in the ball's columns (its skipped columns, map_increment), so
// each lane's sum is map_increment's: adding a zero product moves at most a zero's sign.
struct WideMap {
    v4w S, C, F, P[4];
    v4w vS, vC, vF, vP[2], wv;

    explicit WideMap(const VecMap& vm) {
        auto pair = [](v4w& w, v2 lo, v2 hi) { widen(w, v4{lo, hi}); };
        pair(S, vm.dS[0], vm.dS[1]);
        pair(C, vm.dC[0], vm.dC[1]);
        pair(F, vm.fb[0].d[0], vm.fb[0].d[1]);
        for (int j = 0; j < 4; ++j) pair(P[j], j < 2 ? vm.dP[0][j] : v2{0.0, 0.0}, vm.dP[1][j]);
        widen(vS, vm.vS[0]);
        widen(vC, vm.vC[0]);
        widen(vF, vm.fb[0].v[0]);
        widen(vP[0], vm.vP[0][0]);
        widen(vP[1], vm.vP[0][1]);
        widen(wv, vm.wv[0]);
    }

    // map_increment's dX, all four lanes at once
    BB_ALWAYS_INLINE void increment(const double* X, MapIn z, double* dX) const {
        v4w d = S * z.sn + C * z.cn + F * z.fz;
        for (int j = 0; j < 4; ++j) d += P[j] * X[j];
        for (int j = 0; j < 4; ++j) dX[j] = d[j];
    }

    // map_flows' Wv v^2 of the mode's velocity at stages 2-4 (lanes 0-2)
    BB_ALWAYS_INLINE void stage_loss(const double* X, MapIn z, v4w& out) const {
        v4w v = vS * z.sn + vC * z.cn + vF * z.fz;
        v += vP[0] * X[0] + vP[1] * X[1];
        out = wv * v * v;
    }
};
// (in WideMap's place where the step is not its)
struct NoWide {
    NoWide() = default;
    explicit NoWide(const VecMap&) {}
};

// The energy flows of a mapped step: the dashpots' loss (the RK4 weights on the stage
// velocities squared, stages 2-4 in lanes), the force's work S (Fs . z) + C (Fc . z)
// (lanes Fs, Fc), and for the ball sum_s b_s F_b,s y'_s and sum_s b_s F_b,s psi_d u'_s:
// with F_b the same at every stage, F_b dy and F_b psi_d du; in a sign pattern's step
// (F_b,s = +-F_b), the rows VecMap::fw of the pattern.  decoupled: as map_increment's.
// ffl: in a rolling ball's pattern step, its floor friction as it slips, the same at
// every stage, in the one-sign column (a step of one sign has it in z.fz).
template <int N, int CASE, class Wide = NoWide>
BB_INLINE void map_flows(const Params& q, Shape<N, CASE> sh, const VecMap& vm, Flows& fl,
                         const double* X, const double* dX, MapIn z, bool decoupled,
                         double ffl = 0.0, const Wide& wide = {}) {
    const double sn = z.sn, cn = z.cn, fz = z.fz;
    const FbCol& fbc = vm.fb[z.flips];
    const int n = sh.n(), nx = sh.nxm();
    double pv = 0.0;
    for (int i = 0; i < n; ++i) pv += vm.w0[i] * X[n + i] * X[n + i];
    if (sh.tmd()) {
        double rd = X[sh.iyd()];
        for (int i = 0; i < n; ++i) rd -= q.modes.pA[i] * X[n + i];
        pv += vm.w0[n] * rd * rd;
    }
    v4 wvv[NV_MAX];  // Wv v^2 of velocity k at stages 2-4
    for (int i = 0; i < n; ++i) {
        if constexpr (std::is_same_v<Wide, WideMap>) {  // the one-mode ball's, in one vector
            v4w o;
            wide.stage_loss(X, z, o);
            std::memcpy(&wvv[i], &o, sizeof o);
            continue;
        }
        v4 v = vm.vS[i] * sn + vm.vC[i] * cn + fbc.v[i] * fz;
        if (ffl != 0.0) v += vm.fb[0].v[i] * ffl;
        if (sh.diag()) {
            v += vm.vP[i][i] * X[i] + vm.vP[i][n + i] * X[n + i];
        } else if (decoupled) {
            // the loop's order below without its other columns, whose zero products
            // change at most the sign of a zero sum, which v * v does not see
            v += vm.vP[i][i] * X[i];
            v += vm.vP[i][n + i] * X[n + i];
        } else {
            for (int j = 0; j < nx; ++j) v += vm.vP[i][j] * X[j];
        }
        wvv[i] = vm.wv[i] * v * v;
    }
    if (sh.tmd()) {  // the absorber's stroke rate
        v4 v = vm.vS[n] * sn + vm.vC[n] * cn;
        for (int j = 0; j < nx; ++j) v += vm.vP[n][j] * X[j];
        wvv[n] = vm.wv[n] * v * v;
    }
    const int nv = sh.tmd() ? n + 1 : n;
    for (int s3 = 0; s3 < 3; ++s3) {
        for (int k = 0; k < nv; ++k) pv += wvv[k][s3];
    }
    v2 w = vm.fS * sn + vm.fC * cn + fbc.f * fz;
    if (ffl != 0.0) w += vm.fb[0].f * ffl;
    for (int j = 0; j < nx; ++j) w += vm.fP[j] * X[j];
    fl.d_visc += pv;
    fl.w_force += sn * w[0] + cn * w[1];
    if (sh.ball() && z.flips) {
        const FbWork& fw = vm.fw[z.flips];
        v2 g = fw.S * sn + fw.C * cn + fw.F * fz;
        if (ffl != 0.0) g += vm.fwO[z.flips] * ffl;
        for (int j = 0; j < nx; ++j) g += fw.P[j] * X[j];
        fl.d_fric -= fz * g[0];
        fl.w_nr += (1.0 - q.fric.sr) * fz * g[1];
        // the floor friction's -ffl dy (its reaction is reciprocal: map_slips)
        if (ffl != 0.0) fl.d_fric -= ffl * dX[sh.iy()];
    } else if (sh.ball() && fz != 0.0) {
        // (no friction force, a frictionless ball's: it does no work, and its terms are
        // not formed; they would add zeros to sums that start at +0 and never reach -0)
        fl.d_fric -= fz * dX[sh.iy()];
        double pdu = 0.0;
        for (int i = 0; i < n; ++i) pdu += q.modes.pD[i] * dX[i];
        fl.w_nr += (1.0 - q.fric.sr) * fz * pdu;
    }
}

// A sign pattern's mapped step: the increment, the flows and the new state.
template <int N, int CASE>
BB_INLINE void take_pattern(const Params& q, Shape<N, CASE> sh, const VecMap& vm, Flows& fl,
                            double* X, double* dX, MapIn z) {
    map_increment(sh, vm, X, z, dX, true);
    map_flows(q, sh, vm, fl, X, dX, z, true);
    for (int j = 0; j < sh.nxm(); ++j) X[j] += dX[j];
}

// A rolling ball's spin after a mapped step: rolled, the spin is its y'; slipped, s' =
// -kroll ffl, and the floor's loss -ffl (dy - int s dt), its -ffl dy counted with F_b's
// (map_flows).
template <int N, int CASE>
BB_INLINE void spin_after_map(const Params& q, Shape<N, CASE> sh, double* X, Flows& fl,
                              const FloorStep& fls) {
    const double ffl = fls.ffl, dt = fls.dt;
    if (fls.rolls) {
        X[sh.is()] = X[sh.iyd()];
    } else {
        fl.d_fric += ffl * (X[sh.is()] * dt - 0.5 * q.roll.kroll * ffl * dt * dt);
        X[sh.is()] -= q.roll.kroll * ffl * dt;
    }
}

// A rolling ball's turning step (roll_pattern's z.flips, not 0): the increment, with its
// floor friction as it slips in the one-sign column, the flows and the new state with
// its spin (spin_after_map).  One copy for every pattern: a rolling ball's kernels are
// few, and each copy costs compile time.
template <int N, int CASE>
BB_INLINE void roll_pattern_step(const Params& q, Shape<N, CASE> sh, const VecMap& vm,
                                 Flows& fl, double* X, double* dX, MapIn z,
                                 const FloorStep& fls) {
    const double ffl = fls.ffl;
    const bool decoupled = !fls.rolls;  // (the sliding ball's map as it slips)
    map_increment(sh, vm, X, z, dX, decoupled);
    if (ffl != 0.0) {
        const int n = sh.n();
        for (int pr = 0; pr <= n; ++pr) {
            const v2 d = vm.fb[0].d[pr] * ffl;
            dX[pr < n ? pr : sh.iy()] += d[0];
            dX[pr < n ? n + pr : sh.iyd()] += d[1];
        }
    }
    map_flows(q, sh, vm, fl, X, dX, z, decoupled, ffl);
    for (int j = 0; j < sh.nxm(); ++j) X[j] += dX[j];
    spin_after_map(q, sh, X, fl, fls);
}

// A turning step (map_pattern's z.flips; the pattern + + + + takes the run's one-sign map
// step).  The two patterns a held ball takes most are picked by branches, each with its
// pattern a constant: a predicted branch takes the pick off the step's chain of
// dependences (the state, the stages' y', the pattern, its column, the state), which the
// pattern as data keeps it on: with every pattern as data, or a switch over all 8 (which
// GCC turns into a table of the columns), a held ball's run took 1.09x as long (the paper
// preset at 10 N), and + + + + as data 1.10x; each pattern with a branch of its own costs
// compile time in every ball kernel.
template <int N, int CASE>
BB_INLINE void pattern_step(const Params& q, Shape<N, CASE> sh, const VecMap& vm, Flows& fl,
                            double* X, double* dX, MapIn z) {
    const double sn = z.sn, cn = z.cn, fz = z.fz;
    if (z.flips == 5)  // + - + -
        take_pattern(q, sh, vm, fl, X, dX, MapIn{sn, cn, fz, 5});
    else if (z.flips == 4)  // + + + -
        take_pattern(q, sh, vm, fl, X, dX, MapIn{sn, cn, fz, 4});
    else
        take_pattern(q, sh, vm, fl, X, dX, z);
}

// The tip's W, W' and the auxiliary coordinate (model.hpp's TipAux): the ball's y or the
// absorber's stroke x_a - psi_a u.  aux_always: the stroke even for the solid and locked
// bars (X's own aux slot, as the strobe and the run's first values read it); else 0 there.

template <int N, int CASE>
BB_INLINE TipAux tip_aux(const Params& q, Shape<N, CASE> sh, const double* X, bool aux_always) {
    const int n = sh.n();
    TipAux a{0.0, 0.0, 0.0, 0.0};
    if (n == 1) {
        a.w += q.modes.pL[0] * X[0];
        a.wd += q.modes.pL[0] * X[1];
    } else {
        // (W, W') as one pair of (u_i, u_i'): left to itself GCC summed pairs (u_i, u_i+1)
        // loaded from memory just stored one by one, a store-forwarding stall (1.25x
        // slower with 2 modes); with 1 mode (u, u') are adjacent and that pair stalled
        v2 wwd = {0.0, 0.0};
        for (int i = 0; i < n; ++i) wwd += q.modes.pL[i] * v2{X[i], X[n + i]};
        a.w = wwd[0];
        a.wd = wwd[1];
    }
    if (aux_always || sh.has_aux()) {
        a.aux = X[sh.iy()];
        a.auxd = X[sh.iyd()];
        if (sh.tmd()) {
            for (int i = 0; i < n; ++i) {
                a.aux -= q.modes.pA[i] * X[i];
                a.auxd -= q.modes.pA[i] * X[n + i];
            }
        }
    }
    return a;
}

// ceil(v) as a whole number of periods in int64's range: out of range or NaN gives -2^63
// (what x86's conversion gives), a defined value where a cast would be undefined.
inline double ceil_int64(double v) {
    const double c = std::ceil(v);
    const double lim = 9223372036854775808.0;  // 2^63
    return (c >= -lim && c < lim) ? c : -lim;
}

// The first strobe time at or after t0.
inline double first_strobe(const Params& q, double t0) {
    double t_next = 0.0;
    if (q.strobe.period > 0.0) {
        t_next = q.strobe.t0;
        if (t_next < t0) t_next += ceil_int64((t0 - t_next) / q.strobe.period) * q.strobe.period;
    }
    return t_next;
}

// The Poincare strobe's progress in a run: the next sample's time, the rows written and
// the record they go to.
struct StrobeOut {
    double t_next;
    idx n;
    Mat rows;
};

// A Poincare strobe sample due in the step [t, t1]: W, W' by the cubic Hermite, aux, aux'
// linearly, from the step's start values prev and the end state X (model.hpp).
template <int N, int CASE>
BB_INLINE void strobe_step(const Params& q, Shape<N, CASE> sh, const double* X,
                           const TipAux& prev, double t, double t1, double dt, StrobeOut& so) {
    if (q.strobe.period > 0.0 && so.t_next <= t1) {
        if (so.t_next > t && so.n < so.rows.n0) {
            const TipAux a = tip_aux(q, sh, X, true);
            strobe_row(so.rows.row(so.n), so.t_next, t, dt, prev, a);
            so.n += 1;
        }
        so.t_next = so.t_next + q.strobe.period;
    }
}


// After a step whose four stages held the ball (the stick law): the relative slide left
// from the step it stuck in is stopped by a friction impulse, as a plastic impact
// (model.hpp's impact_law with e = 0; the modes jump by g psi_d,i / M_i), its energy
// dissipated by friction.  Held, y' then stays 0 and y does not drift.
template <int N, int CASE>
BB_INLINE void stop_slide(const Params& q, Shape<N, CASE> sh, double* X, Flows& fl) {
    const ImpactJump j = impact_law(X[sh.iyd()], 0.0, q.ball.meff);
    X[sh.iyd()] = j.yd;
    jump_modes(q, sh.n(), X, j.g);
    fl.d_fric += j.loss;
}

// After a step whose four stages rolled without slip (Shape::rolls): the spin takes y'
// exactly, so that the slip inside the band does not drift; the spin's energy it changes,
// (1/5) m (s^2 - y'^2), goes to friction.
template <int N, int CASE>
BB_INLINE void stop_roll_slip(const Params& q, Shape<N, CASE> sh, double* X, Flows& fl) {
    const double s = X[sh.is()], yd = X[sh.iyd()];
    fl.d_fric += 0.2 * q.ball.m * (s * s - yd * yd);
    X[sh.is()] = yd;
}

// A step as the walls' and the stick's bookkeeping see it: its start t and end t1 (each
// t0 + k dt, so that event times stay within the run: t1 - t may differ from dt in its
// last bit), and whether it is in the steady part, whose events are recorded.
struct StepSpan {
    double t, t1;
    bool steady;
};

// The ball's walls at the step's end t1 (model.hpp's wall rule; the modes jump by
// g psi_d,i / M_i) and the stick bookkeeping.  Returns whether the ball is in contact
// (on a wall at rest, or a sub-threshold impact).
template <int N, int CASE>
BB_INLINE bool ball_walls(const Params& q, Shape<N, CASE> sh, double* X, const EventLog& log,
                          StickState& ss, const StepSpan& step) {
    const int n = sh.n(), iy = sh.iy(), iyd = sh.iyd();
    const double t = step.t, t1 = step.t1;
    const WallResult w = wall_rule(log.met, log.imp, X[iy], X[iyd], t1, step.steady, q.ball);
    X[iy] = w.y;
    X[iyd] = w.yd;
    if (w.outcome == IMPACT || w.outcome == MICRO_IMPACT) jump_modes(q, n, X, w.g);
    const bool contact = w.outcome == MICRO_IMPACT || w.outcome == ON_WALL;
    // stuck: off the walls with |y'| inside the band where the sgn() law chatters
    // (V_STICK = V_IMPACT + 2 F_c dt / m_eff)
    const bool stuck = q.fric.fc > 0.0 && !contact && std::fabs(X[iyd]) < q.fric.vstick;
    stick_step(stuck, ss, t, t1, log, q.fric.stick_min);
    return contact;
}

// A compliant contact of the ball with a wall (Contact::on), from the step whose end
// first finds the ball past the wall to the step whose end finds it back inside: its
// wall, start (the crossing, interpolated linearly in the step), the speed it began with
// (y' at the start of that step, which set its damping chi = alpha / v_in), its largest
// force at step ends, and whether it counts as an impact (v_in > V_IMPACT; slower, it is
// contact, as the impact law's micro impacts are).  Kept in met between calls.
struct Episode {
    bool on = false, counted = false, steady = false;
    double wall = 0.0, t0 = 0.0, vin = 0.0, peak = 0.0;

    static Episode load(const double* met) {
        Episode e;
        e.on = met[L::CONTACT_ON] != 0.0;
        e.counted = met[L::CONTACT_COUNTED] != 0.0;
        e.steady = met[L::CONTACT_STEADY] != 0.0;
        e.wall = met[L::CONTACT_WALL];
        e.t0 = met[L::CONTACT_T0];
        e.vin = met[L::CONTACT_VIN];
        e.peak = met[L::CONTACT_PEAK];
        return e;
    }
    void store(double* met) const {
        met[L::CONTACT_ON] = on ? 1.0 : 0.0;
        met[L::CONTACT_COUNTED] = counted ? 1.0 : 0.0;
        met[L::CONTACT_STEADY] = steady ? 1.0 : 0.0;
        met[L::CONTACT_WALL] = wall;
        met[L::CONTACT_T0] = t0;
        met[L::CONTACT_VIN] = vin;
        met[L::CONTACT_PEAK] = peak;
    }
};

// A run's compliant contacts: the episode under way and the rows the counted ones are
// written to as they end (close_contact).
struct Contacts {
    Episode& ep;
    Mat rows;
};

// The ball as a step begins, as a compliant contact reads it: its y0 (a contact that
// begins in the step crossed the wall between y0 and the step's end) and the speed v0 a
// contact that begins in the step is damped for (contact_speed).
struct Approach {
    double y0, v0;
};

// The speed a contact's damping is referred to: y' as the step begins, at least the
// impact threshold (a ball that creeps onto a wall is damped as one arriving at it).
inline double contact_speed(const Params& q, double yd) {
    const double floor = q.ball.vimp > 1e-12 ? q.ball.vimp : 1e-12;
    return std::fabs(yd) > floor ? std::fabs(yd) : floor;
}

// Where in the step [t, t + dt] the penetration d = |y| - delta/2 crossed zero, from its
// values d0 at the start and d1 at the end (of opposite signs), linearly.
inline double crossing(double t, double dt, double d0, double d1) {
    const double s = d0 != d1 ? d0 / (d0 - d1) : 0.0;
    return t + (s > 0.0 ? (s < 1.0 ? s : 1.0) : 0.0) * dt;
}

// A contact's end: its row (start, wall, v_in, duration, peak force, v_out) for a counted
// contact that began in the steady part (of the call it began in), while there is room.
inline void close_contact(const EventLog& log, Mat rows, const Episode& ep, double t_end,
                          double vout) {
    double* met = log.met;
    met[L::MAX_CONTACT_FORCE] = Steady::pymax(met[L::MAX_CONTACT_FORCE], ep.peak);
    if (!ep.counted || !ep.steady) return;
    const idx k = idx(met[L::N_CONTACT_REC]);
    if (k < rows.n0) {
        double* r = rows.row(k);
        r[0] = ep.t0;
        r[1] = ep.wall;
        r[2] = ep.vin;
        r[3] = t_end - ep.t0;
        r[4] = ep.peak;
        r[5] = vout;
    }
    met[L::N_CONTACT_REC] += 1;
}

// The compliant contact's bookkeeping at the step's end t1 (in place of the impact law's
// wall rule): a contact begins (counted as an impact at its start, with y'- = wall v_in,
// or as a micro impact), goes on (its peak force) or ends (close_contact), and the stick
// bookkeeping off the walls.  from: the ball as the step began; the crossing is
// interpolated over the span's own t1 - t.  Returns whether the ball is in contact as
// the impact law means it (resting on a wall: a contact that began slower than V_IMPACT).
template <int N, int CASE>
BB_INLINE bool contact_walls(const Params& q, Shape<N, CASE> sh, const double* X,
                             const EventLog& log, const Contacts& cs, StickState& ss,
                             const Approach& from, const StepSpan& step) {
    const double t = step.t, t1 = step.t1, dt = t1 - t;
    const double y0 = from.y0, v0 = from.v0;
    const bool steady = step.steady;
    Episode& ep = cs.ep;
    const double y = X[sh.iy()], yd = X[sh.iyd()], half = q.ball.half;
    const double d0 = std::fabs(y0) - half, d1 = std::fabs(y) - half;
    if (!ep.on && d1 > 0.0) {
        ep.on = true;
        ep.wall = y > 0.0 ? 1.0 : -1.0;
        ep.t0 = crossing(t, dt, d0, d1);
        ep.vin = v0;
        ep.peak = 0.0;
        ep.counted = v0 > q.ball.vimp;
        ep.steady = steady;
        if (ep.counted)
            count_impact(log.met, log.imp, ep.t0, ep.wall, ep.wall * v0, steady);
        else
            log.met[L::N_MICRO] += 1;
    }
    if (ep.on && d1 > 0.0) {
        ep.peak = Steady::pymax(ep.peak, std::fabs(contact_force(q, y, yd).f));
    } else if (ep.on) {
        close_contact(log, cs.rows, ep, crossing(t, dt, d0, d1), std::fabs(yd));
        ep.on = false;
    }
    const bool stuck = q.fric.fc > 0.0 && !ep.on && std::fabs(yd) < q.fric.vstick;
    stick_step(stuck, ss, t, t1, log, q.fric.stick_min);
    return ep.on && !ep.counted;
}

// ---- the kernels (rk4_run.hpp, rk4_batch.cpp) -----------------------------------------

// One run's arguments (checked by bind_rk4.cpp).
struct RunArgs {
    const double* p;
    Vec x;
    double t0, dt;
    idx n_steps, steady_start, rec_every;
    Mat rec, imp, stick, strobe;
    Vec met;
    Mat buf;  // the regenerative delay history (nbuf, 2); may be empty for harmonic runs
    // a compliant contact's rows (CONTACT_NCOL columns); empty (0 rows): not kept
    Mat contact;
    // a cut's per-mode extremes: row i holds the max and min of u_i over the steady steps
    // (updated in place, so a caller resets them to -inf, +inf for a window of its own);
    // empty (0 rows): not kept
    Mat modes;
};

// A batch's arguments (checked by bind_rk4.cpp).
struct BatchArgs {
    Mat P;  // (nb, P_SIZE)
    Mat x;  // (nb, 2n + 2)
    double t0, dt;
    idx n_steps, steady_start;
    Arr3 imp, stick, strobe;  // (nb, cap, 3), (nb, cap, 2), (nb, cap, 5)
    Mat met;                  // (nb, MET_SIZE)
};

#ifdef BB_AVX2_CLONE
inline bool cpu_has_avx2() {
    static const bool yes = __builtin_cpu_supports("avx2");
    return yes;
}
#endif

void run_single(const RunArgs& a);
void run_batch(const BatchArgs& a);

// The kernel a run takes: the one specialised on its mode count, its case (ROLLING for a
// rolling ball) and its forcing, or (generic) the kernel of a run-time shape: a compliant
// contact, and the shapes that have no specialised kernel.  A copy's kernels are compiled
// in two halves, each a file of its own (rk4_run.hpp): the one- and two-mode kernels
// (few), and the three- and four-mode ones (with the kernel of a run-time shape in the
// baseline's).
struct ShapeKey {
    int n, kase, forcing;
    bool generic;
    bool few() const { return !generic && (n == 1 || n == 2); }
};
ShapeKey shape_key(const RunArgs& a);  // rk4.cpp

#ifdef BB_AVX2_CLONE
void run_few_avx2(const RunArgs& a, ShapeKey k);   // rk4_avx2.cpp
void run_many_avx2(const RunArgs& a, ShapeKey k);  // rk4_avx2_many.cpp
#else
void run_many_base(const RunArgs& a, ShapeKey k);  // rk4_many.cpp
#endif

}  // namespace bb::rk4
