// boringbar.core.cut_history_map: the linearised map of a periodic cut orbit on its delay
// history, applied over whole periods, for the orbit's Floquet multipliers
// (src/boringbar/orbits/cut_orbits.py, multipliers).
//
// The orbit is m RK4 steps a period.  Linearised about it, step i takes a perturbation
// of node i's state x_i (s values) to
//
//   x_{i+1} = D_i x_i + sum_t col_{i,t} (w0 W_j + w1 W'_j + w2 W_{j+1} + w3 W'_{j+1}),
//
// one term t for each stage and revolution whose delayed W moves the step: W_j = c . x_j
// and W'_j = cv . x_j at node j = base_{i,t} (counted from the period's first node, so
// negative in the history), interpolated with the Hermite weights w_{i,t}.  A delay
// reads only W and W' of its nodes, so the map's state is node 0's x and the (W, W')
// pairs of the `depth` nodes before it; the map's nonzero spectrum is that of the full
// history's.  Every delay reaches back at least one step (j + 1 <= i), so each period
// is a forward recursion over its nodes: O(m (s^2 + K s)) operations, with no matrix
// formed and no solve.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cstdint>
#include <string>
#include <vector>

#include "bind_util.hpp"

namespace bb::bind {
namespace {

template <class T, int D>
using Ro = nb::ndarray<const T, nb::ndim<D>, nb::c_contig, nb::device::cpu>;
using Vector = nb::ndarray<nb::numpy, double, nb::ndim<1>>;

// The linearised orbit: m steps of s values, K delayed terms a step, depth history nodes.
struct Orbit {
    idx m, s, k, depth;
    const double *d, *cols, *wts, *c, *cv;
    const std::int64_t* base;
};

Orbit checked(const Ro<double, 3>& d, const Ro<double, 3>& cols, const Ro<std::int64_t, 2>& base,
              const Ro<double, 3>& wts, const Ro<double, 1>& c, const Ro<double, 1>& cv,
              idx size) {
    const idx m = idx(d.shape(0)), s = idx(d.shape(1)), k = idx(cols.shape(1));
    require(m >= 1 && s >= 1 && idx(d.shape(2)) == s, "d must have shape (m, s, s), m, s >= 1");
    require(idx(cols.shape(0)) == m && idx(cols.shape(2)) == s, "cols must have shape (m, K, s)");
    require(idx(base.shape(0)) == m && idx(base.shape(1)) == k, "base must have shape (m, K)");
    require(idx(wts.shape(0)) == m && idx(wts.shape(1)) == k && wts.shape(2) == 4,
            "weights must have shape (m, K, 4)");
    require(idx(c.shape(0)) == s && idx(cv.shape(0)) == s, "c and cv must have s entries");
    require(size >= s && (size - s) % 2 == 0,
            "v must hold the history's (W, W') pairs and node 0's s values");
    const idx depth = (size - s) / 2;
    const std::int64_t* b = base.data();
    for (idx i = 0; i < m; ++i) {
        for (idx t = 0; t < k; ++t) {
            const std::int64_t j = b[i * k + t];
            if (j < -depth || j + 1 > i)  // (the message is built only when it is needed)
                require(false, "base[" + std::to_string(i) + ", " + std::to_string(t) +
                                   "] = " + std::to_string(j) +
                                   " is outside [-depth, i - 1] (depth " +
                                   std::to_string(depth) + ")");
        }
    }
    return {m, s, k, depth, d.data(), cols.data(), wts.data(), c.data(), cv.data(), b};
}

// v after `periods` periods of the map (v: the history's pairs, oldest first, then x_0),
// into out.
void apply(const Orbit& o, const double* v, idx periods, std::vector<double>& out) {
    const idx m = o.m, s = o.s, k = o.k, depth = o.depth;
    // (W, W') of nodes -depth .. periods m, at index 2 (node + depth)
    std::vector<double> pairs(size_t(2 * (depth + periods * m + 1)));
    for (idx j = 0; j < 2 * depth; ++j) pairs[size_t(j)] = v[j];
    std::vector<double> x(v + 2 * depth, v + 2 * depth + s);
    std::vector<double> next(x.size(), 0.0);
    auto store = [&](idx node) {
        double w = 0.0, wd = 0.0;
        for (idx a = 0; a < s; ++a) {
            w += o.c[a] * x[size_t(a)];
            wd += o.cv[a] * x[size_t(a)];
        }
        pairs[size_t(2 * (node + depth))] = w;
        pairs[size_t(2 * (node + depth) + 1)] = wd;
    };
    store(0);
    for (idx p = 0; p < periods; ++p) {
        for (idx i = 0; i < m; ++i) {
            const double* di = o.d + i * s * s;
            for (idx r = 0; r < s; ++r) {
                double acc = 0.0;
                for (idx a = 0; a < s; ++a) acc += di[r * s + a] * x[size_t(a)];
                next[size_t(r)] = acc;
            }
            for (idx t = 0; t < k; ++t) {
                const double* w = o.wts + (i * k + t) * 4;
                const double* pj = pairs.data() + 2 * (p * m + o.base[i * k + t] + depth);
                const double dw = w[0] * pj[0] + w[1] * pj[1] + w[2] * pj[2] + w[3] * pj[3];
                const double* col = o.cols + (i * k + t) * s;
                for (idx r = 0; r < s; ++r) next[size_t(r)] += col[r] * dw;
            }
            x.swap(next);
            store(p * m + i + 1);
        }
    }
    const double* last = pairs.data() + 2 * (periods * m);  // node periods m - depth
    for (idx j = 0; j < 2 * depth; ++j) out[size_t(j)] = last[j];
    for (idx a = 0; a < s; ++a) out[size_t(2 * depth + a)] = x[size_t(a)];
}

Vector cut_history_map(const Ro<double, 3>& d, const Ro<double, 3>& cols,
                       const Ro<std::int64_t, 2>& base, const Ro<double, 3>& wts,
                       const Ro<double, 1>& c, const Ro<double, 1>& cv, const Ro<double, 1>& v,
                       std::int64_t periods) {
    require(periods >= 1 && periods <= 1000000, "periods must be in [1, 1000000]");
    const Orbit o = checked(d, cols, base, wts, c, cv, idx(v.shape(0)));
    std::vector<double> result(v.shape(0));
    {
        nb::gil_scoped_release unlocked;
        apply(o, v.data(), idx(periods), result);
    }
    const size_t n = result.size();
    return owned_array<double, 1>(std::move(result), {n});
}

}  // namespace

void bind_history_map(nb::module_& m) {
    m.def("cut_history_map", &cut_history_map, nb::arg("d"), nb::arg("cols"), nb::arg("base"),
          nb::arg("weights"), nb::arg("c"), nb::arg("cv"), nb::arg("v"), nb::arg("periods"),
          "A periodic cut orbit's linearised map on its delay history, applied over "
          "`periods` periods: v = [(W, W') of the depth nodes before node 0, oldest first; "
          "node 0's s values].  d (m, s, s): each step's derivative in its node; cols "
          "(m, K, s): in each delayed W it reads, at the nodes base (m, K) and base + 1 of "
          "the period (negative: history), with the Hermite weights (m, K, 4) on "
          "(W_j, W'_j, W_j+1, W'_j+1); W = c . x, W' = cv . x.");
}

}  // namespace bb::bind
