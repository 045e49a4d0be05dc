"""The kernels' own numba intrinsics, each in a tiny function, checked against plain numpy.

kernels/stack.py (``stack_ptr``) and kernels/views.py (``borrow``, ``with_len``)
build LLVM IR through numba's private ``cgutils`` and the layout of its array
struct (meminfo, parent, nitems, itemsize, data, shape, strides); kernels/interp.py's
``fma`` emits llvm.fma.  A numba release that changes any of these breaks the
kernels in ways that may not raise: these tests fail loudly instead (numba is
pinned to the range they ran on, pyproject.toml).  Not cached: each compiles in
well under a second.
"""

import numpy as np
import pytest
from numba import carray, njit
from numba.core import cgutils, errors

from boringbar.kernels.interp import fma
from boringbar.kernels.stack import stack_ptr
from boringbar.kernels.views import borrow, with_len

#: the array struct fields views.py copies, in numba's order (numba/core/datamodel)
ARRAY_FIELDS = ("meminfo", "parent", "nitems", "itemsize", "data", "shape", "strides")


def test_numba_array_struct_has_the_fields_views_copies():
    from numba.core import types
    from numba.core.datamodel import default_manager

    model = default_manager.lookup(types.Array(types.float64, 2, "A"))
    assert tuple(model._fields) == ARRAY_FIELDS
    assert callable(cgutils.alloca_once) and callable(cgutils.create_struct_proxy)
    assert callable(cgutils.get_null_value) and callable(cgutils.pack_array)


@njit
def _stack_two(n):
    a = carray(stack_ptr(8, np.float64), n)
    b = carray(stack_ptr(8, np.float64), (2, n))
    for i in range(n):
        a[i] = i * i
        b[0, i] = -1.0
        b[1, i] = 2.0 * i
    s = 0.0
    for i in range(n):
        s += a[i] + b[1, i]
    return s, a.shape[0], b.shape[0], b.shape[1], a[n - 1]


def test_stack_ptr_gives_separate_writable_arrays_of_the_asked_shape():
    n = 4
    s, la, rb, cb, last = _stack_two(n)
    assert (la, rb, cb) == (n, 2, n)
    assert last == (n - 1) ** 2  # b's writes did not land in a
    assert s == sum(i * i + 2.0 * i for i in range(n))


def test_stack_ptr_takes_only_a_literal_size():
    @njit
    def f(k):
        return carray(stack_ptr(k, np.float64), 1)[0]

    with pytest.raises(errors.TypingError):
        f(3)


@njit
def _borrowed(x, y):
    v = borrow(x)
    w = borrow(y)  # a strided view: shape and strides carried over
    v[1] = 7.0
    s = 0.0
    for i in range(w.shape[0]):
        for j in range(w.shape[1]):
            s += w[i, j]
    return v.shape[0], v[0] + v[1], w.shape[0], w.shape[1], s


def test_borrow_is_the_same_array_and_data():
    x = np.arange(5.0)
    big = np.arange(24.0).reshape(4, 6)
    y = big[::2, 1::2]
    n, s01, r, c, s = _borrowed(x, y)
    assert (n, r, c) == (5, 2, 3)
    assert x[1] == 7.0 and s01 == 7.0  # writes go to the caller's array
    assert s == y.sum()


@njit
def _shortened(x, n):
    v = with_len(x, n)
    v[n - 1] = -1.0
    s = 0.0
    for i in range(v.shape[0]):
        s += v[i]
    return v.shape[0], s, len(v)


def test_with_len_shortens_a_1d_array_in_place():
    x = np.arange(6.0)
    n, s, ln = _shortened(x, 3)
    assert (n, ln) == (3, 3)
    assert x[2] == -1.0 and s == 0.0 + 1.0 - 1.0
    assert list(x[3:]) == [3.0, 4.0, 5.0]


@njit
def _fma(a, b, c):
    return fma(a, b, c), a * b + c


def test_fma_rounds_once():
    a, b = 1.0 + 2.0**-30, 1.0 - 2.0**-30  # a b = 1 - 2^-60: rounds to 1 unless fused
    fused, plain = _fma(a, b, -1.0)
    assert plain == 0.0
    assert fused == -(2.0**-60)


def test_the_inliner_copies_with_one_memo():
    """kernels/inline_copy.py found numba's text to replace (else compiles take up to twice
    as long, and this numba is not the one it was written for)."""
    from numba.core.inline_closurecall import InlineWorker

    from boringbar.kernels import inline_copy

    assert inline_copy.applied()
    assert InlineWorker.inline_ir.__wrapped__ is inline_copy._ORIGINAL

    @njit(inline="always")
    def inner(a, k):
        s = 0.0
        for i in range(k):
            s += a[i] * i
        return s

    @njit
    def outer(a):
        return inner(a, 3) + inner(a, 2)

    assert outer(np.arange(4.0)) == (0 + 1 + 4) + (0 + 1)
