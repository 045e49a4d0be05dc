// boringbar.core.hunt_crossley_restitution and hunt_crossley_alpha: Hunt and Crossley's
// damping for a restitution (docs/model.md, section 2.6).
//
// A compliant contact's force is K d^1.5 (1 + chi d') (dynamics.hpp's contact_force).
// Scaled by its speed v_in and its own time, a free impact is
// X'' = -X^1.5 max(0, 1 + alpha X'), X(0) = 0, X'(0) = 1, with alpha = chi v_in, and the
// restitution e = -X' where X returns to 0 depends on alpha alone.  Here it is
// integrated by classical RK4 at a step of 1e-4 (some 35,000 steps; error ~1e-14) and
// inverted by the Illinois variant of regula falsi, so the run sets chi = alpha / v_in
// per contact for the e the ball is given.
#include <nanobind/nanobind.h>

#include <cmath>
#include <string>

#include "bind_util.hpp"

namespace bb::bind {
namespace {

constexpr double STEP = 1e-4;
constexpr long MAX_STEPS = 100'000'000;  // alpha <= 1e6 returns within ~1e6 steps

double acceleration(double x, double v, double alpha) {
    if (!(x > 0.0)) return 0.0;
    const double push = 1.0 + alpha * v;
    return push > 0.0 ? -x * std::sqrt(x) * push : 0.0;
}

// e of a free impact with damping alpha; 0 if the ball never leaves the wall.
double restitution(double alpha) {
    double x = 0.0, v = 1.0;
    const double h = STEP;
    for (long k = 0; k < MAX_STEPS; ++k) {
        const double a1 = acceleration(x, v, alpha);
        const double x2 = x + 0.5 * h * v, v2 = v + 0.5 * h * a1;
        const double a2 = acceleration(x2, v2, alpha);
        const double x3 = x + 0.5 * h * v2, v3 = v + 0.5 * h * a2;
        const double a3 = acceleration(x3, v3, alpha);
        const double x4 = x + h * v3, v4 = v + h * a3;
        const double a4 = acceleration(x4, v4, alpha);
        const double xn = x + h / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4);
        const double vn = v + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
        if (xn <= 0.0 && vn < 0.0) {
            // back through X = 0 inside the step, where the force is nearly zero (it goes
            // as X^1.5): v at the crossing, linearly in the step
            const double s = x / (x - xn);
            return -(v + s * (vn - v));
        }
        x = xn;
        v = vn;
    }
    return 0.0;
}

double hunt_crossley_restitution(double alpha) {
    require(std::isfinite(alpha) && alpha >= 0.0 && alpha <= 1e6,
            "alpha = " + std::to_string(alpha) + " must be in [0, 1e6]");
    return restitution(alpha);
}

// alpha with restitution(alpha) = e, by the Illinois method on a bracket [0, hi].
double hunt_crossley_alpha(double e) {
    require(std::isfinite(e) && e >= 0.01 && e <= 1.0,
            "restitution = " + std::to_string(e) + " must be in [0.01, 1]");
    if (e == 1.0) return 0.0;
    double lo = 0.0, flo = 1.0 - e, hi = 1.0, fhi = restitution(hi) - e;
    while (fhi > 0.0) {
        lo = hi;
        flo = fhi;
        hi *= 2.0;
        fhi = restitution(hi) - e;
    }
    int side = 0;
    for (int it = 0; it < 200 && hi - lo > 1e-14 * hi; ++it) {
        const double mid = (lo * fhi - hi * flo) / (fhi - flo);
        const double fm = restitution(mid) - e;
        if (fm == 0.0) return mid;
        if ((fm > 0.0) == (flo > 0.0)) {
            lo = mid;
            flo = fm;
            if (side == -1) fhi *= 0.5;
            side = -1;
        } else {
            hi = mid;
            fhi = fm;
            if (side == 1) flo *= 0.5;
            side = 1;
        }
    }
    return 0.5 * (lo + hi);
}

}  // namespace

void bind_contact_law(nb::module_& m) {
    m.def("hunt_crossley_restitution", &hunt_crossley_restitution, nb::arg("alpha"),
          "The restitution of a free Hunt-Crossley impact with alpha = chi v_in in [0, 1e6].");
    m.def("hunt_crossley_alpha", &hunt_crossley_alpha, nb::arg("restitution"),
          "alpha = chi v_in whose free Hunt-Crossley impact restores the restitution e in "
          "[0.01, 1] (0 for e = 1).");
}

}  // namespace bb::bind
