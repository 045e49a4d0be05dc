// One run of the published RK4 scheme (rk4.hpp): harmonic forcing or a regenerative cut.
// This file holds the kernels for the baseline ISA and run_single, which picks the copy
// the CPU can run: rk4_avx2.cpp's or these (rk4_run.hpp).
#include "rk4_run.hpp"

namespace bb::rk4 {
namespace {

struct Baseline {
    template <int N, int CASE, int FORCING>
    static void run(const RunArgs& a) {
        run_body<N, CASE, FORCING>(a);
    }
};

}  // namespace

void run_single(const RunArgs& a) {
#ifdef BB_AVX2_CLONE
    if (cpu_has_avx2()) return run_single_avx2(a);
#endif
    run_shape<Baseline>(a);
}

}  // namespace bb::rk4
