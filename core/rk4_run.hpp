// The RK4 run's body and its dispatch on the run's shape, for the kernel files that
// compile it, two per instruction set (ShapeKey::few): rk4.cpp and rk4_many.cpp (the
// baseline ISA; rk4.cpp also holds run_single, which picks a copy at run time), and
// rk4_avx2.cpp and rk4_avx2_many.cpp (rk4.hpp says what the copy gains).  Each is a
// translation unit of its own, so that a build on two cores compiles them side by side.
//
// The step's state and scratch are local arrays of the kernel function and every helper
// is inlined into it, so nothing of the step goes through memory that the records might
// alias and, with the mode count a template constant, the state stays in registers.
// Specialised on the mode count 1, 2, 3, the case and the forcing (the other bars' and
// the cut's branches fold away), with one kernel for a run-time mode count (4..NMAX).
// (Everything here has internal linkage: each kernel file has its own copy, and only the
// functions it marks for its ISA are compiled for it; the rest stays baseline code.)
#pragma once

#include <type_traits>

#include "noise.hpp"
#include "rk4.hpp"

namespace bb::rk4 {
namespace {

// Python's a % b (the sign of b), for a negative history offset.
inline idx floor_mod(idx a, idx b) {
    const idx r = a % b;
    return (r != 0 && ((r < 0) != (b < 0))) ? r + b : r;
}

// The delayed surface of a regenerative cut (docs/model.md, section 4): the tool meets
// min_j [j h_m + W(t_s - j tau)] at the stage times t_s = t + c dt, c = 0, 1/2, 1.
// Node kg of the history is time t_cut + kg dt, counted over every call since the cut
// began; buf holds the newest nodes circularly.  t_s - j tau is node kg + off[q][j] plus
// a fixed fraction, interpolated between two stored nodes with fixed weights (the cubic
// Hermite from W and W', or linear), so each lookup is four multiply-adds.  ptr[j] is the
// buffer row of node kg + off[0][j], advanced by one each step (no modulo).
struct Delay {
    int nrev = 0;
    idx nbuf = 0;
    double feed = 0.0, w_before_cut = 0.0;
    idx off[3][NREV_MAX];
    double wts[3][NREV_MAX][4];
    idx ptr[NREV_MAX];

    void init(const double* p, double dt, idx kg0, idx rows) {
        nrev = int(p[L::N_REV]);
        nbuf = rows;
        feed = p[L::FEED];
        w_before_cut = p[L::HIST_W0];
        const bool cubic = p[L::INTERP] > 0.0;
        for (int q = 0; q < 3; ++q) {
            for (int j = 0; j < nrev; ++j) {
                const double d = 0.5 * q - double(j + 1) * p[L::TAU] / dt;
                const double fl = std::floor(d);
                off[q][j] = idx(fl);
                const double fr = d - fl;
                double* w = wts[q][j];
                if (cubic) {
                    const double f2 = fr * fr, f3 = f2 * fr;
                    w[0] = 2.0 * f3 - 3.0 * f2 + 1.0;
                    w[1] = (f3 - 2.0 * f2 + fr) * dt;
                    w[2] = -2.0 * f3 + 3.0 * f2;
                    w[3] = (f3 - f2) * dt;
                } else {
                    w[0] = 1.0 - fr;
                    w[1] = 0.0;
                    w[2] = fr;
                    w[3] = 0.0;
                }
            }
        }
        for (int j = 0; j < nrev; ++j) ptr[j] = floor_mod(kg0 + off[0][j], nbuf);
    }

    // W(t_s - j tau) at stage time index q of step kg from the history
    double delayed(const Mat& buf, idx kg, int q, int j) const {
        const double* w = wts[q][j];
        const idx a = kg + off[q][j];
        if (a >= 0) {
            idx ia = ptr[j] + (off[q][j] - off[0][j]);
            if (ia >= nbuf) ia -= nbuf;
            const idx ib = ia + 1 < nbuf ? ia + 1 : 0;
            return w[0] * buf(ia, 0) + w[1] * buf(ia, 1) + w[2] * buf(ib, 0) + w[3] * buf(ib, 1);
        }
        if (a + 1 >= 0)  // between the surface before the cut and node 0
            return w[0] * w_before_cut + w[2] * buf(0, 0) + w[3] * buf(0, 1);
        return w_before_cut;
    }

    // The surface at stages 0, 1 (and 2, the same time) and 3.  Until h first reaches
    // zero the j = 1 term is the minimum, so the older revolutions are read only after.
    void surface(const Mat& buf, idx kg, bool all_revs, double* hsurf) const {
        const int nr_eff = all_revs ? nrev : 1;
        for (int q = 0; q < 3; ++q) {
            double hmin = 1e300;
            for (int j = 0; j < nr_eff; ++j)
                hmin = Steady::pymin(hmin, double(j + 1) * feed + delayed(buf, kg, q, j));
            hsurf[q < 2 ? q : 3] = hmin;
        }
        hsurf[2] = hsurf[1];
    }

    void advance() {
        for (int j = 0; j < nrev; ++j) {
            ptr[j] += 1;
            if (ptr[j] == nbuf) ptr[j] = 0;
        }
    }
};

// The regenerative cut's bookkeeping of a step's stages: the chip thickness
// h = max(0, surface - W) and the force of the cutting law, Kr b h (m_c = 0) or Kienzle's
// K b h^(1 - m_c) (h > 0), times the noise's gain max(0, 1 + eps_j) where the cut has
// noise.  The linear law without noise computes the product krb * h alone, so that a
// linear cut's bits do not depend on the other law or on the noise.
struct Cut {
    double krb;
    double max_force, first_zero, n_zero;
    bool cut_zero = false;  // h = 0 at some stage of this step
    bool power = false;     // Kienzle's law: h^expo, expo = 1 - m_c
    double expo = 1.0;
    // the noise: eps_j = noise_std N_j(seed) over steps [j steps_per, (j + 1) steps_per)
    // of the cut (steps counted from its start, so a continued run draws the same eps)
    bool noisy = false;
    double noise_std = 0.0, gain = 1.0;
    std::uint64_t seed = 0;
    idx steps_per = 1, j_now = -1;

    static Cut of(const double* p, const double* met, double dt) {
        Cut c;
        c.krb = p[L::KR_B];
        c.max_force = met[L::MAX_FORCE];
        c.first_zero = met[L::FIRST_ZERO_T];
        c.n_zero = met[L::N_ZERO_STEPS];
        c.power = p[L::CUT_MC] != 0.0;
        c.expo = 1.0 - p[L::CUT_MC];
        c.noisy = p[L::NOISE_STD] > 0.0;
        if (c.noisy) {
            c.noise_std = p[L::NOISE_STD];
            c.seed = std::uint64_t(p[L::NOISE_SEED]);
            // the interval in whole steps, at least one (capped where the count would
            // leave an int64: one interval for any run the core can take)
            const double r = std::nearbyint(p[L::NOISE_INTERVAL] / dt);
            c.steps_per = r >= 1.0 ? (r < 4.0e18 ? idx(r) : idx(4.0e18)) : 1;
        }
        return c;
    }

    // the gain of step kg of the cut (kg >= 0)
    void noise_at(idx kg) {
        const idx j = kg / steps_per;
        if (j != j_now) {
            j_now = j;
            const double g = 1.0 + noise_std * noise::normal_at(seed, std::uint64_t(j));
            gain = g > 0.0 ? g : 0.0;
        }
    }

    double force(double hmin, double ws, double t_stage) {
        double hh = hmin - ws;
        if (hh <= 0.0) {
            hh = 0.0;
            if (!cut_zero) {
                cut_zero = true;
                if (first_zero < 0.0) first_zero = t_stage;
            }
        }
        double f = power ? krb * std::pow(hh, expo) : krb * hh;
        if (noisy) f *= gain;
        max_force = Steady::pymax(max_force, f);
        return f;
    }
};

template <int N, int CASE, int FORCING, bool WIDE = false>
BB_INLINE void run_body(const RunArgs& a) {
    Params q = unpack(a.p, a.dt);  // (q.contact.chi is set contact by contact)
    const Shape<N, CASE> sh(q);
    const bool regen = FORCING >= 0 ? FORCING == L::REGENERATIVE : q.force.regen;
    const int n = sh.n(), nx = sh.nx(), iyd = sh.iyd();
    const bool ball = sh.ball(), has_aux = sh.has_aux();
    const bool hertz = ball && sh.hertz(q);  // a compliant contact at the walls
    const double t0 = a.t0, dt = a.dt;
    double* met = a.met.d;
    const Mat buf = a.buf;
    const idx nbuf = buf.n0;
    const idx kg0 = idx(met[L::STEPS_DONE]);  // steps since the cut began

    Delay delay;
    if (regen) delay.init(a.p, dt, kg0, nbuf);
    Cut cut = Cut::of(a.p, met, dt);
    const bool stop_at_zero = a.p[L::STOP_AT_ZERO] > 0.0;
    double hsurf[4] = {0.0, 0.0, 0.0, 0.0};
    idx steps_run = a.n_steps;

    constexpr int NXC = Shape<N, CASE>::NXC;
    // the stages' short forms (stages_fast: the same bits, a little sooner) but in a
    // rolling ball's kernels, which they would take 1.5 s of compile each
    constexpr bool SHORT_STAGES = CASE != ROLLING;
    double X[NXC], Kd[NXC], dX[NXC];
    // (unrolled here, before GCC's scalar replacement of X and Kd, which a loop with a
    // run-time index would keep in memory)
#pragma GCC unroll 8
    for (int j = 0; j < nx; ++j) {
        X[j] = a.x[j];
        Kd[j] = 0.0;
    }
    if (sh.kase() == L::LOCKED) X[iyd] = 0.0;
    double fst[4], cst[4], wst[4];  // forcing at the stages, c_s dt, b_s dt
    for (int s = 0; s < 4; ++s) {
        cst[s] = C_FRAC[s] * dt;
        wst[s] = B_MULT[s] * (dt / 6.0);
    }

    // the step as an affine map where F_b cannot switch (linmap.hpp)
    // (a rolling ball's map is its rolled regime's, linmap.hpp)
    const bool linear = !regen && !q.stage_loop;
    const VecMap mp = linear ? step_map(n, a.p, dt) : VecMap{};
    const VecMap mpr = linear && sh.rolls() ? step_map(n, a.p, dt, true) : VecMap{};
    // the one-mode ball's mapped step in one 32-byte vector (the AVX2 copy: WideMap)
    constexpr bool WIDE1 = WIDE && N == 1 && CASE == L::BALL;
    const std::conditional_t<WIDE1, WideMap, NoWide> wide(mp);
    const bool check_fb = ball && q.fric.fc > 0.0;
    // a sliding ball that the sgn() law turns within a step: the sign patterns' maps
    const bool patterns =
        linear && check_fb && !q.fric.hold && !sh.rolls() && !hertz && mp.n_patterns == NPAT;
    // and a rolling ball's, in the kernels that can roll alone: GCC's code for a kernel
    // follows its source even where lines fold away, and with the rolling ball's pattern
    // code in them the sliding ball's kernels ran the held paper cases 4-8 % longer;
    // without it their instructions are the same as before it was written (objdump)
    constexpr bool ROLL_MAPS = CASE == ROLLING || CASE < 0;
    const bool roll_patterns = ROLL_MAPS && linear && check_fb && !q.fric.hold && sh.rolls() &&
                               !hertz && mp.n_patterns == NPAT && mpr.n_patterns == NPAT;
    double sn = 0.0, cn = 1.0;

    // streamed metrics in registers, written back at the end; the events' counts and
    // rows go to met and the records directly (model.hpp)
    Steady st = Steady::load(met);
    Flows fl = Flows::load(met);
    idx n_rec = idx(met[L::N_REC]);
    StrobeOut so{0.0, idx(met[L::N_STROBE]), a.strobe};
    const double t_steady = t0 + double(a.steady_start) * dt;
    const EventLog log{met, a.imp, a.stick, t_steady};
    StickState ss;
    // how near the stick law's hold came to slipping, and the steps it did not hold
    double hold_max = met[L::MAX_HOLD_FORCE], n_free = met[L::N_FREE_STEPS];
    // a compliant contact under way (from an earlier call) keeps its damping
    Episode ep = Episode::load(met);
    if (hertz && ep.on) q.contact.chi = q.contact.alpha / ep.vin;

    TipAux prev = tip_aux(q, sh, X, true);
    idx wptr = regen ? kg0 % nbuf : 0;  // the row of the newest node
    if (regen && kg0 == 0) {
        buf(0, 0) = prev.w;
        buf(0, 1) = prev.wd;
    }
    so.t_next = first_strobe(q, t0);

    for (idx k = 0; k < a.n_steps; ++k) {
        const double t = t0 + double(k) * dt;
        const double t1 = t0 + double(k + 1) * dt;  // not t + dt: event times in [t0, t_end]
        if (k % RESYNC == 0) {
            sn = std::sin(q.force.om * t);
            cn = std::cos(q.force.om * t);
        }
        cut.cut_zero = false;
        if (regen) delay.surface(buf, kg0 + k, cut.first_zero >= 0.0, hsurf);
        if (regen && cut.noisy) cut.noise_at(kg0 + k);
        const Phase ph = rotate(sn, cn, q.force.chh, q.force.shh);
        fst[0] = q.force.f0 * sn;
        fst[1] = q.force.f0 * ph.s_h;
        fst[2] = fst[1];
        fst[3] = q.force.f0 * ph.s_1;

        // off the walls a contact's damping is set by the speed the ball has as it
        // begins (contact_walls keeps it for the contact)
        double y0 = 0.0, v0 = 0.0;
        if (hertz) {
            y0 = X[sh.iy()];
            v0 = contact_speed(q, X[iyd]);
            if (!ep.on) q.contact.chi = q.contact.alpha / v0;
        }

        // the step as an affine map if F_b keeps its sign, else the four stages
        bool use_map = linear;
        double fz = 0.0, ffl = 0.0;  // F_b, and a slipping ball's floor friction
        // a rolling ball: its rolled regime's map, or the sliding ball's as it slips
        const bool rolls_now = sh.rolls() && X[sh.is()] == X[iyd];
        const VecMap& map = rolls_now ? mpr : mp;
        if (sh.rolls() && !rolls_now)
            ffl = X[iyd] - X[sh.is()] > 0.0 ? -q.roll.muk_n : q.roll.muk_n;
        double spread = NAN;
        YStages yst;
        if (linear && check_fb) {
            fz = map_friction(q, X[iyd]);
            use_map = map_fits(q, sh, map, X, MapIn{sn, cn, fz + ffl}, true, spread, &yst);
        }
        const bool fits = use_map;  // y' of one sign, outside the chatter band
        if (use_map && sh.rolls())
            use_map = rolls_now ? map_rolls(q, sh, map, X, MapIn{sn, cn, fz})
                                : map_slips(q, sh, map, X, MapIn{sn, cn, fz + ffl}, ffl, cst,
                                            spread, yst);
        const double fb = fz;  // F_b alone
        fz += ffl;
        // a slipping ball takes the sliding ball's map, whose modes are decoupled
        const bool decoupled = sh.diag() || (sh.rolls() && !rolls_now);
        // a sliding ball that the sgn() law turns within the step: its sign pattern's map
        MapIn zp{sn, cn, fz};
        bool turns = patterns && !use_map && map_pattern(sh, mp, X, zp);
        if constexpr (ROLL_MAPS) {
            // a rolling ball's, where it rolls, or slips, at every stage
            if (roll_patterns && !fits) {
                zp = MapIn{sn, cn, fb};
                turns = roll_pattern(q, sh, map, X, zp, FloorStep{rolls_now, ffl, dt}, cst);
            }
        }
        // (y' of one sign at every stage: the map above, in the band where map_fits
        // leaves it to the stages)
        if (turns && zp.flips == 0) {
            use_map = true;
            turns = false;
        }
        if (use_map) {
            if constexpr (WIDE1)
                wide.increment(X, MapIn{sn, cn, fz}, dX);
            else
                map_increment(sh, map, X, MapIn{sn, cn, fz}, dX, decoupled);
        }
        // the map holds no contact force: a step in a compliant contact, or one that ends
        // in one, takes the stages
        if (use_map && hertz &&
            (ep.on || !(std::fabs(X[sh.iy()] + dX[sh.iy()]) <= q.ball.half)))
            use_map = false;
        if (turns) {
            if constexpr (ROLL_MAPS) {
                if (sh.rolls())
                    roll_pattern_step(q, sh, map, fl, X, dX, zp, FloorStep{rolls_now, ffl, dt});
                else
                    pattern_step(q, sh, mp, fl, X, dX, zp);
            } else {
                pattern_step(q, sh, mp, fl, X, dX, zp);
            }
        } else if (use_map) {
            if constexpr (WIDE1)
                map_flows(q, sh, map, fl, X, dX, MapIn{sn, cn, fz}, true, 0.0, wide);
            else
                map_flows(q, sh, map, fl, X, dX, MapIn{sn, cn, fz}, decoupled);
            for (int j = 0; j < sh.nxm(); ++j) X[j] += dX[j];
            // (spin_after_map's, written out: the sliding ball's kernels, see ROLL_MAPS)
            if (rolls_now) {
                X[sh.is()] = X[iyd];  // it rolled: the spin is its y'
            } else if (sh.rolls()) {
                // it slipped: s' = -kroll ffl; the floor's loss -ffl (dy - int s dt), its
                // -ffl dy counted with F_b's (map_flows)
                fl.d_fric += ffl * (X[sh.is()] * dt - 0.5 * q.roll.kroll * ffl * dt * dt);
                X[sh.is()] -= q.roll.kroll * ffl * dt;
            }
            if (ball && q.fric.hold) n_free += 1.0;  // the map slides
        } else {
            auto force = [&](int s, const double* Xs) {
                double f = fst[s];
                if (regen) {  // the cutting law at h = max(0, surface - W(t_s))
                    double ws = 0.0;
                    for (int i = 0; i < n; ++i) ws += q.modes.pL[i] * Xs[i];
                    f = cut.force(hsurf[s], ws, t + C_FRAC[s] * dt);
                    fst[s] = f;
                }
                return f;
            };
            bool held, rolled = sh.rolls();
            if (SHORT_STAGES && (!ball || q.fric.ydd_sum_from_first) &&
                stages_fast(sh, X, Kd, cst[0]))
                held = rk4_stages<N, CASE, SHORT_STAGES>(q, sh, X, Kd, StepStages{cst, wst, force},
                                                         fl, hold_max, rolled);
            else
                held = rk4_stages<N, CASE, false>(q, sh, X, Kd, StepStages{cst, wst, force}, fl,
                                                  hold_max, rolled);
            if (rolled) stop_roll_slip(q, sh, X, fl);
            // (a step held from y' = 0 keeps y' = 0 exactly: nothing to stop)
            if (ball && held && X[iyd] != 0.0) stop_slide(q, sh, X, fl);
            if (ball && q.fric.hold && !held) n_free += 1.0;
        }
        const bool steady = k >= a.steady_start;

        strobe_step(q, sh, X, prev, t, t1, dt, so);
        // (the walls' arguments are built at the calls: a StepSpan, Approach or Contacts
        // kept as a named local changed GCC's code for the kernels, registers and spills)
        bool contact = false;
        if (hertz)
            contact = contact_walls(q, sh, X, log, Contacts{ep, a.contact}, ss, Approach{y0, v0},
                                    StepSpan{t, t1, steady});
        else if (ball)
            contact = ball_walls(q, sh, X, log, ss, StepSpan{t, t1, steady});

        // streamed metrics
        prev = tip_aux(q, sh, X, false);
        if (has_aux) st.max_aux_all = Steady::pymax(st.max_aux_all, std::fabs(prev.aux));
        if (regen) {
            wptr += 1;  // the row of node kg + 1
            if (wptr == nbuf) wptr = 0;
            buf(wptr, 0) = prev.w;
            buf(wptr, 1) = prev.wd;
            delay.advance();
            if (cut.cut_zero) cut.n_zero += 1;
        }
        if (steady) {
            st.sample(prev.w, prev.aux, fst[3]);
            if (contact) st.t_contact += dt;
            if (regen && a.modes.n0 > 0) {
                for (int i = 0; i < n; ++i) {
                    a.modes(i, 0) = Steady::pymax(a.modes(i, 0), X[i]);
                    a.modes(i, 1) = Steady::pymin(a.modes(i, 1), X[i]);
                }
            }
        }
        if (a.rec_every > 0 && (k + 1) % a.rec_every == 0 && n_rec < a.rec.n0) {
            double* row = a.rec.row(n_rec);
            row[0] = t1;
            row[1] = prev.w;
            row[2] = prev.wd;
            row[3] = prev.aux;
            row[4] = prev.auxd;
            row[5] = fst[3];
            // a rolling ball's spin where rec has its column
            if (sh.rolls() && a.rec.n1 > L::REC_NCOL) row[L::REC_NCOL] = X[sh.is()];
            n_rec += 1;
        }
        sn = ph.s_1;
        cn = ph.c_1;
        if (cut.cut_zero && stop_at_zero) {
            steps_run = k + 1;
            break;
        }
    }

    // a stick interval still open at the end is closed there
    if (ss.in_stick)
        close_stick(met, a.stick, ss.t0, t0 + double(steps_run) * dt, t_steady, q.fric.stick_min);
#pragma GCC unroll 8
    for (int j = 0; j < nx; ++j) a.x[j] = X[j];
    st.store(met);
    fl.store(met);
    if (hertz) {
        ep.store(met);
        met[L::D_IMPACT] += fl.d_con;
    }
    met[L::N_REC] = double(n_rec);
    met[L::N_STROBE] = double(so.n);
    met[L::MAX_FORCE] = cut.max_force;
    met[L::MAX_HOLD_FORCE] = hold_max;
    met[L::N_FREE_STEPS] = n_free;
    met[L::FIRST_ZERO_T] = cut.first_zero;
    met[L::N_ZERO_STEPS] = cut.n_zero;
    met[L::STEPS_DONE] += double(steps_run);
}

// The case and the forcing as template constants for 1-3 modes, and for the ball and
// solid bars in two planes of two modes (the other cases' and the cut's branches fold
// away: 1.7-3.1x through bb.simulate over the kernel of a run-time shape,
// docs/performance.md).  Copy is a struct whose run<N, CASE, FORCING> is run_body
// compiled for its ISA (Baseline, Avx2).
template <class Copy, int N, int CASE>
void run_case(const RunArgs& a, int forcing) {
    if (forcing == L::REGENERATIVE) return Copy::template run<N, CASE, L::REGENERATIVE>(a);
    Copy::template run<N, CASE, L::HARMONIC>(a);
}

template <class Copy, int N>
void run_modes(const RunArgs& a, ShapeKey k) {
    switch (k.kase) {
        case L::SOLID: return run_case<Copy, N, L::SOLID>(a, k.forcing);
        case L::BALL: return run_case<Copy, N, L::BALL>(a, k.forcing);
        case L::TMD: return run_case<Copy, N, L::TMD>(a, k.forcing);
        case ROLLING: return run_case<Copy, N, ROLLING>(a, k.forcing);
        default: return run_case<Copy, N, L::LOCKED>(a, k.forcing);
    }
}

// The two halves of a copy's kernels (ShapeKey::few), each compiled in a file of its own.
template <class Copy>
void run_few(const RunArgs& a, ShapeKey k) {
    if (k.n == 1) return run_modes<Copy, 1>(a, k);
    run_modes<Copy, 2>(a, k);
}

struct Baseline;

// (the kernel of a run-time shape is the baseline's alone, rk4.hpp: no other copy
// compiles it)
template <class Copy>
void run_many(const RunArgs& a, ShapeKey k) {
    if constexpr (std::is_same_v<Copy, Baseline>) {
        if (k.generic) return Copy::template run<0, -1, -1>(a);
    }
    if (k.n == 3) return run_modes<Copy, 3>(a, k);
    // two bending planes of two modes each (docs/model.md, 4.7)
    if (k.kase == L::BALL) return run_case<Copy, 4, L::BALL>(a, k.forcing);
    run_case<Copy, 4, L::SOLID>(a, k.forcing);
}

struct Baseline {
    template <int N, int CASE, int FORCING>
    static void run(const RunArgs& a) {
        run_body<N, CASE, FORCING>(a);
    }
};

#ifdef BB_AVX2_CLONE
struct Avx2 {
    template <int N, int CASE, int FORCING>
    BB_TARGET_AVX2 static void run(const RunArgs& a) {
        run_body<N, CASE, FORCING, true>(a);
    }
};
#endif

}  // namespace
}  // namespace bb::rk4
