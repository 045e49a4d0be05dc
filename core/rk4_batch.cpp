// The published RK4 scheme for a batch of harmonic runs advanced in lock-step.
//
// One RK4 step is a chain of four dependent stage evaluations, so a single run waits on
// latency.  Here up to BMAX independent runs advance together: every stage, the step-end
// events and the streamed metrics are loops over the runs, so the runs' chains overlap.
// The runs share the mode count, the case, t0, dt, the number of steps and the steady
// start; each has its own parameters (row r of P), state, metrics and records.
//
// A run's arithmetic is the single run's (rk4.cpp), through the same helpers (rk4.hpp)
// in the same order, so a run of a batch equals the run alone bit for bit.  The one
// thing a run sees of the others: when any run needs the stage loop, every run's stage
// derivatives are evaluated (those that took the map drop their sums), as the numba
// kernel did.  The derivative so left enters the run's next staged step only as
// X + 0 * Kd, which is X unless X holds a -0.0 or Kd overflowed; the numba batch has
// the same dependence, and this kernel reproduces it.
//
// Runs are stored one after the other (Lane) and the loops over the runs are scalar:
// per run-step this is about twice the single run's time (the numba batch vectorised
// across runs, four to an AVX2 instruction, with the runs' values interleaved).
#include <memory>

#include "rk4.hpp"

namespace bb::rk4 {
namespace {

// One run of the batch: its parameters, tables, state and running metrics.
struct Lane {
    Params q;
    VecMap mp;
    // state, stage derivative, stage sum and map increment; read and written in pairs
    // (v2) where the stages touch them: a pair load of values just stored one by one
    // stalls on store forwarding
    alignas(16) double X[NX_MAX];
    alignas(16) double Kd[NX_MAX];
    alignas(16) double acc[NX_MAX];
    alignas(16) double dX[NX_MAX];
    double fst[4];
    double sn, cn;  // the forcing phase at the next step's start
    double S0, C0;  // ... and at this step's start
    double fz;      // F_b of a mapped step
    double t_next;  // the next strobe time
    double contact;  // 1.0: the ball is on a wall this step
    bool staged;    // the run never takes the map (STAGE_LOOP)
    bool um;        // the run takes the map this step
    idx n_stb;
    TipAux prev;
    StickState ss;
    Steady st;
    Flows fl;
    double* met;
    Mat imp, stick, strobe;
};

template <int N, int CASE>
BB_INLINE void init_lane(Lane& ln, const BatchArgs& a, idx r, Shape<N, CASE> sh) {
    const double* p = a.P.row(r);
    const int nx = sh.nx();
    ln.mp = step_map(sh.n, p, a.dt);
    ln.staged = p[L::STAGE_LOOP] != 0.0;
    for (int j = 0; j < nx; ++j) {
        ln.X[j] = a.x(r, j);
        ln.Kd[j] = 0.0;
        ln.dX[j] = 0.0;
    }
    if (sh.kase == L::LOCKED) ln.X[sh.iyd()] = 0.0;
    ln.sn = 0.0;
    ln.cn = 1.0;
    ln.contact = 0.0;
    ln.met = a.met.row(r);
    ln.imp = a.imp[r];
    ln.stick = a.stick[r];
    ln.strobe = a.strobe[r];
    ln.st = Steady::load(ln.met);
    ln.fl = Flows::load(ln.met);
    ln.n_stb = idx(ln.met[L::N_STROBE]);
    ln.prev = tip_aux(ln.q, sh, ln.X, true);
    ln.t_next = first_strobe(ln.q, a.t0);
}

// Does the run take the map this step (the single run's test, rk4.hpp)?
template <int N, int CASE>
BB_INLINE void decide(Lane& ln, Shape<N, CASE> sh) {
    const Params& q = ln.q;
    bool ok = !ln.staged;
    double fz = 0.0;
    if (sh.ball() && q.fc > 0.0) {
        fz = map_friction(q, ln.X[sh.iyd()]);
        ok = ok && map_fits(q, sh, ln.mp, ln.X, ln.S0, ln.C0, fz, false);
    }
    ln.fz = fz;
    ln.um = ok;
}

// a lane's pair (memcpy: no aliasing of double storage through the vector type)
BB_INLINE v2 load2(const double* p) {
    v2 v;
    __builtin_memcpy(&v, p, sizeof v);
    return v;
}
BB_INLINE void store2(double* p, v2 v) { __builtin_memcpy(p, &v, sizeof v); }

// Stage s of one run (rk4_stage, rk4.hpp), on the lane's pairs.
template <int N, int CASE>
BB_INLINE void stage(Lane& ln, Shape<N, CASE> sh, int s, double cs, double w_s) {
    const int np = sh.n + 1;
    v2 x2[NX_MAX / 2], k2[NX_MAX / 2], sum[NX_MAX / 2];
    for (int p = 0; p < np; ++p) {
        x2[p] = load2(ln.X + 2 * p);
        k2[p] = load2(ln.Kd + 2 * p);
        sum[p] = load2(ln.acc + 2 * p);
    }
    auto force = [&](int st, const double*) { return ln.fst[st]; };
    double f;
    const StageTerms terms = rk4_stage(ln.q, sh, s, x2, k2, sum, cs, w_s, force, f);
    for (int p = 0; p < np; ++p) {
        store2(ln.Kd + 2 * p, k2[p]);
        store2(ln.acc + 2 * p, sum[p]);
    }
    if (!ln.um) stage_flows(ln.q, sh, ln.fl, terms, w_s, f);
}

template <int N, int CASE>
BB_INLINE void run(const BatchArgs& a, Shape<N, CASE> sh, Lane* lanes, int nb) {
    const int nx = sh.nx();
    const double t0 = a.t0, dt = a.dt;
    double cst[4], wst[4];
    for (int s = 0; s < 4; ++s) {
        cst[s] = C_FRAC[s] * dt;
        wst[s] = B_MULT[s] * (dt / 6.0);
    }
    const double t_steady = t0 + double(a.steady_start) * dt;

    for (idx k = 0; k < a.n_steps; ++k) {
        const double t = t0 + double(k) * dt;
        const double t1 = t0 + double(k + 1) * dt;  // not t + dt: event times in [t0, t_end]
        const bool steady = k >= a.steady_start;
        if (k % RESYNC == 0) {
            for (int r = 0; r < nb; ++r) {
                lanes[r].sn = std::sin(lanes[r].q.om * t);
                lanes[r].cn = std::cos(lanes[r].q.om * t);
            }
        }
        for (int r = 0; r < nb; ++r) {
            Lane& ln = lanes[r];
            ln.S0 = ln.sn;
            ln.C0 = ln.cn;
            const Phase ph = rotate(ln.sn, ln.cn, ln.q.chh, ln.q.shh);
            ln.fst[0] = ln.q.f0 * ln.sn;
            ln.fst[1] = ln.q.f0 * ph.s_h;
            ln.fst[2] = ln.fst[1];
            ln.fst[3] = ln.q.f0 * ph.s_1;
            ln.sn = ph.s_1;
            ln.cn = ph.c_1;
        }

        // the step as an affine map for the runs whose F_b keeps its sign
        int n_staged = 0;
        for (int r = 0; r < nb; ++r) {
            decide(lanes[r], sh);
            n_staged += lanes[r].um ? 0 : 1;
        }
        if (n_staged < nb) {
            for (int r = 0; r < nb; ++r) {
                Lane& ln = lanes[r];
                if (!ln.um) continue;
                map_increment(sh, ln.mp, ln.X, ln.S0, ln.C0, ln.fz, ln.dX);
                map_flows(ln.q, sh, ln.mp, ln.fl, ln.X, ln.dX, ln.S0, ln.C0, ln.fz);
            }
        }
        // the others: the four RK4 stages, each a loop over the runs (the runs that took
        // the map too, as the numba kernel did: their derivatives are kept, sums dropped)
        if (n_staged > 0) {
            for (int r = 0; r < nb; ++r) {
                for (int j = 0; j < nx; j += 2) store2(lanes[r].acc + j, v2{0.0, 0.0});
            }
            for (int s = 0; s < 4; ++s) {
                for (int r = 0; r < nb; ++r) stage(lanes[r], sh, s, cst[s], wst[s]);
            }
        }
        for (int r = 0; r < nb; ++r) {
            Lane& ln = lanes[r];
            const double* inc = ln.um ? ln.dX : ln.acc;
            for (int j = 0; j < nx; j += 2) store2(ln.X + j, load2(ln.X + j) + load2(inc + j));
        }

        // step-end events, run by run
        for (int r = 0; r < nb; ++r) {
            Lane& ln = lanes[r];
            strobe_step(ln.q, sh, ln.X, ln.prev, t, t1, dt, ln.t_next, ln.n_stb, ln.strobe);
            if (!sh.ball()) continue;
            const bool hit = ball_walls(ln.q, sh, ln.X, ln.met, ln.imp, ln.stick, ln.ss, t, t1,
                                        steady, t_steady);
            ln.contact = hit ? 1.0 : 0.0;
        }

        // streamed metrics
        for (int r = 0; r < nb; ++r) {
            Lane& ln = lanes[r];
            ln.prev = tip_aux(ln.q, sh, ln.X, false);
            if (sh.has_aux())
                ln.st.max_aux_all = Steady::pymax(ln.st.max_aux_all, std::fabs(ln.prev.aux));
            if (steady) {
                ln.st.sample(ln.prev.w, ln.prev.aux, ln.fst[3]);
                ln.st.t_contact += ln.contact * dt;
            }
        }
    }

    const double t_end = t0 + double(a.n_steps) * dt;
    for (int r = 0; r < nb; ++r) {
        Lane& ln = lanes[r];
        // a stick interval still open at the end is closed there
        if (ln.ss.in_stick)
            close_stick(ln.met, ln.stick, ln.ss.t0, t_end, t_steady, ln.q.stick_min);
        for (int j = 0; j < nx; ++j) a.x(r, j) = ln.X[j];
        ln.st.store(ln.met);
        ln.fl.store(ln.met);
        ln.met[L::N_STROBE] = double(ln.n_stb);
        ln.met[L::STEPS_DONE] += double(a.n_steps);
    }
}

template <int N, int CASE>
BB_INLINE void run_lanes(const BatchArgs& a, int nb) {
    std::unique_ptr<Lane[]> lanes(new Lane[nb]);
    for (int r = 0; r < nb; ++r) lanes[r].q = unpack(a.P.row(r), a.dt);
    const Shape<N, CASE> sh(lanes[0].q);
    for (int r = 0; r < nb; ++r) init_lane(lanes[r], a, r, sh);
    run(a, sh, lanes.get(), nb);
}

template <int N, int CASE>
void run_base(const BatchArgs& a, int nb) {
    run_lanes<N, CASE>(a, nb);
}

#ifdef BB_AVX2_CLONE
template <int N, int CASE>
BB_TARGET_AVX2 void run_avx2(const BatchArgs& a, int nb) {
    run_lanes<N, CASE>(a, nb);
}
#endif

// the kernel for the CPU (rk4.hpp: the same bits either way)
template <int N, int CASE>
void run_shape(const BatchArgs& a, int nb) {
#ifdef BB_AVX2_CLONE
    if (cpu_has_avx2()) return run_avx2<N, CASE>(a, nb);
#endif
    run_base<N, CASE>(a, nb);
}

template <int N>
void run_modes(const BatchArgs& a, int kase, int nb) {
    switch (kase) {
        case L::SOLID: return run_shape<N, L::SOLID>(a, nb);
        case L::BALL: return run_shape<N, L::BALL>(a, nb);
        case L::TMD: return run_shape<N, L::TMD>(a, nb);
        default: return run_shape<N, L::LOCKED>(a, nb);
    }
}

}  // namespace

void run_batch(const BatchArgs& a) {
    const int nb = int(a.P.n0);
    const int n = int(a.P(0, L::N_MODES));
    const int kase = int(a.P(0, L::CASE));
    switch (n) {
        case 1: return run_modes<1>(a, kase, nb);
        case 2: return run_modes<2>(a, kase, nb);
        case 3: return run_modes<3>(a, kase, nb);
        default: return run_shape<0, -1>(a, nb);
    }
}

}  // namespace bb::rk4
