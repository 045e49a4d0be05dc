// The namespace of the exact kernel's code: bb::exact, or bb::exact_avx2 where
// driver_avx2.cpp compiles the same headers a second time, for AVX2 (see driver.cpp).
#pragma once

#ifndef BB_EXACT_NS
#define BB_EXACT_NS exact
#endif
