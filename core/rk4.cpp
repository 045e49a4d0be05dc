// One run of the published RK4 scheme (rk4.hpp): harmonic forcing or a regenerative cut.
// This file holds run_single, which picks the kernel a run takes (its shape, and the copy
// the CPU can run: rk4.hpp), and the baseline ISA's one- and two-mode kernels, or where an
// AVX2 copy is built the baseline's kernel of a run-time shape alone (rk4_run.hpp).
#include "rk4_run.hpp"

namespace bb::rk4 {

ShapeKey shape_key(const RunArgs& a) {
    const int n = int(a.p[L::N_MODES]);
    int kase = int(a.p[L::CASE]);
    // a compliant contact: the kernel of a run-time shape; a rolling ball: its own case
    // (ROLLING), so that the others compile the roll law away
    const bool contact = a.p[L::CONTACT_K] > 0.0 && kase == L::BALL;
    if (kase == L::BALL && a.p[L::ROLL] > 0.0) kase = ROLLING;
    const bool planes = n == 4 && (kase == L::BALL || kase == L::SOLID);
    const bool generic = contact || !((n >= 1 && n <= 3) || planes);
    return {n, kase, int(a.p[L::FORCING]), generic};
}

void run_single(const RunArgs& a) {
    const ShapeKey k = shape_key(a);
#ifdef BB_AVX2_CLONE
    // (the kernel of a run-time shape: the baseline's on every CPU, rk4.hpp)
    if (cpu_has_avx2() && !k.generic) return k.few() ? run_few_avx2(a, k) : run_many_avx2(a, k);
    Baseline::run<0, -1, -1>(a);
#else
    if (k.few()) return run_few<Baseline>(a, k);
    run_many_base(a, k);
#endif
}

}  // namespace bb::rk4
