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
#include <utility>
#include <vector>

#include "arrays.hpp"
#include "layout.hpp"

namespace bb::bind {

namespace nb = nanobind;

// A NumPy array of the given shape that takes v's memory over (freed with the array).
template <class T, int D>
nb::ndarray<nb::numpy, T, nb::ndim<D>> owned_array(std::vector<T>&& v,
                                                   std::initializer_list<size_t> shape) {
    auto* data = new std::vector<T>(std::move(v));
    nb::capsule owner(data, [](void* p) noexcept { delete static_cast<std::vector<T>*>(p); });
    return nb::ndarray<nb::numpy, T, nb::ndim<D>>(data->data(), shape, owner);
}

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

// The history's columns: REC_NCOL, or one more (the spin) for a rolling ball whose rec
// has it.
template <class A>
std::int64_t rec_columns(const A& rec, bool roll) {
    constexpr std::int64_t ncol = layout::REC_NCOL;
    const bool spin = roll && rec.ndim() == 2 && std::int64_t(rec.shape(1)) == ncol + 1;
    return spin ? ncol + 1 : ncol;
}

// A scalar argument outside its range is a ValueError that names it.
inline void require(bool ok, const std::string& what) {
    if (!ok) throw nb::value_error(("core: " + what).c_str());
}

inline bool finite(double v) { return std::isfinite(v); }

// ---- the run descriptions' fields --------------------------------------------------------
//
// A run description (RK4Run, RK4Batch, ExactRun) is a small class whose fields Python sets
// one by one; each field's setter checks what it is given and names the field when it
// refuses it (a NumPy array; writable for an output; a number; an integer).  The arrays'
// dtype, shape and contiguity are checked when the run starts, against each other.

// h as a NumPy array (read-only allowed), or a ValueError naming it
inline In input_array(nb::handle h, const char* name) {
    In a;
    if (!nb::try_cast(h, a, false))
        throw nb::value_error(("core: '" + std::string(name) + "' must be a NumPy array").c_str());
    return a;
}

// h as a writable NumPy array (the run writes into it), or a ValueError naming it
inline Out output_array(nb::handle h, const char* name) {
    Out a;
    if (!nb::try_cast(h, a, false)) {
        In ro;
        const bool is_array = nb::try_cast(h, ro, false);
        throw nb::value_error(("core: '" + std::string(name) + "' must be a " +
                               (is_array ? "writable" : "NumPy") + " array")
                                  .c_str());
    }
    return a;
}

// h as a float (a Python number), or a ValueError naming it
inline double real_value(nb::handle h, const char* name) {
    double v;
    if (!nb::try_cast(h, v, true))
        throw nb::value_error(("core: '" + std::string(name) + "' must be a number").c_str());
    return v;
}

// h as an integer (an integral float too: a count computed in floating point, 2e4 or
// n / 2.0, is accepted), or a ValueError naming it
inline std::int64_t int_value(nb::handle h, const char* name) {
    std::int64_t v;
    if (!nb::isinstance<nb::float_>(h) && nb::try_cast(h, v, true)) return v;
    double d;
    if (nb::isinstance<nb::float_>(h) && nb::try_cast(h, d, false) && std::isfinite(d) &&
        d == std::floor(d) && std::fabs(d) < 9.0e18)
        return std::int64_t(d);
    throw nb::value_error(("core: '" + std::string(name) + "' must be an integer").c_str());
}

// The fields of a run description C, each a property whose setter checks its value.
template <class C>
struct Fields {
    nb::class_<C>& cls;

    // an input array (read-only allowed)
    Fields& in(const char* name, In C::*m, const char* doc) {
        cls.def_prop_rw(
            name, [m](const C& c) { return c.*m; },
            [m, name](C& c, nb::handle h) { c.*m = input_array(h, name); }, nb::arg("value").none(),
            doc);
        return *this;
    }
    // an output array (written in place: writable)
    Fields& out(const char* name, Out C::*m, const char* doc) {
        cls.def_prop_rw(
            name, [m](const C& c) { return c.*m; },
            [m, name](C& c, nb::handle h) { c.*m = output_array(h, name); },
            nb::arg("value").none(), doc);
        return *this;
    }
    // an optional output array (None: not kept)
    Fields& out_or_none(const char* name, Out C::*m, const char* doc) {
        cls.def_prop_rw(
            name, [m](const C& c) -> nb::object {
                if (!(c.*m).is_valid()) return nb::none();
                return nb::cast(c.*m);
            },
            [m, name](C& c, nb::handle h) { c.*m = h.is_none() ? Out() : output_array(h, name); },
            nb::arg("value").none(), doc);
        return *this;
    }
    Fields& real(const char* name, double C::*m, const char* doc) {
        cls.def_prop_rw(
            name, [m](const C& c) { return c.*m; },
            [m, name](C& c, nb::handle h) { c.*m = real_value(h, name); }, nb::arg("value").none(),
            doc);
        return *this;
    }
    Fields& integer(const char* name, std::int64_t C::*m, const char* doc) {
        cls.def_prop_rw(
            name, [m](const C& c) { return c.*m; },
            [m, name](C& c, nb::handle h) { c.*m = int_value(h, name); }, nb::arg("value").none(),
            doc);
        return *this;
    }
};

// An array field that was never set, when the run starts: a ValueError naming it.
template <class A>
const A& given(const A& a, const char* name) {
    if (!a.is_valid())
        throw nb::value_error(("core: '" + std::string(name) + "' was not set").c_str());
    return a;
}

}  // namespace bb::bind
