// Complex and power arithmetic as numba compiles it, for bit-identical ports of the exact
// kernel (numba 0.68 on CPython 3.11; numba/cpython/numbers.py and cmathimpl.py).
//
// Why not std::complex's operators:
// - complex / complex: GCC calls __divdc3 (scaled Smith's algorithm); numba does CPython's
//   _Py_c_quot (one ratio, one denominator): different roundings.
// - a float operand: numba promotes it to complex(x, 0.0) and does the complex operation, so
//   (a + bi) * x = (a x - b 0.0) + (a 0.0 + b x) i and (a + bi) + x = (a + x) + (b + 0.0) i;
//   std::complex computes (a x, b x) and (a + x, b).  The values agree except for signed
//   zeros, infinities and NaNs (b 0.0 is NaN for an infinite b; -0.0 + 0.0 is +0.0), which
//   we keep as numba has them: the same formula, operation for operation.
// - complex * complex: the same formula (ac - bd, ad + bc) as numba on CPython < 3.14, but
//   GCC adds a NaN recovery through __muldc3; ncplx has none, like numba.
//
// So the exact kernel does every complex operation on ncplx, whose operators are numba's.
// The arrays (CVec, CMat, ...) store std::complex<double> (the same layout as NumPy's
// complex128); read an element into an ncplx (ncplx(q[k])) before any arithmetic: an
// expression whose operands are all std::complex (or std::complex and double) would take
// std's operators.  No -ffast-math, no FMA contraction (CMakeLists: -ffp-contract=off), as
// numba's LLVM, which contracts nothing without fastmath.
//
// exp, expm1, sin, cos, sqrt, hypot: the C library's (std::), as numba calls them.
#pragma once

#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>

#include "../arrays.hpp"
#include "../compiler.hpp"

namespace bb::exact {

// numba raises ZeroDivisionError("complex division by zero"); the bindings may map this
// type to it (it is a std::domain_error, a ValueError to nanobind by default)
struct ComplexZeroDivision : std::domain_error {
    ComplexZeroDivision() : std::domain_error("complex division by zero") {}
};

#define BB_HOT BB_ALWAYS_INLINE

struct ncplx {
    double re = 0.0;
    double im = 0.0;

    constexpr ncplx() = default;
    constexpr ncplx(double r, double i) : re(r), im(i) {}
    // from and to the arrays' element type (implicit: q[k] = z; ncplx z = q[k])
    ncplx(const cplx& z) : re(z.real()), im(z.imag()) {}
    operator cplx() const { return cplx(re, im); }

    double real() const { return re; }
    double imag() const { return im; }
    // numba: imag negated as -0.0 - imag (mathimpl.negate_real)
    ncplx conjugate() const { return {re, -0.0 - im}; }
};

// a float assigned to or combined with a complex: numba's cast, complex(x, 0.0)
BB_HOT constexpr ncplx promote(double x) { return {x, 0.0}; }

BB_HOT ncplx operator+(const ncplx& a, const ncplx& b) { return {a.re + b.re, a.im + b.im}; }
BB_HOT ncplx operator-(const ncplx& a, const ncplx& b) { return {a.re - b.re, a.im - b.im}; }
BB_HOT ncplx operator-(const ncplx& a) { return {-0.0 - a.re, -0.0 - a.im}; }

// CPython's _Py_c_prod (numba's complex_mul without the 3.14 infinity recovery)
BB_HOT ncplx operator*(const ncplx& z, const ncplx& w) {
    double ac = z.re * w.re;
    double bd = z.im * w.im;
    double ad = z.re * w.im;
    double bc = z.im * w.re;
    return {ac - bd, ad + bc};
}

// CPython's _Py_c_quot (numba's complex_div)
BB_HOT ncplx operator/(const ncplx& a, const ncplx& b) {
    double abs_breal = std::fabs(b.re);
    double abs_bimag = std::fabs(b.im);
    if (abs_breal >= abs_bimag) {
        if (abs_breal == 0.0) throw ComplexZeroDivision();
        double ratio = b.im / b.re;
        double denom = b.re + b.im * ratio;
        return {(a.re + a.im * ratio) / denom, (a.im - a.re * ratio) / denom};
    }
    if (abs_bimag >= abs_breal) {
        double ratio = b.re / b.im;
        double denom = b.re * ratio + b.im;
        return {(a.re * ratio + a.im) / denom, (a.im * ratio - a.re) / denom};
    }
    // at least one of b.re, b.im is a NaN
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan};
}

// mixed operands: the float promoted first, as numba types them
BB_HOT ncplx operator+(const ncplx& a, double x) { return a + promote(x); }
BB_HOT ncplx operator+(double x, const ncplx& a) { return promote(x) + a; }
BB_HOT ncplx operator-(const ncplx& a, double x) { return a - promote(x); }
BB_HOT ncplx operator-(double x, const ncplx& a) { return promote(x) - a; }
BB_HOT ncplx operator*(const ncplx& a, double x) { return a * promote(x); }
BB_HOT ncplx operator*(double x, const ncplx& a) { return promote(x) * a; }
BB_HOT ncplx operator/(const ncplx& a, double x) { return a / promote(x); }
BB_HOT ncplx operator/(double x, const ncplx& a) { return promote(x) / a; }

BB_HOT ncplx& operator+=(ncplx& a, const ncplx& b) { return a = a + b; }
BB_HOT ncplx& operator+=(ncplx& a, double x) { return a = a + x; }
BB_HOT ncplx& operator-=(ncplx& a, const ncplx& b) { return a = a - b; }
BB_HOT ncplx& operator*=(ncplx& a, const ncplx& b) { return a = a * b; }
BB_HOT ncplx& operator*=(ncplx& a, double x) { return a = a * x; }
BB_HOT ncplx& operator/=(ncplx& a, const ncplx& b) { return a = a / b; }
BB_HOT ncplx& operator/=(ncplx& a, double x) { return a = a / x; }

// numba: both parts ordered-equal; != is its negation, unordered
BB_HOT bool operator==(const ncplx& a, const ncplx& b) { return a.re == b.re && a.im == b.im; }
BB_HOT bool operator!=(const ncplx& a, const ncplx& b) { return !(a.re == b.re) || !(a.im == b.im); }
BB_HOT bool operator==(const ncplx& a, double x) { return a == promote(x); }
BB_HOT bool operator!=(const ncplx& a, double x) { return a != promote(x); }

// abs(z): numba's complex_abs, the C library's hypot
BB_HOT double abs(const ncplx& z) { return std::hypot(z.re, z.im); }

// cmath.exp as numba's exp_impl (cmathimpl.py), with its special cases
inline ncplx cexp(const ncplx& z) {
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    double x = z.re;
    double y = z.im;
    bool x_finite = std::isfinite(x);
    bool y_finite = std::isfinite(y);
    if (x_finite) {
        if (y_finite) {
            // cos and sin in one call: glibc's sincos gives the bits of its cos and sin (GCC
            // merges the two calls itself, but not where a caller is flattened)
            double c, s;
#ifdef __GLIBC__
            ::sincos(y, &s, &c);
#else
            c = std::cos(y);
            s = std::sin(y);
#endif
            double r = std::exp(x);
            return {r * c, r * s};
        }
        return {nan, nan};
    }
    if (std::isnan(x)) {
        if (y != 0.0) return {x, x};
        return {x, y};
    }
    if (x > 0.0) {  // +inf
        if (y_finite) {
            double real = std::cos(y);
            double imag = std::sin(y);
            if (real != 0.0) real *= x;
            if (imag != 0.0) imag *= x;
            return {real, imag};
        }
        return {x, nan};
    }
    // -inf
    if (y_finite) {
        double r = std::exp(x);
        double c = std::cos(y);
        double s = std::sin(y);
        return {r * c, r * s};
    }
    return {0.0, 0.0};
}

// x ** k for an integer literal k, as numba's static_power_impl unrolls it: repeated
// squaring, res = 1 * x^(bits of k) from the lowest bit up (tau ** 3 = tau * (tau * tau),
// h ** 4 = (h * h) * (h * h)); a negative k inverts at the end
inline double ipow(double x, int k) {
    bool invert = k < 0;
    int e = invert ? -k : k;
    double res = 1.0;
    double val = x;
    while (e != 0) {
        if (e & 1) res = res * val;
        e >>= 1;
        val = val * val;
    }
    return invert ? 1.0 / res : res;
}

// Python's max(a, b) and min(a, b) as numba compiles them: b if b > a (b < a) else a, so
// the first argument wins ties and NaN comparisons
inline double pymax(double a, double b) { return b > a ? b : a; }
inline double pymin(double a, double b) { return b < a ? b : a; }
template <class... T>
inline double pymax(double a, double b, T... rest) { return pymax(pymax(a, b), rest...); }
template <class... T>
inline double pymin(double a, double b, T... rest) { return pymin(pymin(a, b), rest...); }

}  // namespace bb::exact
