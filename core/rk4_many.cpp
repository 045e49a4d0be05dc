// The baseline ISA's three- and four-mode kernels and its kernel of a run-time shape
// (rk4_run.hpp), where no AVX2 copy is built (rk4.hpp).
#include "rk4_run.hpp"

#ifndef BB_AVX2_CLONE
namespace bb::rk4 {

void run_many_base(const RunArgs& a, ShapeKey k) { run_many<Baseline>(a, k); }

}  // namespace bb::rk4
#endif
