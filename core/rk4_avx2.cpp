// The RK4 kernels (rk4_run.hpp) compiled for AVX2; rk4.cpp's run_single calls them
// where the CPU has it (rk4.hpp).  Empty where the copy is not built.
#include "rk4_run.hpp"

#ifdef BB_AVX2_CLONE
namespace bb::rk4 {
namespace {

struct Avx2 {
    template <int N, int CASE, int FORCING>
    BB_TARGET_AVX2 static void run(const RunArgs& a) {
        run_body<N, CASE, FORCING>(a);
    }
};

}  // namespace

void run_single_avx2(const RunArgs& a) { run_shape<Avx2>(a); }

}  // namespace bb::rk4
#endif
