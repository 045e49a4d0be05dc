// Non-owning views of the NumPy arrays the bindings hand to the integrators.
//
// The integrators index arrays as NumPy does (a[i], a(i, j), ..., row-major); a view
// knows its shape, so a kernel can test "is there room for another row" itself.  Views never own memory: the bindings check dtype, shape
// and contiguity once, at the boundary (bind_util.hpp), and the views are then
// trusted inside the core.
#pragma once

#include <complex>
#include <cstdint>

namespace bb {

using cplx = std::complex<double>;
using idx = std::int64_t;

template <class T>
struct Span1 {
    T* d = nullptr;
    idx n = 0;
    T& operator[](idx i) const { return d[i]; }
    idx size() const { return n; }
};

template <class T>
struct Span2 {
    T* d = nullptr;
    idx n0 = 0, n1 = 0;
    T& operator()(idx i, idx j) const { return d[i * n1 + j]; }
    T* row(idx i) const { return d + i * n1; }
    Span1<T> operator[](idx i) const { return {d + i * n1, n1}; }
};

template <class T>
struct Span3 {
    T* d = nullptr;
    idx n0 = 0, n1 = 0, n2 = 0;
    T& operator()(idx i, idx j, idx k) const { return d[(i * n1 + j) * n2 + k]; }
    Span2<T> operator[](idx i) const { return {d + i * n1 * n2, n1, n2}; }
};

template <class T>
struct Span4 {
    T* d = nullptr;
    idx n0 = 0, n1 = 0, n2 = 0, n3 = 0;
    T& operator()(idx i, idx j, idx k, idx l) const {
        return d[((i * n1 + j) * n2 + k) * n3 + l];
    }
    Span3<T> operator[](idx i) const { return {d + i * n1 * n2 * n3, n1, n2, n3}; }
};

using Vec = Span1<double>;
using Mat = Span2<double>;
using Arr3 = Span3<double>;
using CVec = Span1<cplx>;
using CMat = Span2<cplx>;
using CArr3 = Span3<cplx>;
using CArr4 = Span4<cplx>;

}  // namespace bb
