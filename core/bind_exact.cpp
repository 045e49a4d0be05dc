// boringbar.core.run_exact: the exact event-driven integrator's entry point (the harmonic
// and the cut kernel, exact/driver.hpp), which takes one run description (ExactRun, its
// fields set from Python; bind_util.hpp's Fields: each array field's dtype, float64 or
// complex128 for a cut's tables, and an output's writability are checked when it is set).
// Everything else from Python is checked here, before the GIL is released: every array's
// shape and contiguity (prepare's ExactSetup's too: its fields can change after it is
// given, so they are read when the run starts), every scalar's finiteness and range, and
// what the kernel indexes with (the case, the mode count, prepare's regime count and step
// patterns, the record counters), so that no input can make the core read or write out of
// bounds; a wrong one is a ValueError that names it.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "bind_util.hpp"
#include "exact/consts.hpp"
#include "exact/driver.hpp"
#include "layout.hpp"

namespace bb::bind {

namespace {

namespace L = bb::layout;
using exact::GRID_LEVELS;

// Largest counts the checks let through: beyond them a float-to-integer conversion of the
// kernel (a record counter, a step index) could overflow, or a loop could not progress.
constexpr double MAX_COUNT = 9007199254740992.0;  // 2^53: integers exact in a double
constexpr double MAX_STEPS = 1e15;                // steps of dt, H or the strobe in a run
constexpr double MAX_GRID = 1e13;                 // grid steps of h in a run
constexpr double MAX_KNOTS = 1e8;                 // knots a cut's history starts with
constexpr double MAX_REV = 1e6;                   // revolutions in a cut's minimum
constexpr double MAX_TIME_PER_TAU = 1e12;         // |t0| + |t_end| in delays tau

// A record array (rows of ncol floats) that may be empty: NumPy gives a zero-size array the
// strides (0, 0), which bind_util's contiguity test would refuse; no row of it is ever
// touched, so its dtype and shape are all that matter.
template <class A>
Mat record_rows(const A& a, const char* name, idx ncol) {
    if (a.size() == 0 && a.ndim() == 2 && a.dtype() == nb::dtype<double>() &&
        idx(a.shape(1)) == ncol) {
        return {nullptr, 0, ncol};
    }
    return span2<double>(a, name, -1, ncol);
}

template <class T>
bool all_finite(const T* d, idx count) {
    for (idx i = 0; i < count; ++i) {
        if (!std::isfinite(d[i])) return false;
    }
    return true;
}

template <>
bool all_finite(const cplx* d, idx count) {
    for (idx i = 0; i < count; ++i) {
        if (!std::isfinite(d[i].real()) || !std::isfinite(d[i].imag())) return false;
    }
    return true;
}

void require_finite(bool ok, const std::string& name) {
    require(ok, "array '" + name + "' must hold finite numbers only");
}

inline idx count(const Span1<double>& v) { return v.n; }
template <class T> idx count(const Span2<T>& v) { return v.n0 * v.n1; }
template <class T> idx count(const Span3<T>& v) { return v.n0 * v.n1 * v.n2; }
template <class T> idx count(const Span4<T>& v) { return v.n0 * v.n1 * v.n2 * v.n3; }

// a view whose entries must all be finite
template <class S>
S finite_view(S v, const char* name) {
    require_finite(all_finite(v.d, count(v)), name);
    return v;
}

bool is_int(double v, double lo, double hi) {
    return std::isfinite(v) && v == std::floor(v) && v >= lo && v <= hi;
}

// The parameter vector's scalars that decide shapes and loops.
struct Shape {
    idx n, kase, nz, nb, nreg, R;
    bool regen, roll;
};

Shape check_params(Vec p) {
    finite_view(p, "p");
    double nm = p[L::N_MODES];
    require(is_int(nm, 1, L::NMAX),
            "p[N_MODES] = " + std::to_string(nm) + " must be an integer in [1, " +
                std::to_string(L::NMAX) + "]");
    require(is_int(p[L::CASE], 0, 3), "p[CASE] must be SOLID, BALL, TMD or LOCKED (0-3)");
    require(is_int(p[L::FORCING], 0, 1), "p[FORCING] must be HARMONIC or REGENERATIVE (0, 1)");
    Shape s;
    s.n = idx(nm);
    s.kase = idx(p[L::CASE]);
    s.regen = int(p[L::FORCING]) == L::REGENERATIVE;
    s.nz = s.kase == L::TMD ? 2 * s.n + 2 : 2 * s.n;
    s.nb = s.nz + 3;
    s.roll = s.kase == L::BALL && p[L::ROLL] > 0.0;
    s.nreg = s.kase == L::BALL ? (s.roll ? 4 : 3) : 1;
    s.R = s.regen ? 2 * s.nreg : s.nreg;
    for (idx i = 0; i < s.n; ++i) {
        require(p[L::M_ + i] > 0.0, "p[M_ + " + std::to_string(i) + "] (a modal mass) must be > 0");
    }
    if (s.kase == L::BALL) {
        require(p[L::HALF_GAP] > 0.0, "p[HALF_GAP] must be > 0 for a ball damper");
        require(p[L::BALL_MASS] >= 0.0, "p[BALL_MASS] must be >= 0");
    }
    require(p[L::STROBE_PERIOD] >= 0.0, "p[STROBE_PERIOD] must be >= 0");
    require(p[L::CONTACT_K] == 0.0, "p[CONTACT_K] must be 0: the exact integrator takes the "
                                    "impact law; a Hertz contact steps with run_rk4");
    if (s.roll) {
        require(p[L::REACTION] == 1.0, "p[REACTION] must be 1 for a rolling ball: its "
                                       "floor's friction reacts on the bar reciprocally");
        require(p[L::BALL_MASS] > 0.0 && p[L::ROLL_STATIC] >= p[L::ROLL_KINETIC] &&
                    p[L::ROLL_KINETIC] >= 0.0,
                "a rolling ball needs p[BALL_MASS] > 0 and p[ROLL_STATIC] >= "
                "p[ROLL_KINETIC] >= 0");
    }
    return s;
}

// A cut's delay: the revolutions and the history step must give a bounded knot store.
void check_cut(Vec p, double t0, double t_end, double dt, double H) {
    require(std::isfinite(dt) && dt > 0.0, "a regenerative cut needs dt > 0 (got " +
                                               std::to_string(dt) + ")");
    require(std::isfinite(H) && H > 0.0, "a regenerative cut needs H > 0 (got " +
                                             std::to_string(H) + ")");
    // the cut's events and propagators assume a force linear in the state (Kr b h)
    require(p[L::CUT_MC] == 0.0 && p[L::NOISE_STD] == 0.0,
            "the exact integrator takes the linear cutting law without noise (p[CUT_MC] = "
            "p[NOISE_STD] = 0); Kienzle's law and force noise: run_rk4");
    double tau = p[L::TAU];
    require(tau > 0.0, "p[TAU] must be > 0 in a regenerative cut");
    require(is_int(p[L::N_REV], 1, MAX_REV), "p[N_REV] must be an integer in [1, 1e6]");
    // at least two nodes a revolution (history_step's H): the surface's knots then always
    // have a successor in the store
    double mrev = std::nearbyint(tau / H);
    require(mrev >= 2.0 && p[L::N_REV] * mrev <= MAX_KNOTS,
            "p[TAU] / H must round to at least 2 nodes a revolution (H = history_step(tau, "
            "dt)), and p[N_REV] times it to at most 1e8 knots");
    // times closer than ttol are one: it must stay far below the delay
    require(std::fabs(t0) + std::fabs(t_end) <= MAX_TIME_PER_TAU * tau,
            "the run's times are too large for the delay p[TAU] (over 1e12 revolutions)");
    require((t_end - t0) / dt <= MAX_STEPS && (t_end - t0) / H <= MAX_STEPS,
            "the run spans more than 1e15 steps of dt or H");
}

void check_strobe(Vec p, double t0, double t_end) {
    double period = p[L::STROBE_PERIOD];
    if (period <= 0.0) return;
    double span = std::fabs(t0) + std::fabs(t_end) + std::fabs(p[L::STROBE_T0]);
    require(span / period <= MAX_STEPS,
            "p[STROBE_PERIOD] is too short for the run's times (more than 1e15 periods)");
}

// met's counters become row indices and counts: whole numbers in [0, 2^53]
void check_met(Vec met) {
    for (int k : {L::N_REC, L::N_STROBE, L::N_IMP_REC, L::N_STICK_REC, L::N_EVENTS}) {
        require(is_int(met[k], 0, MAX_COUNT),
                "met's counters (N_REC, N_STROBE, N_IMP_REC, N_STICK_REC, N_EVENTS) must be "
                "whole numbers in [0, 2^53]");
    }
}

// Integer per-regime arrays: kstep in {1, 2}, levmax in [0, GRID_LEVELS)
void check_steps(Span1<idx> kstep, Span1<idx> levmax) {
    for (idx r = 0; r < kstep.n; ++r) {
        require(kstep[r] == 1 || kstep[r] == 2, "prep.kstep's entries must be 1 or 2");
        require(levmax[r] >= 0 && levmax[r] < GRID_LEVELS,
                "prep.levmax's entries must be in [0, " + std::to_string(GRID_LEVELS - 1) + "]");
    }
}

}  // namespace

// The exact kernel's per-run matrices as prepare(p) sets them (boringbar.core.ExactSetup):
// each regime's eigenvalues lam, eigenvectors V (Vh: for a real state, a conjugate pair's
// first doubled and its second zero), their inverse Vi, the forced response Z and the
// steady response D to a unit F_b, the grid's exponentials eh, the dashpots' rows lvis
// and constants cvis, the inverse sums isum, the modal inputs bq, the derivative bounds
// bnd, the step patterns kstep and grid levels levmax; the regime count nreg and the grid
// step h.
struct ExactSetupPy {
    In<cplx> lam, V, Vh, Vi, Z, eh, isum, bq;
    In<double> D, lvis, cvis, bnd;
    In<std::int64_t> kstep, levmax;
    std::int64_t nreg = -1;
    double h = 0.0;
};

namespace {

// prepare's matrices as the kernel's views, with the shapes this bar and forcing need
void attach_prep(exact::ExactRun& a, const ExactSetupPy& g, const Shape& s, double t0,
                 double t_end) {
    const idx R = s.R, nz = s.nz, nb = s.nb;
    require(g.nreg == s.nreg, "prep.nreg must be " + std::to_string(s.nreg) + " for this bar");
    a.nreg = s.nreg;
    a.h = g.h;
    require(std::isfinite(a.h) && a.h > 0.0, "prep.h must be finite and > 0");
    require((t_end - t0) / a.h <= MAX_GRID, "the run spans more than 1e13 grid steps prep.h");
    a.lam = finite_view(span2<cplx>(given(g.lam, "lam"), "lam", R, nz), "lam");
    a.V = finite_view(span3<cplx>(given(g.Vh, "Vh"), "Vh", R, nz, nz), "Vh");
    a.Vi = finite_view(span3<cplx>(given(g.Vi, "Vi"), "Vi", R, nz, nz), "Vi");
    a.Vfull = finite_view(span3<cplx>(given(g.V, "V"), "V", R, nz, nz), "V");
    a.Z = finite_view(span2<cplx>(given(g.Z, "Z"), "Z", R, nz), "Z");
    a.D = finite_view(span2<double>(given(g.D, "D"), "D", R, nz), "D");
    a.eh = finite_view(span3<cplx>(given(g.eh, "eh"), "eh", R, GRID_LEVELS, nz), "eh");
    idx nd = s.kase == L::TMD ? s.n + 1 : s.n;  // the dashpots
    a.lvis = finite_view(span2<double>(given(g.lvis, "lvis"), "lvis", nd, nz), "lvis");
    a.cvis = finite_view(span1<double>(given(g.cvis, "cvis"), "cvis", nd), "cvis");
    a.isum = finite_view(span3<cplx>(given(g.isum, "isum"), "isum", R, nb, nb), "isum");
    a.bq = finite_view(span2<cplx>(given(g.bq, "bq"), "bq", R, nz), "bq");
    a.bnd = finite_view(span3<double>(given(g.bnd, "bnd"), "bnd", R, 4, nz + 1), "bnd");
    a.kstep = span1<idx>(given(g.kstep, "kstep"), "kstep", R);
    a.levmax = span1<idx>(given(g.levmax, "levmax"), "levmax", R);
    check_steps(a.kstep, a.levmax);
}

void attach_tables(exact::ExactRun& a, const In<cplx>& tabE, const In<cplx>& tabP,
                   const Shape& s) {
    if (s.regen) {
        a.tabE = finite_view(span3<cplx>(given(tabE, "tabE"), "tabE", s.R, 5, s.nz), "tabE");
        a.tabP = finite_view(span4<cplx>(given(tabP, "tabP"), "tabP", s.R, 5, 4, s.nz), "tabP");
    } else if (tabE.is_valid() || tabP.is_valid()) {  // unused: the dummy tables, if given
        a.tabE = span3<cplx>(given(tabE, "tabE"), "tabE", 1, 5, 1);
        a.tabP = span4<cplx>(given(tabP, "tabP"), "tabP", 1, 5, 4, 1);
    }
}

}  // namespace

// One exact run as Python describes it (boringbar.core.ExactRun): the packed parameters p,
// the state x (advanced in place), the span, the history's sampling, the records and
// metrics (written in place), prepare(p)'s setup and a cut's step, history step and tables.
struct ExactRunPy {
    In<double> p;
    Out<double> x;
    double t0 = 0.0, t_end = 0.0, t_steady = 0.0, rec_dt = 0.0;
    Out<double> rec, imp, stick, strobe, met;
    nb::object prep;  // prepare(p)'s ExactSetup, the object itself (its fields read at the run)
    double dt = 0.0, H = 0.0;
    In<cplx> tabE, tabP;  // a cut's tables; not set (or zeros of shape (1, 5, 1),
                          // (1, 5, 4, 1)): a harmonic run
};

namespace {

double run_exact_py(const ExactRunPy& run) {
    const ExactRunPy r = run;  // its arrays, prep's too, held for the run
    exact::ExactRun a;
    a.p = span1<double>(given(r.p, "p"), "p", L::P_SIZE);
    const double t0 = r.t0, t_end = r.t_end, t_steady = r.t_steady, rec_dt = r.rec_dt;
    const double dt = r.dt, H = r.H;
    Shape s = check_params(a.p);
    require(std::isfinite(t0) && std::isfinite(t_end) && std::isfinite(t_steady),
            "t0, t_end and t_steady must be finite");
    require(t_end >= t0, "t_end must be >= t0");
    require(std::isfinite(rec_dt) && rec_dt >= 0.0, "rec_dt must be finite and >= 0");
    require(std::isfinite(dt) && dt >= 0.0, "dt must be finite and >= 0");
    require(std::isfinite(H) && H >= 0.0, "H must be finite and >= 0");
    if (s.regen) check_cut(a.p, t0, t_end, dt, H);
    check_strobe(a.p, t0, t_end);
    a.t0 = t0;
    a.t_end = t_end;
    a.t_steady = t_steady;
    a.rec_dt = rec_dt;
    a.dt_out = dt;
    a.hist_step = H;

    a.x = span1<double>(given(r.x, "x"), "x", 2 * s.n + 2 + (s.roll ? 1 : 0));
    finite_view(a.x, "x");
    a.rec = record_rows(given(r.rec, "rec"), "rec", rec_columns(r.rec, s.roll));
    a.imp = record_rows(given(r.imp, "imp"), "imp", L::IMP_NCOL);
    a.stick = record_rows(given(r.stick, "stick"), "stick", L::STICK_NCOL);
    a.strobe = record_rows(given(r.strobe, "strobe"), "strobe", L::STROBE_NCOL);
    a.met = span1<double>(given(r.met, "met"), "met", L::MET_SIZE);
    check_met(a.met);

    require(r.prep.is_valid(), "'prep' was not set");
    const ExactSetupPy setup = nb::cast<const ExactSetupPy&>(r.prep);  // its arrays held
    attach_prep(a, setup, s, t0, t_end);
    attach_tables(a, r.tabE, r.tabP, s);

    nb::gil_scoped_release release;
    return exact::run_exact(a);
}

}  // namespace

void bind_exact(nb::module_& m) {
    auto setup = nb::class_<ExactSetupPy>(
        m, "ExactSetup",
        "The exact kernel's per-run matrices, as prepare(p) sets them (R regimes, nz state "
        "entries, nb = nz + 3): their shapes are checked against the run's when it starts.");
    setup.def(nb::init<>());
    Fields<ExactSetupPy>{setup}
        .in("lam", &ExactSetupPy::lam, "each regime's eigenvalues, (R, nz) complex")
        .in("V", &ExactSetupPy::V, "their eigenvectors, (R, nz, nz) complex")
        .in("Vh", &ExactSetupPy::Vh, "V for a real state (a conjugate pair's first doubled, its "
             "second zero), (R, nz, nz) complex")
        .in("Vi", &ExactSetupPy::Vi, "the inverse of V, (R, nz, nz) complex")
        .in("Z", &ExactSetupPy::Z, "the forced response to F0 sin(Omega t), (R, nz) complex")
        .in("D", &ExactSetupPy::D, "the steady response to a unit F_b, (R, nz)")
        .in("eh", &ExactSetupPy::eh, "exp(lambda 2^l h) of the grid's levels, (R, GRID_LEVELS, nz)")
        .in("lvis", &ExactSetupPy::lvis, "the dashpots' rows, (n or n + 1, nz)")
        .in("cvis", &ExactSetupPy::cvis, "the dashpots' constants, (n or n + 1,)")
        .in("isum", &ExactSetupPy::isum, "the flows' inverse sums, (R, nb, nb) complex")
        .in("bq", &ExactSetupPy::bq, "the modal inputs, (R, nz) complex")
        .in("bnd", &ExactSetupPy::bnd, "the derivative bounds, (R, 4, nz + 1)")
        .in("kstep", &ExactSetupPy::kstep, "each regime's step pattern, 1 or 2, (R,) int64")
        .in("levmax", &ExactSetupPy::levmax, "each regime's top grid level, (R,) int64")
        .integer("nreg", &ExactSetupPy::nreg, "the regimes outside a cut (1, 3 or 4)")
        .real("h", &ExactSetupPy::h, "the event-search grid step (s)");

    auto run = nb::class_<ExactRunPy>(m, "ExactRun",
                                      "One exact run for run_exact: set its fields, then call "
                                      "run_exact (tabE, tabP only for a cut).");
    run.def(nb::init<>());
    Fields<ExactRunPy>{run}
        .in("p", &ExactRunPy::p, "the packed parameter vector (P_SIZE float64)")
        .out("x", &ExactRunPy::x, "the state (2 n + 2 float64, a rolling ball's 2 n + 3), advanced in place")
        .real("t0", &ExactRunPy::t0, "the start time (s)")
        .real("t_end", &ExactRunPy::t_end, "the end time (s), >= t0")
        .real("t_steady", &ExactRunPy::t_steady, "the steady window's start (s)")
        .real("rec_dt", &ExactRunPy::rec_dt, "the history's sampling step (s); 0: none")
        .records()
        .real("dt", &ExactRunPy::dt, "a cut's step (s): the unit of N_ZERO_STEPS")
        .real("H", &ExactRunPy::H, "a cut's history step (s); 0 for harmonic forcing")
        .in("tabE", &ExactRunPy::tabE, "a cut's tables exp(lambda tau_p), (R, 5, nz) complex")
        .in("tabP", &ExactRunPy::tabP, "a cut's input tables, (R, 5, 4, nz) complex");
    run.def_prop_rw(
        "prep", [](const ExactRunPy& r) { return r.prep.is_valid() ? r.prep : nb::none(); },
        [](ExactRunPy& r, nb::handle h) {
            require(nb::isinstance<ExactSetupPy>(h), "'prep' must be an ExactSetup (prepare(p)'s)");
            r.prep = nb::borrow(h);
        },
        nb::arg("value").none(), "prepare(p)'s ExactSetup: the regimes' matrices");
    m.def("run_exact", &run_exact_py, nb::arg("run"),
          "Advance run.x exactly from run.t0 to run.t_end (the exact event-driven integrator), "
          "writing the records and metrics in place; returns the time reached.  The GIL is "
          "released while it runs.");
    // the event-search grid that prepare() sizes its tables for (simulate/regimes.py)
    m.attr("GRID_PER_PERIOD") = exact::GRID_PER_PERIOD;
    m.attr("GRID_LEVELS") = exact::GRID_LEVELS;
}

}  // namespace bb::bind
