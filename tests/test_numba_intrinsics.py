"""The kernels' own numba intrinsics, each in a tiny function, checked against plain numpy.

kernels/stack.py (``stack_ptr``) and kernels/views.py (``borrow``, ``with_len``)
build LLVM IR through numba's private ``cgutils`` and the layout of its array
struct (meminfo, parent, nitems, itemsize, data, shape, strides); kernels/interp.py's
``fma`` emits llvm.fma.  A numba release that changes any of these breaks the
kernels in ways that may not raise: these tests fail loudly instead (numba is
pinned to the range they ran on, pyproject.toml).  Not cached: each compiles in
well under a second.
"""

import copy

import numpy as np
import pytest
from numba import carray, njit
from numba.core import analysis, cgutils, errors
from numba.core.compiler import run_frontend
from numba.core.inline_closurecall import InlineWorker

from boringbar.kernels import live_bits, rk4, ssa_blocks
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


def _ssa_ir(blocks):
    """A function's IR as text, block by block, with every scope's variable names."""
    scopes = {id(b.scope): b.scope for b in blocks.values()}
    return ([(label, [str(s) for s in b.body]) for label, b in blocks.items()],
            sorted(sorted(s.localvars._con) for s in scopes.values()))


def _branchy(a, n):
    x = 0.0
    y = 1.0
    for i in range(n):
        if a[i] > 0:
            x = a[i]
            y = x * 2
        elif a[i] < -1:
            x = -a[i]
        else:
            y = y + 1
        while y > 10:
            y = y / 2
            x = x + y
    if n > 3:
        x = y
    return x + y


def _frontend_blocks(name):
    """The IR blocks numba's front end makes of ``_branchy`` or of the RK4 kernel's driver,
    before SSA."""
    return run_frontend(_branchy if name == "branchy" else rk4._rk4.py_func).blocks


@pytest.mark.parametrize("name", ["branchy", "rk4"])
def test_ssa_on_the_naming_blocks_gives_numbas_ir(name):
    """kernels/ssa_blocks.py is in use, and its SSA reconstruction gives the IR numba's own
    gives (same statements, fresh names and phi nodes, in the same blocks and order): on a
    function with redefinitions in branches and loops, and on the RK4 kernel's driver."""
    assert ssa_blocks.applied()
    blocks = _frontend_blocks(name)
    theirs = ssa_blocks.ORIGINAL(copy.deepcopy(blocks))
    ours = ssa_blocks.run_ssa(copy.deepcopy(blocks))
    assert _ssa_ir(ours) == _ssa_ir(theirs)
    assert any("phi" in s for _, body in _ssa_ir(ours)[0] for s in body)


@pytest.mark.parametrize("name", ["branchy", "rk4"])
def test_liveness_on_bit_sets_gives_numbas_live_map(name):
    """kernels/live_bits.py is in use, and its liveness analysis gives numba's own: the
    same variables live at each block's entry, before and after SSA (phi nodes, loops)."""
    assert live_bits.applied()
    blocks = _frontend_blocks(name)
    for ir_blocks in (blocks, ssa_blocks.run_ssa(blocks)):
        cfg = analysis.compute_cfg_from_blocks(ir_blocks)
        usedefs = analysis.compute_use_defs(ir_blocks)
        args = (cfg, ir_blocks, usedefs.usemap, usedefs.defmap)
        theirs = live_bits.ORIGINAL(*args)
        assert live_bits.compute_live_map(*args) == theirs
        assert sum(map(len, theirs.values())) > 20


def test_an_inlined_function_is_built_once_per_compile(monkeypatch):
    """kernels/inline_copy.py keeps a callee's untyped IR for the compile under way: a
    function inlined at three sites (one of them inside another inlined function) is
    built from its bytecode once, not three times, and the result is still right."""
    built = []
    run = InlineWorker.run_untyped_passes

    def counted(self, func, enable_ssa=False):
        built.append(func.__name__)
        return run(self, func, enable_ssa)

    monkeypatch.setattr(InlineWorker, "run_untyped_passes", counted)

    @njit(inline="always")
    def leaf(a, k):
        return a[k] * 2.0

    @njit(inline="always")
    def middle(a):
        return leaf(a, 0) + 1.0

    @njit
    def top(a):
        return leaf(a, 1) + leaf(a, 2) + middle(a)

    assert top(np.arange(4.0)) == 2.0 + 4.0 + 1.0
    assert built.count("leaf") == 1
    assert built.count("middle") == 1
