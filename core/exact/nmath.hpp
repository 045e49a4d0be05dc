// Complex and power arithmetic of the exact kernel, written out operation by operation so
// that its rounding is fixed by this file and not by the compiler or its runtime library.
//
// Why not std::complex's operators:
// - complex / complex: GCC calls __divdc3 (scaled Smith's algorithm), MSVC and Clang their
//   own; ncplx divides as CPython does (_Py_c_quot: one ratio, one denominator), which is
//   also what the exact integrator's setup in Python (simulate/regimes.py) does.
// - complex * complex: the plain formula (ac - bd, ad + bc); GCC adds a NaN recovery
//   through __muldc3 (a library call on every product), which ncplx has not: the kernel's
//   operands are finite (the bindings check them).
// - a float operand acts on each part: (a + bi) x = a x + b x i, (a + bi) / x = a / x +
//   (b / x) i, (a + bi) + x = (a + x) + b i (two operations where promoting x to
//   complex(x, 0.0) took six, or a complex division); a float divided by a complex is the
//   complex division of complex(x, 0.0).
//
// So the exact kernel does every complex operation on ncplx.  The arrays (CVec, CMat, ...)
// store std::complex<double> (the same layout as NumPy's complex128); read an element into
// an ncplx (ncplx(q[k])) before any arithmetic: an expression whose operands are all
// std::complex (or std::complex and double) would take std's operators.  No -ffast-math,
// no FMA contraction (CMakeLists: -ffp-contract=off): a run gives the same bits on every
// x86-64 CPU.
//
// exp, expm1, sin, cos, sqrt, hypot: the C library's (std::).
#pragma once

#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>

#include "../arrays.hpp"
#include "../compiler.hpp"

namespace bb::exact {

// A complex division by zero: Python's ZeroDivisionError message; a std::domain_error,
// so a ValueError to nanobind should one ever reach the bindings
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
    ncplx conjugate() const { return {re, -im}; }
};

// a float assigned to or combined with a complex: complex(x, 0.0)
BB_HOT constexpr ncplx promote(double x) { return {x, 0.0}; }

BB_HOT ncplx operator+(const ncplx& a, const ncplx& b) { return {a.re + b.re, a.im + b.im}; }
BB_HOT ncplx operator-(const ncplx& a, const ncplx& b) { return {a.re - b.re, a.im - b.im}; }
BB_HOT ncplx operator-(const ncplx& a) { return {-a.re, -a.im}; }

// (ac - bd, ad + bc), CPython's _Py_c_prod before 3.14 (no infinity recovery)
BB_HOT ncplx operator*(const ncplx& z, const ncplx& w) {
    double ac = z.re * w.re;
    double bd = z.im * w.im;
    double ad = z.re * w.im;
    double bc = z.im * w.re;
    return {ac - bd, ad + bc};
}

// CPython's _Py_c_quot: Smith's division without scaling
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

// mixed operands: the float acts on each part (a float over a complex: complex division)
BB_HOT ncplx operator+(const ncplx& a, double x) { return {a.re + x, a.im}; }
BB_HOT ncplx operator+(double x, const ncplx& a) { return {x + a.re, a.im}; }
BB_HOT ncplx operator-(const ncplx& a, double x) { return {a.re - x, a.im}; }
BB_HOT ncplx operator-(double x, const ncplx& a) { return {x - a.re, -a.im}; }
BB_HOT ncplx operator*(const ncplx& a, double x) { return {a.re * x, a.im * x}; }
BB_HOT ncplx operator*(double x, const ncplx& a) { return {x * a.re, x * a.im}; }
BB_HOT ncplx operator/(const ncplx& a, double x) {
    if (x == 0.0) throw ComplexZeroDivision();
    return {a.re / x, a.im / x};
}
BB_HOT ncplx operator/(double x, const ncplx& a) { return promote(x) / a; }

BB_HOT ncplx& operator+=(ncplx& a, const ncplx& b) { return a = a + b; }
BB_HOT ncplx& operator+=(ncplx& a, double x) { return a = a + x; }
BB_HOT ncplx& operator-=(ncplx& a, const ncplx& b) { return a = a - b; }
BB_HOT ncplx& operator*=(ncplx& a, const ncplx& b) { return a = a * b; }
BB_HOT ncplx& operator*=(ncplx& a, double x) { return a = a * x; }
BB_HOT ncplx& operator/=(ncplx& a, const ncplx& b) { return a = a / b; }
BB_HOT ncplx& operator/=(ncplx& a, double x) { return a = a / x; }

// equal: both parts ordered-equal; != is its negation, true when a part is NaN
BB_HOT bool operator==(const ncplx& a, const ncplx& b) { return a.re == b.re && a.im == b.im; }
BB_HOT bool operator!=(const ncplx& a, const ncplx& b) { return !(a.re == b.re) || !(a.im == b.im); }
BB_HOT bool operator==(const ncplx& a, double x) { return a.re == x && a.im == 0.0; }
BB_HOT bool operator!=(const ncplx& a, double x) { return !(a == x); }

// abs(z): the C library's hypot (no overflow for large parts)
BB_HOT double abs(const ncplx& z) { return std::hypot(z.re, z.im); }

// e^z = e^x (cos y + i sin y) from the C library's exp, cos and sin, with C99's special
// cases for infinite and NaN parts (Python's cmath.exp gives the same values)
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
            if (x == 0.0) return {c, s};  // a phasor: e^0 = 1, and 1 c is c
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

// x^k for a small integer k by repeated squaring, res = 1 * x^(bits of k) from the lowest
// bit up (tau^3 = tau * (tau * tau), h^4 = (h * h) * (h * h)): exact for the small powers
// the kernel takes and cheaper than std::pow; a negative k inverts at the end
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

// max(a, b) and min(a, b) as b if b > a (b < a) else a (Python's max and min): the first
// argument wins ties and NaN comparisons, so a NaN never replaces a number held in a
inline double pymax(double a, double b) { return b > a ? b : a; }
inline double pymin(double a, double b) { return b < a ? b : a; }
template <class... T>
inline double pymax(double a, double b, T... rest) { return pymax(pymax(a, b), rest...); }
template <class... T>
inline double pymin(double a, double b, T... rest) { return pymin(pymin(a, b), rest...); }

}  // namespace bb::exact
