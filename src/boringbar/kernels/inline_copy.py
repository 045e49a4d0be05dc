"""numba's inliner, faster: one copy of an inlined function's IR, and its IR built once
per compile (compile time only).

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

Each ``inline="always"`` call site also makes numba run the callee's whole untyped
pipeline again (``InlineWorker.inline_function`` calls ``run_untyped_passes``), its
own inlining of its callees included: a piece inlined at 17 sites, or into a
function that is itself inlined at several, is rebuilt from its bytecode each time
(339 times in the exact kernel's compile, for about 60 functions).  Within one
compile (the same typing and target contexts, locals, pipeline and flags objects,
which numba hands down unchanged to every nested inlining) the result depends on the
function alone, and ``inline_ir`` copies it before changing anything.
:func:`inline_function` keeps it by function for the compile under way and hands
the kept IR to ``inline_ir``; it repeats the one side effect of
``run_untyped_passes`` that outlives it (``flags.enable_ssa = False``).
"""

import inspect
import textwrap

from numba.core import inline_closurecall as _icc

from boringbar.kernels.numba_source import source_digest

_OLD = """        for block_label, block in the_ir.blocks.items():
            new_block = copy.deepcopy(the_ir.blocks[block_label])"""
_NEW = """        memo = {}  # boringbar.kernels.inline_copy: the scope copied once per copy
        for block_label, block in the_ir.blocks.items():
            new_block = copy.deepcopy(the_ir.blocks[block_label], memo)"""
#: numba's own (unwrapped if this module was loaded before)
_ORIGINAL = getattr(_icc.InlineWorker.inline_ir, "__wrapped__", _icc.InlineWorker.inline_ir)
_PATCHED = None
_INLINE_FUNCTION = _icc.InlineWorker.inline_function
_ORIGINAL_INLINE_FUNCTION = getattr(_INLINE_FUNCTION, "__wrapped__", _INLINE_FUNCTION)
#: SHA-256 of numba 0.68's ``InlineWorker.inline_function`` source, which
#: :func:`inline_function` replaces
NUMBA_INLINE_FUNCTION = "1b53f183258e659da3c7dd47a5cd6dfb342016a03e20a079fb24f469d7c6d1e1"
#: the compile whose callees' IR is kept (its five objects), and that IR by function
_KEPT = {"compile": None, "ir": {}}


def inline_function(self, caller_ir, block, i, function, arg_typs=None):
    """numba's ``InlineWorker.inline_function``, the callee's untyped IR built once per
    compile."""
    compile_ = (self.typingctx, self.targetctx, self.locals, self.pipeline, self.flags)
    kept = _KEPT["compile"]
    if kept is None or any(a is not b for a, b in zip(kept, compile_)):
        _KEPT["compile"], _KEPT["ir"] = compile_, {}
    callee_ir = _KEPT["ir"].get(function)
    if callee_ir is None:
        callee_ir = _KEPT["ir"][function] = self.run_untyped_passes(function)
    else:
        self.flags.enable_ssa = False  # as run_untyped_passes leaves it
    return self.inline_ir(caller_ir, block, i, callee_ir, function.__code__.co_freevars,
                          arg_typs=arg_typs)


inline_function.__wrapped__ = _ORIGINAL_INLINE_FUNCTION


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
    ours = bool(enabled and _PATCHED)
    _icc.InlineWorker.inline_ir = _PATCHED if ours else _ORIGINAL
    keep = ours and source_digest(_ORIGINAL_INLINE_FUNCTION) == NUMBA_INLINE_FUNCTION
    _icc.InlineWorker.inline_function = inline_function if keep else _ORIGINAL_INLINE_FUNCTION
    _KEPT["compile"], _KEPT["ir"] = None, {}
    return applied()


def applied() -> bool:
    """Whether numba's inliner copies with the one-memo copy of this module and builds an
    inlined function's IR once per compile."""
    return (_PATCHED is not None and _icc.InlineWorker.inline_ir is _PATCHED
            and _icc.InlineWorker.inline_function is inline_function)
