// boringbar.core.run_rk4 and run_rk4_batch: the RK4 kernels' boundary.
//
// Every argument is checked here, before the integration starts: each array's dtype
// (float64), shape, C-contiguity and (for outputs) writability, and each scalar's range,
// including the slots of p and met the kernel uses to index or to choose its path.
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

// An input array (read-only allowed).
In input(nb::handle h, const char* name) {
    In a;
    if (!nb::try_cast(h, a, false))
        throw nb::value_error(("core: '" + std::string(name) + "' must be a NumPy array").c_str());
    return a;
}

// An output array: the kernel writes into it, so it must be writable.
Out output(nb::handle h, const char* name) {
    Out a;
    if (!nb::try_cast(h, a, false)) {
        In ro;
        const bool is_array = nb::try_cast(h, ro, false);
        throw nb::value_error(("core: '" + std::string(name) + "' must be a " +
                               (is_array ? "writable" : "NumPy") + " array")
                                  .c_str());
    }
    return a;
}

double real(nb::handle h, const char* name) {
    double v;
    if (!nb::try_cast(h, v, true))
        throw nb::value_error(("core: '" + std::string(name) + "' must be a number").c_str());
    return v;
}

std::int64_t integer(nb::handle h, const char* name) {
    std::int64_t v;
    if (!nb::isinstance<nb::float_>(h) && nb::try_cast(h, v, true)) return v;
    // an integral float: a count computed in floating point (2e4, n / 2.0) is accepted
    double d;
    if (nb::isinstance<nb::float_>(h) && nb::try_cast(h, d, false) && std::isfinite(d) &&
        d == std::floor(d) && std::fabs(d) < 9.0e18)
        return std::int64_t(d);
    throw nb::value_error(("core: '" + std::string(name) + "' must be an integer").c_str());
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

void run_rk4(nb::handle p_, nb::handle x_, nb::handle t0_, nb::handle dt_,
             nb::handle n_steps_, nb::handle steady_start_, nb::handle rec_every_,
             nb::handle rec_, nb::handle imp_, nb::handle stick_, nb::handle strobe_,
             nb::handle met_, nb::handle buf_, nb::handle modes_) {
    In p_arr = input(p_, "p");
    Out x_arr = output(x_, "x"), rec_arr = output(rec_, "rec"), imp_arr = output(imp_, "imp");
    Out stick_arr = output(stick_, "stick"), strobe_arr = output(strobe_, "strobe");
    Out met_arr = output(met_, "met"), buf_arr = output(buf_, "buf");

    R::RunArgs a;
    const Span1<double> p = span1<double>(p_arr, "p", L::P_SIZE);
    a.p = p.d;
    const Kind k = kind_of(a.p, "p");
    a.x = span1<double>(x_arr, "x", 2 * k.n + 2);
    a.t0 = real(t0_, "t0");
    a.dt = real(dt_, "dt");
    a.n_steps = integer(n_steps_, "n_steps");
    a.steady_start = integer(steady_start_, "steady_start");
    a.rec_every = integer(rec_every_, "rec_every");
    check_time(a.t0, a.dt, a.n_steps, a.steady_start);
    require(a.rec_every >= 0, "rec_every = " + std::to_string(a.rec_every) + " must be >= 0");
    a.rec = span2<double>(rec_arr, "rec", -1, L::REC_NCOL);
    a.imp = span2<double>(imp_arr, "imp", -1, L::IMP_NCOL);
    a.stick = span2<double>(stick_arr, "stick", -1, L::STICK_NCOL);
    a.strobe = span2<double>(strobe_arr, "strobe", -1, L::STROBE_NCOL);
    a.met = span1<double>(met_arr, "met", L::MET_SIZE);
    a.buf = span2<double>(buf_arr, "buf", -1, 2);
    Out modes_arr;  // held for the run, like the other arrays
    if (!modes_.is_none()) {
        modes_arr = output(modes_, "modes");
        a.modes = span2<double>(modes_arr, "modes", k.n, 2);
    }
    check_counts(a.met.d, "met");
    if (k.forcing == L::REGENERATIVE) check_cut(a.p, a.dt, a.buf.n0);

    nb::gil_scoped_release unlocked;
    R::run_single(a);
}

void run_rk4_batch(nb::handle P_, nb::handle x_, nb::handle t0_, nb::handle dt_,
                   nb::handle n_steps_, nb::handle steady_start_, nb::handle imp_,
                   nb::handle stick_, nb::handle strobe_, nb::handle met_) {
    In P_arr = input(P_, "P");
    Out x_arr = output(x_, "x"), imp_arr = output(imp_, "imp");
    Out stick_arr = output(stick_, "stick"), strobe_arr = output(strobe_, "strobe");
    Out met_arr = output(met_, "met");

    R::BatchArgs a;
    const Span2<double> P = span2<double>(P_arr, "P", -1, L::P_SIZE);
    a.P = {P.d, P.n0, P.n1};
    const std::int64_t n_runs = P.n0;
    require(n_runs >= 1 && n_runs <= R::BMAX, "a batch of " + std::to_string(n_runs) +
                                                  " runs: P must have 1.." +
                                                  std::to_string(R::BMAX) + " rows");
    const Kind k = kind_of(a.P.row(0), "P[0]");
    for (std::int64_t r = 0; r < n_runs; ++r) {
        const std::string row = "P[" + std::to_string(r) + "]";
        const Kind kr = kind_of(a.P.row(r), row);
        require(kr.n == k.n && kr.kase == k.kase,
                "the runs of a batch must share the mode count and the case (" + row +
                    " differs from P[0])");
        require(kr.forcing == L::HARMONIC,
                row + ": batches take harmonic forcing only (cuts: run_rk4)");
    }
    a.x = span2<double>(x_arr, "x", n_runs, 2 * k.n + 2);
    a.t0 = real(t0_, "t0");
    a.dt = real(dt_, "dt");
    a.n_steps = integer(n_steps_, "n_steps");
    a.steady_start = integer(steady_start_, "steady_start");
    check_time(a.t0, a.dt, a.n_steps, a.steady_start);
    a.imp = span3<double>(imp_arr, "imp", n_runs, -1, L::IMP_NCOL);
    a.stick = span3<double>(stick_arr, "stick", n_runs, -1, L::STICK_NCOL);
    a.strobe = span3<double>(strobe_arr, "strobe", n_runs, -1, L::STROBE_NCOL);
    a.met = span2<double>(met_arr, "met", n_runs, L::MET_SIZE);
    for (std::int64_t r = 0; r < n_runs; ++r)
        check_counts(a.met.row(r), "met[" + std::to_string(r) + "]");

    nb::gil_scoped_release unlocked;
    R::run_batch(a);
}

}  // namespace

void bind_rk4(nb::module_& m) {
    m.attr("BMAX") = R::BMAX;
    m.attr("NREV_MAX") = R::NREV_MAX;
    m.def("run_rk4", &run_rk4, nb::arg("p"), nb::arg("x"), nb::arg("t0"), nb::arg("dt"),
          nb::arg("n_steps"), nb::arg("steady_start"), nb::arg("rec_every"), nb::arg("rec"),
          nb::arg("imp"), nb::arg("stick"), nb::arg("strobe"), nb::arg("met"), nb::arg("buf"),
          nb::arg("modes").none() = nb::none(),
          "Advance x (updated in place) by n_steps RK4 steps of the published scheme from t0 "
          "(docs/model.md, section 5): the records rec (t, W, W', aux, aux', f every "
          "rec_every steps), imp, stick, strobe and the metrics met as boringbar.simulate.kernels "
          "describes; buf the regenerative delay history ((0, 2) when unused); modes (a "
          "cut's, optional: (n_modes, 2)) each mode's max and min over the steady steps, "
          "updated in place.");
    m.def("run_rk4_batch", &run_rk4_batch, nb::arg("P"), nb::arg("x"), nb::arg("t0"),
          nb::arg("dt"), nb::arg("n_steps"), nb::arg("steady_start"), nb::arg("imp"),
          nb::arg("stick"), nb::arg("strobe"), nb::arg("met"),
          "Advance a batch of harmonic runs (rows of P, x, met; imp, stick, strobe per run) "
          "in lock-step; each run's results are run_rk4's bit for bit.");
}

}  // namespace bb::bind
