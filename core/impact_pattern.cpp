// boringbar.core.impact_period and impact_fault: the period of a run's impact sequence
// and whether it is symmetric, the part of the impact-pattern classifier
// (src/boringbar/simulate/patterns.py, docs/model.md, section 6) that loops over the
// impacts.  It runs once for every run whose pattern is read, thousands of times in a
// sweep; in NumPy it cost 0.1-0.3 ms a run.
//
// The impacts of the tail (t >= tail_start) repeat with span kT when impact j + n is on
// impact j's wall, kT later within tol, for every j, n being the impacts before
// t_0 + kT - tol; the smallest k <= max_k whose span fits min_periods times into the tail
// is taken.  The sequence is symmetric when, folded modulo kT, the + wall's phases shifted
// by an odd multiple s of T/2 are the - wall's and the - wall's shifted by s are the
// + wall's, each matched within tol.  Every comparison fails on a NaN, as NumPy's do.
// impact_fault is the classifier's check of its input, in the same loop's terms.
#include <nanobind/nanobind.h>
#include <nanobind/stl/tuple.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <tuple>
#include <vector>

#include "bind_util.hpp"

namespace bb::bind {
namespace {

struct Impacts {
    const double* t;
    const double* wall;
    std::int64_t n;
};

// NumPy's float modulo (the result takes the divisor's sign; 0 is +0 for span > 0).
double mod(double a, double span) {
    double m = std::fmod(a, span);
    if (m != 0.0) {
        if ((span < 0.0) != (m < 0.0)) m += span;
    } else {
        m = std::copysign(0.0, span);
    }
    return m;
}

// m = min(m, g), a NaN kept once seen (as np.minimum and ndarray.min spread it).
void take_least(double& m, double g) {
    if (!std::isnan(m) && (std::isnan(g) || g < m)) m = g;
}

// Impacts per span if the sequence repeats with that span over the tail, else 0.
std::int64_t period_count(const Impacts& s, double span, double tail0, double tail1,
                          double tol) {
    if (s.n < 2) return 0;
    const double first = s.t[0] + span - tol;
    std::int64_t n = 0;  // searchsorted, side left: the impacts before first
    while (n < s.n && s.t[n] < first) ++n;
    if (n == 0 || n >= s.n) return 0;
    if (!(s.t[0] <= tail0 + span + tol && s.t[s.n - 1] >= tail1 - span - tol)) return 0;
    for (std::int64_t j = 0; j + n < s.n; ++j) {
        if (s.wall[j + n] != s.wall[j]) return 0;
        if (!(std::fabs(s.t[j + n] - s.t[j] - span) <= tol)) return 0;
    }
    return n;
}

// Every phase of a (shifted by s) has one of b within tol, circularly modulo span, and
// vice versa.
bool same_phases(const std::vector<double>& a, double s, const std::vector<double>& b,
                 double span, double tol) {
    const size_t na = a.size(), nb_ = b.size();
    std::vector<double> by_a(na, INFINITY), by_b(nb_, INFINITY);
    for (size_t i = 0; i < na; ++i) {
        const double pa = mod(a[i] + s, span);
        for (size_t j = 0; j < nb_; ++j) {
            const double g = std::fabs(pa - b[j]), h = span - g;
            const double gap = (std::isnan(g) || std::isnan(h)) ? NAN : (h < g ? h : g);
            take_least(by_a[i], gap);
            take_least(by_b[j], gap);
        }
    }
    auto all_within = [tol](const std::vector<double>& v) {
        for (double g : v)
            if (!(g <= tol)) return false;
        return true;
    };
    return all_within(by_b) && all_within(by_a);
}

// The + and - walls' phases modulo span of the first n impacts.
bool symmetric(const Impacts& s, std::int64_t n, double period, int k, double tol) {
    const double span = k * period;
    std::vector<double> plus, minus;
    for (std::int64_t j = 0; j < n; ++j) {
        if (s.wall[j] == 1.0) plus.push_back(mod(s.t[j], span));
        if (s.wall[j] == -1.0) minus.push_back(mod(s.t[j], span));
    }
    if (plus.size() != minus.size()) return false;
    for (int j = 0; j < k; ++j) {
        const double shift = double(2 * j + 1) * period / 2.0;
        if (same_phases(plus, shift, minus, span, tol) &&
            same_phases(minus, shift, plus, span, tol))
            return true;
    }
    return false;
}

std::tuple<std::int64_t, int, bool> impact_period(AnyArray times, AnyArray walls, double tail_start,
                                                  double tail_end, double period, double tol,
                                                  int max_k, int min_periods) {
    const Span1<double> t = span1<double>(times, "times");
    const Span1<double> w = span1<double>(walls, "walls", t.n);
    require(std::isfinite(period) && period > 0.0,
            "period = " + std::to_string(period) + " must be finite and > 0");
    require(max_k >= 1, "max_k = " + std::to_string(max_k) + " must be >= 1");
    require(min_periods >= 2, "min_periods = " + std::to_string(min_periods) + " must be >= 2");
    std::vector<double> tt, ww;  // the tail's impacts, in order (a NaN time is not in it)
    for (std::int64_t j = 0; j < t.n; ++j) {
        if (t[j] >= tail_start) {
            tt.push_back(t[j]);
            ww.push_back(w[j]);
        }
    }
    const Impacts s{tt.data(), ww.data(), std::int64_t(tt.size())};
    for (int k = 1; k <= max_k; ++k) {
        if (tail_end - tail_start < double(min_periods) * k * period) break;
        const std::int64_t n = period_count(s, k * period, tail_start, tail_end, tol);
        if (n) return {n, k, symmetric(s, n, period, k, tol)};
    }
    return {0, 0, false};
}

// 0 if the impacts can be classified; 1 if a wall is neither +1 nor -1; 2 if the times
// are not ascending inside [t_start, t_end] (a NaN time passes, as NumPy's comparisons
// let it: its impacts then fail every match).
int impact_fault(AnyArray times, AnyArray walls, double t_start, double t_end) {
    const Span1<double> t = span1<double>(times, "times");
    const Span1<double> w = span1<double>(walls, "walls", t.n);
    for (std::int64_t j = 0; j < w.n; ++j)
        if (!(w[j] == 1.0 || w[j] == -1.0)) return 1;
    if (t.n == 0) return 0;
    for (std::int64_t j = 0; j + 1 < t.n; ++j)
        if (t[j + 1] - t[j] < 0.0) return 2;
    return (t[0] < t_start || t[t.n - 1] > t_end) ? 2 : 0;
}

}  // namespace

void bind_impact_pattern(nb::module_& m) {
    m.def("impact_period", &impact_period, nb::arg("times"), nb::arg("walls"),
          nb::arg("tail_start"), nb::arg("tail_end"), nb::arg("period"), nb::arg("tol"),
          nb::arg("max_k"), nb::arg("min_periods"),
          "(n, k, symmetric) of the impacts at times >= tail_start (ascending float64 "
          "times and walls of +1 or -1): the smallest period k T, k <= max_k, that repeats "
          "min_periods times in the tail (tail_start, tail_end), with its n impacts, and "
          "whether the motion is antisymmetric; (0, 0, False) if none.");
    m.def("impact_fault", &impact_fault, nb::arg("times"), nb::arg("walls"),
          nb::arg("t_start"), nb::arg("t_end"),
          "0 if the impacts (float64 times and walls) can be classified; 1 if a wall is "
          "neither +1 nor -1; 2 if the times are not ascending inside [t_start, t_end].");
}

}  // namespace bb::bind
