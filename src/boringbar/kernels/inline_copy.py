"""A faster copy of an inlined function's IR in numba's inliner (compile time only).

Every ``inline="always"`` call site makes numba's ``InlineWorker.inline_ir``
(numba/core/inline_closurecall.py) copy the callee's IR block by block, each
block with its own ``copy.deepcopy``.  Every variable of a block refers to the
function's one ``Scope``, which holds every variable of the function: each
block's copy therefore copies the whole scope again, and the copy grows as
blocks times variables (numba issue 8989).  The kernels inline large functions
at many sites (kernels/rk4.py's ``_rk4`` into each specialisation, most of
kernels/exact.py): for the default run's kernel, deep copies were about half of
its compile time.

:func:`apply` rebuilds ``inline_ir`` from numba's own source with one ``memo``
shared by the blocks of a copy, so that the scope and its variables are copied
once per copy, and the copied blocks share one scope as the original's do.  The
IR inlined is the same; the machine code compiled is the same (the RK4 kernel's
assembly compared equal, up to the addresses in symbol names).  Where numba's
source differs from the text replaced (another numba), nothing is changed and
:func:`applied` says so (tests/test_numba_intrinsics.py fails loudly then).
"""

import inspect
import textwrap

from numba.core import inline_closurecall as _icc

_OLD = """        for block_label, block in the_ir.blocks.items():
            new_block = copy.deepcopy(the_ir.blocks[block_label])"""
_NEW = """        memo = {}  # boringbar.kernels.inline_copy: the scope copied once per copy
        for block_label, block in the_ir.blocks.items():
            new_block = copy.deepcopy(the_ir.blocks[block_label], memo)"""
#: numba's own (unwrapped if this module was loaded before)
_ORIGINAL = getattr(_icc.InlineWorker.inline_ir, "__wrapped__", _icc.InlineWorker.inline_ir)
_PATCHED = None


def _build():
    try:
        src = textwrap.dedent(inspect.getsource(_ORIGINAL))
    except (OSError, TypeError):
        return None
    if src.count(_OLD) != 1:
        return None
    ns = {}
    exec(compile(src.replace(_OLD, _NEW), _icc.__file__, "exec"), vars(_icc), ns)
    fn = ns["inline_ir"]
    fn.__wrapped__ = _ORIGINAL
    return fn


def apply(enabled: bool = True) -> bool:
    """Use the one-memo copy (``enabled``) or numba's own; True if the one-memo copy is in
    use afterwards."""
    global _PATCHED
    if enabled and _PATCHED is None:
        _PATCHED = _build()
    _icc.InlineWorker.inline_ir = _PATCHED if enabled and _PATCHED else _ORIGINAL
    return applied()


def applied() -> bool:
    """Whether numba's inliner copies with the one-memo copy of this module."""
    return _PATCHED is not None and _icc.InlineWorker.inline_ir is _PATCHED
