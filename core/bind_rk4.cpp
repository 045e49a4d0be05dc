// boringbar.core.run_rk4 and run_rk4_batch: the RK4 kernels' boundary.
//
// Each takes one run description (RK4Run, RK4Batch: its fields set from Python, each
// setter checking that it is given a float64 array, a writable one for an output, a number
// or an integer).  Everything else is checked here, before the integration starts: each
// array's shape and C-contiguity, and each scalar's range, including the slots of p and
// met the kernel uses to index or to choose its path.
// A bad one is a ValueError that names it and says what is allowed; past these checks
// every write of the kernel stays inside its array (the kernel tests the record counts
// against the arrays' lengths before writing a row).  The integration runs without the GIL.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cmath>
#include <cstdio>
#include <cstdint>
#include <string>

#include "bind_util.hpp"
#include "rk4.hpp"

namespace bb::bind {
namespace {

namespace R = bb::rk4;

std::string num(double v) {
    char s[32];
    std::snprintf(s, sizeof s, "%.17g", v);
    return s;
}

// An integer-valued slot of a parameter vector in [lo, hi].
int int_slot(const double* p, int slot, const char* name, int lo, int hi,
             const std::string& where) {
    const double v = p[slot];
    require(std::isfinite(v) && v == std::floor(v) && v >= lo && v <= hi,
            where + "[" + name + "] = " + num(v) + " must be an integer in [" +
                std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return int(v);
}

// The mode count, the case and the forcing of a parameter vector.
struct Kind {
    int n, kase, forcing;
};

Kind kind_of(const double* p, const std::string& where) {
    Kind k;
    k.n = int_slot(p, L::N_MODES, "N_MODES", 1, L::NMAX, where);
    k.kase = int_slot(p, L::CASE, "CASE", L::SOLID, L::LOCKED, where);
    k.forcing = int_slot(p, L::FORCING, "FORCING", L::HARMONIC, L::REGENERATIVE, where);
    return k;
}

// The metric slots the kernel reads as row counts or step counts (indices into the
// records): finite, non-negative and exact in a double.
void check_counts(const double* met, const std::string& where) {
    static const std::pair<int, const char*> slots[] = {
        {L::N_IMP_REC, "N_IMP_REC"}, {L::N_STICK_REC, "N_STICK_REC"}, {L::N_REC, "N_REC"},
        {L::N_STROBE, "N_STROBE"},   {L::STEPS_DONE, "STEPS_DONE"}};
    for (const auto& [slot, name] : slots) {
        const double v = met[slot];
        require(std::isfinite(v) && v >= 0.0 && v <= 9007199254740992.0,
                where + "[" + name + "] = " + num(v) + " must be a count in [0, 2^53]");
    }
}

void check_time(double t0, double dt, std::int64_t n_steps, std::int64_t steady_start) {
    require(std::isfinite(t0), "t0 = " + num(t0) + " must be finite");
    require(std::isfinite(dt) && dt > 0.0, "dt = " + num(dt) + " must be finite and > 0");
    require(n_steps >= 0, "n_steps = " + std::to_string(n_steps) + " must be >= 0");
    require(steady_start >= 0 && steady_start <= n_steps,
            "steady_start = " + std::to_string(steady_start) + " must be in [0, n_steps = " +
                std::to_string(n_steps) + "]");
}

// A regenerative cut's law and noise: m_c and the noise's relative std in [0, 1), and
// with noise an interval > 0 and a seed that converts to an unsigned integer exactly.
void check_law(const double* p) {
    const double mc = p[L::CUT_MC], sd = p[L::NOISE_STD];
    require(std::isfinite(mc) && mc >= 0.0 && mc < 1.0,
            "p[CUT_MC] = " + num(mc) + " must be in [0, 1)");
    require(std::isfinite(sd) && sd >= 0.0 && sd < 1.0,
            "p[NOISE_STD] = " + num(sd) + " must be in [0, 1)");
    if (sd == 0.0) return;
    const double iv = p[L::NOISE_INTERVAL], seed = p[L::NOISE_SEED];
    require(std::isfinite(iv) && iv > 0.0,
            "p[NOISE_INTERVAL] = " + num(iv) + " must be finite and > 0 with noise");
    require(std::isfinite(seed) && seed == std::floor(seed) && seed >= 0.0 &&
                seed <= 9007199254740992.0,
            "p[NOISE_SEED] = " + num(seed) + " must be an integer in [0, 2^53]");
}

// A regenerative cut's delay: N_REV revolutions of TAU, and a history buffer that holds
// them (N_REV TAU / dt + 3 rows; the kernel's ring-buffer indices rely on it).
void check_cut(const double* p, double dt, std::int64_t nbuf) {
    check_law(p);
    const int nrev = int_slot(p, L::N_REV, "N_REV", 1, R::NREV_MAX, "p");
    const double tau = p[L::TAU];
    require(std::isfinite(tau) && tau > 0.0,
            "p[TAU] = " + num(tau) + " must be finite and > 0 in a regenerative run");
    const double need = double(nrev) * tau / dt + 3.0;
    require(double(nbuf) >= need, "buf has " + std::to_string(nbuf) +
                                      " rows; a regenerative run needs at least N_REV TAU / dt "
                                      "+ 3 = " + num(need));
}

// A rolling ball's constants: ROLL 0 or 1, the friction forces and the band finite and
// >= 0, the static force at least the kinetic one.
void check_roll(const double* p, const std::string& where) {
    int_slot(p, L::ROLL, "ROLL", 0, 1, where);
    for (const auto& [slot, name] : {std::pair{L::ROLL_STATIC, "ROLL_STATIC"},
                                     std::pair{L::ROLL_KINETIC, "ROLL_KINETIC"},
                                     std::pair{L::ROLL_BAND, "ROLL_BAND"}})
        require(std::isfinite(p[slot]) && p[slot] >= 0.0,
                where + "[" + name + "] = " + num(p[slot]) + " must be finite and >= 0");
    require(p[L::ROLL_STATIC] >= p[L::ROLL_KINETIC],
            where + "[ROLL_STATIC] = " + num(p[L::ROLL_STATIC]) + " must be >= ROLL_KINETIC = " +
                num(p[L::ROLL_KINETIC]));
}

// Whether p's ball rolls: its state has the spin after y', 2 n + 3 entries.
bool rolls(const double* p, const Kind& k) { return k.kase == L::BALL && p[L::ROLL] > 0.0; }

// The state's length: u, u', the damper's two entries and a rolling ball's spin (the twin
// of Python's simulate.state_size).
std::int64_t state_length(bool roll, const Kind& k) { return 2 * k.n + 2 + (roll ? 1 : 0); }

// A compliant contact's constants: K >= 0 (0: the impact law) and alpha >= 0, finite.
void check_contact(const double* p, const std::string& where) {
    const double k = p[L::CONTACT_K], alpha = p[L::CONTACT_ALPHA];
    require(std::isfinite(k) && k >= 0.0,
            where + "[CONTACT_K] = " + num(k) + " must be finite and >= 0");
    require(std::isfinite(alpha) && alpha >= 0.0,
            where + "[CONTACT_ALPHA] = " + num(alpha) + " must be finite and >= 0");
}

}  // namespace

// One RK4 run as Python describes it (boringbar.core.RK4Run): the packed parameters p, the
// state x (advanced in place), the time grid, the history's sampling, the records and
// metrics (written in place), a cut's delay history and, optionally, its modes' extremes.
struct RK4Run {
    In<double> p;
    Out<double> x;
    double t0 = 0.0, dt = 0.0;
    std::int64_t n_steps = 0, steady_start = 0, rec_every = 0;
    Out<double> rec, imp, stick, strobe, met;
    Out<double> buf;      // a cut's delay history; (0, 2) for a harmonic run
    Out<double> modes;    // not set: not kept
    Out<double> contact;  // not set: not kept
};

// A lock-step batch of harmonic RK4 runs (boringbar.core.RK4Batch): one row of P, x, met
// and one block of imp, stick, strobe per run, the time grid shared.
struct RK4Batch {
    In<double> P;
    Out<double> x;
    double t0 = 0.0, dt = 0.0;
    std::int64_t n_steps = 0, steady_start = 0;
    Out<double> imp, stick, strobe, met;
};

namespace {

void run_rk4(const RK4Run& run) {
    const RK4Run r = run;  // the arrays held for the run, whatever Python does meanwhile
    R::RunArgs a;
    const Span1<double> p = span1<double>(given(r.p, "p"), "p", L::P_SIZE);
    a.p = p.d;
    const Kind k = kind_of(a.p, "p");
    check_roll(a.p, "p");
    a.x = span1<double>(given(r.x, "x"), "x", state_length(rolls(a.p, k), k));
    a.t0 = r.t0;
    a.dt = r.dt;
    a.n_steps = r.n_steps;
    a.steady_start = r.steady_start;
    a.rec_every = r.rec_every;
    check_time(a.t0, a.dt, a.n_steps, a.steady_start);
    require(a.rec_every >= 0, "rec_every = " + std::to_string(a.rec_every) + " must be >= 0");
    a.rec = span2<double>(given(r.rec, "rec"), "rec", -1, rec_columns(r.rec, rolls(a.p, k)));
    a.imp = span2<double>(given(r.imp, "imp"), "imp", -1, L::IMP_NCOL);
    a.stick = span2<double>(given(r.stick, "stick"), "stick", -1, L::STICK_NCOL);
    a.strobe = span2<double>(given(r.strobe, "strobe"), "strobe", -1, L::STROBE_NCOL);
    a.met = span1<double>(given(r.met, "met"), "met", L::MET_SIZE);
    a.buf = span2<double>(given(r.buf, "buf"), "buf", -1, 2);
    if (r.modes.is_valid()) a.modes = span2<double>(r.modes, "modes", k.n, 2);
    if (r.contact.is_valid())
        a.contact = span2<double>(r.contact, "contact", -1, L::CONTACT_NCOL);
    check_contact(a.p, "p");
    check_counts(a.met.d, "met");
    if (k.forcing == L::REGENERATIVE) check_cut(a.p, a.dt, a.buf.n0);

    nb::gil_scoped_release unlocked;
    R::run_single(a);
}

void run_rk4_batch(const RK4Batch& run) {
    const RK4Batch r = run;  // the arrays held for the run
    R::BatchArgs a;
    const Span2<double> P = span2<double>(given(r.P, "P"), "P", -1, L::P_SIZE);
    a.P = {P.d, P.n0, P.n1};
    const std::int64_t n_runs = P.n0;
    require(n_runs >= 1 && n_runs <= R::BMAX, "a batch of " + std::to_string(n_runs) +
                                                  " runs: P must have 1.." +
                                                  std::to_string(R::BMAX) + " rows");
    const Kind k = kind_of(a.P.row(0), "P[0]");
    const bool roll = rolls(a.P.row(0), k);
    for (std::int64_t r = 0; r < n_runs; ++r) {
        const std::string row = "P[" + std::to_string(r) + "]";
        const Kind kr = kind_of(a.P.row(r), row);
        // (so that the rows of x, the states, have one length)
        require(kr.n == k.n && kr.kase == k.kase && rolls(a.P.row(r), kr) == roll,
                "the runs of a batch must share the mode count, the case and the ball's "
                "motion (" + row + " differs from P[0])");
        require(kr.forcing == L::HARMONIC,
                row + ": batches take harmonic forcing only (cuts: run_rk4)");
        check_contact(a.P.row(r), row);
        check_roll(a.P.row(r), row);
    }
    a.x = span2<double>(given(r.x, "x"), "x", n_runs, state_length(roll, k));
    a.t0 = r.t0;
    a.dt = r.dt;
    a.n_steps = r.n_steps;
    a.steady_start = r.steady_start;
    check_time(a.t0, a.dt, a.n_steps, a.steady_start);
    a.imp = span3<double>(given(r.imp, "imp"), "imp", n_runs, -1, L::IMP_NCOL);
    a.stick = span3<double>(given(r.stick, "stick"), "stick", n_runs, -1, L::STICK_NCOL);
    a.strobe = span3<double>(given(r.strobe, "strobe"), "strobe", n_runs, -1, L::STROBE_NCOL);
    a.met = span2<double>(given(r.met, "met"), "met", n_runs, L::MET_SIZE);
    for (std::int64_t r = 0; r < n_runs; ++r)
        check_counts(a.met.row(r), "met[" + std::to_string(r) + "]");

    nb::gil_scoped_release unlocked;
    R::run_batch(a);
}

}  // namespace

void bind_rk4(nb::module_& m) {
    m.attr("BMAX") = R::BMAX;
    m.attr("NREV_MAX") = R::NREV_MAX;
    auto run = nb::class_<RK4Run>(m, "RK4Run",
                                  "One RK4 run for run_rk4: set every field, then call run_rk4.");
    run.def(nb::init<>());
    Fields<RK4Run>{run}
        .in("p", &RK4Run::p, "the packed parameter vector (P_SIZE float64)")
        .out("x", &RK4Run::x, "the state (2 n + 2 float64), advanced in place")
        .real("t0", &RK4Run::t0, "the start time (s)")
        .real("dt", &RK4Run::dt, "the step (s), > 0")
        .integer("n_steps", &RK4Run::n_steps, "the steps to take, >= 0")
        .integer("steady_start", &RK4Run::steady_start,
                 "the first step of the steady part, in [0, n_steps]")
        .integer("rec_every", &RK4Run::rec_every, "a history row every this many steps; 0: none")
        .records()
        .out("buf", &RK4Run::buf,
             "a cut's delay history of W, W' ((rows, 2); (0, 2) for a harmonic run)")
        .out_or_none("modes", &RK4Run::modes,
                     "a cut's per-mode max and min of u_i over the steady steps, (n, 2), "
                     "updated in place; None: not kept")
        .out_or_none("contact", &RK4Run::contact,
                     "a Hertz contact's rows (start, wall, v_in, duration, peak force, "
                     "v_out), (n, 6); None: not kept");
    auto batch = nb::class_<RK4Batch>(
        m, "RK4Batch", "A lock-step batch for run_rk4_batch: set every field, then call it.");
    batch.def(nb::init<>());
    Fields<RK4Batch>{batch}
        .in("P", &RK4Batch::P, "the runs' packed parameters, one row a run (1..BMAX rows)")
        .out("x", &RK4Batch::x, "the runs' states, one row a run, advanced in place")
        .real("t0", &RK4Batch::t0, "the start time (s)")
        .real("dt", &RK4Batch::dt, "the step (s), > 0")
        .integer("n_steps", &RK4Batch::n_steps, "the steps to take, >= 0")
        .integer("steady_start", &RK4Batch::steady_start,
                 "the first step of the steady part, in [0, n_steps]")
        .out("imp", &RK4Batch::imp, "the impact rows, (runs, n, 3)")
        .out("stick", &RK4Batch::stick, "the stick intervals, (runs, n, 2)")
        .out("strobe", &RK4Batch::strobe, "the Poincare rows, (runs, n, 5)")
        .out("met", &RK4Batch::met, "the metrics, one row a run, updated in place");
    m.def("run_rk4", &run_rk4, nb::arg("run"),
          "Advance run.x (in place) by run.n_steps RK4 steps of the published scheme from "
          "run.t0 (docs/model.md, section 5), writing the records and metrics in place as "
          "boringbar.simulate.kernels describes.  The GIL is released while it runs.");
    m.def("run_rk4_batch", &run_rk4_batch, nb::arg("run"),
          "Advance a batch of harmonic runs (rows of P, x, met; imp, stick, strobe per run) "
          "in lock-step; each run's results are run_rk4's bit for bit.");
}

}  // namespace bb::bind
