// The three- and four-mode RK4 kernels (rk4_run.hpp) compiled for AVX2; run_single
// (rk4.cpp) calls them where the CPU has it (rk4.hpp).
// Empty where the copy is not built.
#include "rk4_run.hpp"

#ifdef BB_AVX2_CLONE
namespace bb::rk4 {

void run_many_avx2(const RunArgs& a, ShapeKey k) { run_many<Avx2>(a, k); }

}  // namespace bb::rk4
#endif
