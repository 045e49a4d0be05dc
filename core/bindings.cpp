// The compiled core's Python module, boringbar.core: the packed layout's names and
// the integrators' entry points and the equations of motion as matrices.  Each part's
// bindings live beside it (bind_rk4.cpp, bind_exact.cpp, dynamics.cpp); this file only
// assembles the module.
#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/map.h>
#include <nanobind/stl/vector.h>

#include <map>
#include <string>
#include <vector>

#include "layout.hpp"

namespace nb = nanobind;

namespace bb::bind {
void bind_rk4(nb::module_& m);
void bind_exact(nb::module_& m);
void bind_dynamics(nb::module_& m);
void bind_history_map(nb::module_& m);
void bind_forcing_setup(nb::module_& m);
void bind_contact_law(nb::module_& m);
void bind_impact_pattern(nb::module_& m);
}  // namespace bb::bind

namespace {

std::map<std::string, int> layout_names() {
    using namespace bb::layout;
    std::map<std::string, int> out;
#define BB_NAME(name) out[#name] = name;
    BB_P_SCALARS(BB_NAME)
    BB_METRICS(BB_NAME)
#undef BB_NAME
    out["NMAX"] = NMAX;
    out["SOLID"] = SOLID;
    out["BALL"] = BALL;
    out["TMD"] = TMD;
    out["LOCKED"] = LOCKED;
    out["HARMONIC"] = HARMONIC;
    out["REGENERATIVE"] = REGENERATIVE;
    out["M_"] = M_;
    out["K_"] = K_;
    out["C_"] = C_;
    out["PSI_L"] = PSI_L;
    out["PSI_D"] = PSI_D;
    out["PSI_A"] = PSI_A;
    out["PSI_F"] = PSI_F;
    out["P_SIZE"] = P_SIZE;
    out["MET_SIZE"] = MET_SIZE;
    out["CONTACT_NCOL"] = CONTACT_NCOL;
    return out;
}

// The scalar slots of p, in order (the per-mode blocks M_ .. PSI_A follow them).
std::vector<std::string> param_names() {
    std::vector<std::string> out;
#define BB_NAME(name) out.push_back(#name);
    BB_P_SCALARS(BB_NAME)
#undef BB_NAME
    return out;
}

// The slots of met, in order.
std::vector<std::string> metric_names() {
    std::vector<std::string> out;
#define BB_NAME(name) out.push_back(#name);
    BB_METRICS(BB_NAME)
#undef BB_NAME
    return out;
}

}  // namespace

NB_MODULE(core, m) {
    m.doc() = "boringbar's compiled core: the RK4 and exact event-driven integrators.";
    m.def("layout", &layout_names,
          "The packed parameter vector's and the metric vector's slots, by name.");
    m.def("param_names", &param_names,
          "The scalar slots of the packed parameter vector, in order; the per-mode blocks "
          "M_, K_, C_, PSI_L, PSI_D, PSI_A, PSI_F of NMAX entries each follow them.");
    m.def("metric_names", &metric_names, "The metric vector's slots, in order.");
    bb::bind::bind_rk4(m);
    bb::bind::bind_exact(m);
    bb::bind::bind_dynamics(m);
    bb::bind::bind_history_map(m);
    bb::bind::bind_forcing_setup(m);
    bb::bind::bind_contact_law(m);
    bb::bind::bind_impact_pattern(m);
}
