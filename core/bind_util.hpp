// The bindings' boundary checks: every array handed to the core is checked for
// dtype, shape, contiguity and writability here, and a wrong one is a ValueError
// that names it (never a crash).  After the check the integrators see only views
// (arrays.hpp).
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>

#include <cmath>
#include <complex>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <type_traits>
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

// The run descriptions' array fields carry their dtype in their type, so that a field
// refuses an array of another dtype when it is set and the signatures show what it takes:
// In<T> takes a read-only array too (the run only reads it), Out<T> only a writable one
// (the run writes into it: an output, a state advanced in place).  Their shapes and
// contiguity depend on each other (the mode count is in p), so they are checked when the
// run starts (checked, span1...).
template <class T> using In = nb::ndarray<const T, nb::device::cpu>;
template <class T> using Out = nb::ndarray<T, nb::device::cpu>;
// Any CPU array, read-only ones too: what a refused value is described from, and the
// arguments of the functions that check their dtype themselves (impact_period).
using AnyArray = nb::ndarray<nb::ro, nb::device::cpu>;

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
    if (d.code == uint8_t(nb::dlpack::dtype_code::Bool)) return kind;  // NumPy's name
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
    // a typed field is read as its own dtype (its setter refused any other)
    constexpr bool typed = !std::is_void_v<std::remove_const_t<typename A::Scalar>>;
    static_assert(!typed || std::is_same_v<std::remove_const_t<typename A::Scalar>, T>,
                  "an array field read as another dtype than its own");
    auto fail = [&](const std::string& why) {
        throw nb::value_error(("core: array '" + std::string(name) + "' must be a C-contiguous " +
                               dtype_name<T>() + " array of shape " + wanted(shape) + "; " + why)
                                  .c_str());
    };
    if (!typed && a.dtype() != nb::dtype<T>()) fail("got dtype " + dtype_of(a.dtype()));
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
// refuses it: an array of the field's dtype (In<T>, Out<T>), writable for an output; a
// number; an integer.  An array is never converted: a converted copy of an output would
// take the run's writes and lose them, and an input is held to the same rule (a float64
// array is what every caller has; a field then always is the caller's own array).  The
// arrays' shapes and contiguity are checked when the run starts, against each other.

// Why h cannot be a field of dtype T (writable for an output): a ValueError naming it.
template <class T>
[[noreturn]] void refuse_array(nb::handle h, const char* name, bool writable) {
    std::string got;
    AnyArray any;
    if (!nb::try_cast(h, any, false)) {
        got = h.is_none() ? std::string("None")
                          : "type " + std::string(nb::type_name(h.type()).c_str());
    } else {
        nb::ndarray<nb::device::cpu> rw;
        const bool read_only = writable && !nb::try_cast(h, rw, false);
        if (any.dtype() != nb::dtype<T>())
            got = "dtype " + dtype_of(any.dtype()) + (read_only ? ", read-only" : "");
        else if (read_only)
            got = "a read-only array";
        else
            got = "an array it cannot take";
    }
    const char* article = writable ? "a writable " : dtype_name<T>()[0] == 'i' ? "an " : "a ";
    throw nb::value_error(("core: '" + std::string(name) + "' must be " + article +
                           dtype_name<T>() + " array; got " + got)
                              .c_str());
}

// h as an input of dtype T (read-only allowed, not converted), or a ValueError naming it
template <class T>
In<T> input_array(nb::handle h, const char* name) {
    In<T> a;
    if (!nb::try_cast(h, a, false)) refuse_array<T>(h, name, false);
    return a;
}

// h as a writable array of dtype T (the run writes into it; not converted), or a
// ValueError naming it
template <class T>
Out<T> output_array(nb::handle h, const char* name) {
    Out<T> a;
    if (!nb::try_cast(h, a, false)) refuse_array<T>(h, name, true);
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

    // an input array of dtype T (read-only allowed)
    template <class T>
    Fields& in(const char* name, In<T> C::*m, const char* doc) {
        return array(name, m, doc, [name](nb::handle h) { return input_array<T>(h, name); });
    }
    // an output array of dtype T (written in place: writable)
    template <class T>
    Fields& out(const char* name, Out<T> C::*m, const char* doc) {
        return array(name, m, doc, [name](nb::handle h) { return output_array<T>(h, name); });
    }
    // an optional output array of dtype T (None: not kept)
    template <class T>
    Fields& out_or_none(const char* name, Out<T> C::*m, const char* doc) {
        using A = Out<T>;
        const std::string type = type_text<A>() + " | None";
        cls.def_prop_rw(
            name, [m](const C& c) -> std::optional<A> {
                if (!(c.*m).is_valid()) return std::nullopt;
                return c.*m;
            },
            [m, name](C& c, nb::handle h) { c.*m = h.is_none() ? A() : output_array<T>(h, name); },
            nb::arg("value").none(), nb::for_setter(nb::sig(setter_sig(name, type).c_str())),
            (std::string(doc) + "\n\n" + type).c_str());
        return *this;
    }
    // the records a single run writes, RK4's and the exact integrator's alike (the same
    // rows: model.hpp): members rec, imp, stick, strobe and met of C
    Fields& records() {
        return out("rec", &C::rec,
                   "the history rows (t, W, W', aux, aux', f), (n, 6); a rolling ball's (n, 7) "
                   "adds its spin")
            .out("imp", &C::imp, "the impact rows (t, wall, y'-), (n, 3)")
            .out("stick", &C::stick, "the stick intervals (start, end), (n, 2)")
            .out("strobe", &C::strobe, "the Poincare rows (t, W, W', aux, aux'), (n, 5)")
            .out("met", &C::met, "the metrics (MET_SIZE float64), updated in place");
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

  private:
    // nanobind's name of the array type A, as its signatures show it
    template <class A>
    static std::string type_text() {
        return nb::detail::make_caster<A>::Name.text;
    }
    // the setter's signature: it takes an object (None too: refused with the field's name
    // rather than by nanobind's dispatch), but only a value of ``type`` is kept
    static std::string setter_sig(const char* name, const std::string& type) {
        return "def " + std::string(name) + "(self, value: " + type + ", /) -> None";
    }
    // a required array field of type A, set through ``convert``; its type closes its doc
    // (help() shows a property's doc only)
    template <class A, class Convert>
    Fields& array(const char* name, A C::*m, const char* doc, Convert convert) {
        const std::string type = type_text<A>();
        cls.def_prop_rw(
            name, [m](const C& c) { return c.*m; },
            [m, convert](C& c, nb::handle h) { c.*m = convert(h); }, nb::arg("value").none(),
            nb::for_setter(nb::sig(setter_sig(name, type).c_str())),
            (std::string(doc) + "\n\n" + type).c_str());
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
