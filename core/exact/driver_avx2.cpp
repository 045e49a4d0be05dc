// The exact kernel compiled for AVX2, in bb::exact_avx2: driver.cpp and its headers again,
// with every function of theirs under target("avx2"); driver.cpp's run_exact calls this
// one's for harmonic runs where the CPU has AVX2.  The standard and shared headers come first, outside the
// pragma, so that their inline functions (one copy each in the module) stay baseline code.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(BB_NO_AVX2_CLONE)

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include "../arrays.hpp"
#include "../layout.hpp"
#include "../model.hpp"
#include "driver.hpp"

namespace bb::exact_avx2 {
using exact::ExactRun;
}  // namespace bb::exact_avx2

#pragma GCC target("avx2")
#define BB_EXACT_NS exact_avx2
#define BB_EXACT_AVX2_BUILD 1
#include "driver.cpp"

#endif
