// What the sources ask of the compiler beyond standard C++, in one place, so that GCC and
// Clang (Linux, macOS) and MSVC (Windows) each get their own spelling of it.
//
// - BB_ALWAYS_INLINE: the kernels' helpers are inlined into the step loop (with the mode
//   count a template constant their loops unroll and the state stays in registers);
// - BB_NOINLINE: a function kept out of line (its callers' code stays small);
// - BB_FLATTEN: a function with everything it calls inlined into it (GCC and Clang; MSVC
//   has no such attribute and keeps it out of line only).
//
// v2 and i2 (two doubles, two 64-bit masks side by side, as one SSE2 or NEON register):
// GCC's and Clang's vector extensions, which keep the RK4 step's pairs in vector
// registers and their selects branch-free (rk4.hpp, linmap.hpp).  MSVC has no vector
// extensions; there they are structs of two lanes with the same operators, lane by lane,
// so the same IEEE operations in the same order give the same bits (slower: MSVC may keep
// the lanes apart).  -DBB_PORTABLE_VECTORS builds the structs with GCC or Clang too, to
// test that path where MSVC is not at hand.
#pragma once

#include <cstring>

#if defined(__GNUC__) || defined(__clang__)
#define BB_ALWAYS_INLINE inline __attribute__((always_inline))
#define BB_NOINLINE __attribute__((noinline))
#define BB_FLATTEN __attribute__((flatten, noinline))
#elif defined(_MSC_VER)
#define BB_ALWAYS_INLINE __forceinline
#define BB_NOINLINE __declspec(noinline)
#define BB_FLATTEN __declspec(noinline)
#else
#define BB_ALWAYS_INLINE inline
#define BB_NOINLINE
#define BB_FLATTEN
#endif

namespace bb {

#if (defined(__GNUC__) || defined(__clang__)) && !defined(BB_PORTABLE_VECTORS)

typedef double v2 __attribute__((vector_size(16)));
typedef long long i2 __attribute__((vector_size(16)));

// the bits of a pair as masks, and back (no conversion: a reinterpretation)
BB_ALWAYS_INLINE i2 as_bits(v2 v) { return (i2)v; }
BB_ALWAYS_INLINE v2 as_v2(i2 m) { return (v2)m; }

#else

struct i2 {
    long long l[2];
    long long operator[](int k) const { return l[k]; }
};
struct v2 {
    double d[2];
    double operator[](int k) const { return d[k]; }
};

BB_ALWAYS_INLINE i2 as_bits(v2 v) {
    i2 m;
    std::memcpy(&m, &v, sizeof m);
    return m;
}
BB_ALWAYS_INLINE v2 as_v2(i2 m) {
    v2 v;
    std::memcpy(&v, &m, sizeof v);
    return v;
}

BB_ALWAYS_INLINE v2 operator+(v2 a, v2 b) { return {a.d[0] + b.d[0], a.d[1] + b.d[1]}; }
BB_ALWAYS_INLINE v2 operator-(v2 a, v2 b) { return {a.d[0] - b.d[0], a.d[1] - b.d[1]}; }
BB_ALWAYS_INLINE v2 operator*(v2 a, v2 b) { return {a.d[0] * b.d[0], a.d[1] * b.d[1]}; }
BB_ALWAYS_INLINE v2 operator+(v2 a, double s) { return {a.d[0] + s, a.d[1] + s}; }
BB_ALWAYS_INLINE v2 operator-(v2 a, double s) { return {a.d[0] - s, a.d[1] - s}; }
BB_ALWAYS_INLINE v2 operator*(v2 a, double s) { return {a.d[0] * s, a.d[1] * s}; }
BB_ALWAYS_INLINE v2 operator+(double s, v2 a) { return {s + a.d[0], s + a.d[1]}; }
BB_ALWAYS_INLINE v2 operator-(double s, v2 a) { return {s - a.d[0], s - a.d[1]}; }
BB_ALWAYS_INLINE v2 operator*(double s, v2 a) { return {s * a.d[0], s * a.d[1]}; }
BB_ALWAYS_INLINE v2& operator+=(v2& a, v2 b) { return a = a + b; }
// comparisons as the vector extensions give them: all ones where true, 0 where false
BB_ALWAYS_INLINE i2 operator>(v2 a, v2 b) { return {-(long long)(a.d[0] > b.d[0]),
                                                    -(long long)(a.d[1] > b.d[1])}; }
BB_ALWAYS_INLINE i2 operator<(v2 a, v2 b) { return {-(long long)(a.d[0] < b.d[0]),
                                                    -(long long)(a.d[1] < b.d[1])}; }
BB_ALWAYS_INLINE i2 operator==(v2 a, v2 b) { return {-(long long)(a.d[0] == b.d[0]),
                                                     -(long long)(a.d[1] == b.d[1])}; }
BB_ALWAYS_INLINE i2 operator&(i2 a, i2 b) { return {a.l[0] & b.l[0], a.l[1] & b.l[1]}; }
BB_ALWAYS_INLINE i2 operator|(i2 a, i2 b) { return {a.l[0] | b.l[0], a.l[1] | b.l[1]}; }
BB_ALWAYS_INLINE i2 operator~(i2 a) { return {~a.l[0], ~a.l[1]}; }
BB_ALWAYS_INLINE i2& operator&=(i2& a, i2 b) { return a = a & b; }

#endif

}  // namespace bb
