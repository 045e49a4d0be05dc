// The bindings' boundary checks: every array handed to the core is checked for
// dtype, shape, contiguity and writability here, and a wrong one is a ValueError
// that names it (never a crash).  After the check the integrators see only views
// (arrays.hpp).
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cmath>
#include <complex>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <vector>

#include "arrays.hpp"

namespace bb::bind {

namespace nb = nanobind;

// Any CPU array; read-only ones too (for inputs).
using In = nb::ndarray<nb::ro, nb::device::cpu>;
// Any writable CPU array (for outputs and states updated in place).
using Out = nb::ndarray<nb::device::cpu>;

template <class T> inline const char* dtype_name();
template <> inline const char* dtype_name<double>() { return "float64"; }
template <> inline const char* dtype_name<std::complex<double>>() { return "complex128"; }
template <> inline const char* dtype_name<std::int64_t>() { return "int64"; }

inline std::string dtype_of(nb::dlpack::dtype d) {
    const char* kind = d.code == uint8_t(nb::dlpack::dtype_code::Float)     ? "float"
                       : d.code == uint8_t(nb::dlpack::dtype_code::Int)     ? "int"
                       : d.code == uint8_t(nb::dlpack::dtype_code::UInt)    ? "uint"
                       : d.code == uint8_t(nb::dlpack::dtype_code::Complex) ? "complex"
                       : d.code == uint8_t(nb::dlpack::dtype_code::Bool)    ? "bool"
                                                                            : "other";
    return std::string(kind) + std::to_string(int(d.bits));
}

template <class A>
std::string shape_of(const A& a) {
    std::string s = "(";
    for (size_t i = 0; i < a.ndim(); ++i) {
        s += std::to_string(a.shape(i));
        if (a.ndim() == 1 || i + 1 < a.ndim()) s += a.ndim() == 1 ? "," : ", ";
    }
    return s + ")";
}

inline std::string wanted(std::initializer_list<std::int64_t> shape) {
    std::string s = "(";
    size_t i = 0;
    for (auto n : shape) {
        s += n < 0 ? std::string("n") : std::to_string(n);
        if (shape.size() == 1 || ++i < shape.size()) s += shape.size() == 1 ? "," : ", ";
    }
    return s + ")";
}

// The data pointer of ``a`` once it is a C-contiguous array of T with the given shape
// (-1: any length; a length given as lo..hi through ``min_len`` is checked by the caller).
template <class T, class A>
T* checked(const A& a, const char* name, std::initializer_list<std::int64_t> shape) {
    auto fail = [&](const std::string& why) {
        throw nb::value_error(("core: array '" + std::string(name) + "' must be a C-contiguous " +
                               dtype_name<T>() + " array of shape " + wanted(shape) + "; " + why)
                                  .c_str());
    };
    if (a.dtype() != nb::dtype<T>()) fail("got dtype " + dtype_of(a.dtype()));
    if (a.ndim() != shape.size()) fail("got shape " + shape_of(a));
    size_t i = 0;
    for (auto n : shape) {
        if (n >= 0 && std::int64_t(a.shape(i)) != n) fail("got shape " + shape_of(a));
        ++i;
    }
    // an empty array is contiguous whatever its strides (NumPy gives (0, 0) for (0, n))
    std::int64_t step = 1;
    for (size_t k = a.ndim(); k-- > 0 && a.size() > 0;) {
        if (a.shape(k) > 1 && a.stride(k) != step) fail("got a non-contiguous view");
        step *= std::int64_t(a.shape(k));
    }
    return static_cast<T*>(const_cast<void*>(static_cast<const void*>(a.data())));
}

template <class T, class A>
Span1<T> span1(const A& a, const char* name, std::int64_t n0 = -1) {
    T* d = checked<T>(a, name, {n0});
    return {d, std::int64_t(a.shape(0))};
}

template <class T, class A>
Span2<T> span2(const A& a, const char* name, std::int64_t n0 = -1, std::int64_t n1 = -1) {
    T* d = checked<T>(a, name, {n0, n1});
    return {d, std::int64_t(a.shape(0)), std::int64_t(a.shape(1))};
}

template <class T, class A>
Span3<T> span3(const A& a, const char* name, std::int64_t n0 = -1, std::int64_t n1 = -1,
               std::int64_t n2 = -1) {
    T* d = checked<T>(a, name, {n0, n1, n2});
    return {d, std::int64_t(a.shape(0)), std::int64_t(a.shape(1)), std::int64_t(a.shape(2))};
}

template <class T, class A>
Span4<T> span4(const A& a, const char* name, std::int64_t n0 = -1, std::int64_t n1 = -1,
               std::int64_t n2 = -1, std::int64_t n3 = -1) {
    T* d = checked<T>(a, name, {n0, n1, n2, n3});
    return {d, std::int64_t(a.shape(0)), std::int64_t(a.shape(1)), std::int64_t(a.shape(2)),
            std::int64_t(a.shape(3))};
}

// A scalar argument outside its range is a ValueError that names it.
inline void require(bool ok, const std::string& what) {
    if (!ok) throw nb::value_error(("core: " + what).c_str());
}

inline bool finite(double v) { return std::isfinite(v); }

}  // namespace bb::bind
