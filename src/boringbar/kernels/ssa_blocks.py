"""numba's SSA reconstruction visiting only the blocks that name a variable (compile time only).

numba rebuilds SSA form (numba/core/ssa.py, ``_run_ssa``) one variable at a time, for
every variable assigned more than once, and for each such variable it rewrites every
block of the function twice (fresh names for its definitions, then each use tied to its
reaching definition), statement by statement.  The kernels inline their pieces into one
large function (the exact kernel's driver: about 870 such variables over thousands of
blocks), so the pass grows as variables times blocks: about 37 s of the exact kernel's
cold compile.

A block that neither assigns nor uses the variable comes out of both rewrites as it went
in; the one thing the second rewrite can do to such a block is to put a phi node at its
top (a join that the variable's definitions reach).  :func:`apply` installs a
``_run_ssa`` that runs numba's own two rewrites (its handlers, states and phi placement,
unchanged) on the blocks that name the variable only, and prepends the phi nodes wherever
they land; the blocks, the variables' fresh names and the phi nodes are the same as
numba's, in the same order (``tests/test_numba_intrinsics.py`` compares the two on a
function's IR).  Where numba's ssa module is not the text this module was written
against (another numba), nothing is changed and :func:`applied` says so, and that test
fails loudly.
"""

from collections import defaultdict

from numba.core import errors, ir
from numba.core import ssa as _ssa
from numba.core.analysis import compute_cfg_from_blocks

from boringbar.kernels.numba_source import source_digest

#: SHA-256 of the source of numba 0.68's ``numba.core.ssa``, whose ``_run_ssa`` this module
#: replaces with one made of that module's own pieces
NUMBA_SSA = "d20accd92757fef663a43e78d0ee88fe01d9333379eda463c9e15f0e7785e490"
#: numba's own (unwrapped if this module was loaded before)
ORIGINAL = getattr(_ssa._run_ssa, "__wrapped__", _ssa._run_ssa)


def naming_blocks(blocks) -> dict:
    """For each variable name, the labels of the blocks whose statements name it, in block
    order."""
    where = defaultdict(list)
    for label, block in blocks.items():
        names = set()
        for stmt in block.body:
            names.update(var.name for var in stmt.list_vars())
        for name in names:
            where[name].append(label)
    return where


def _rewrite(blocks, labels, states, handler):
    sub = {label: blocks[label] for label in labels}
    return _ssa._run_block_rewrite(sub, states, handler)


def _fix_variable(blocks, labels, varname, scope, cfg, df_plus, list_vars):
    """numba's ``_fresh_vars`` then ``_fix_ssa_vars`` for one variable, on ``labels``
    only; the blocks that changed, by label."""
    defmap = defaultdict(list)
    states = {"scope": scope, "varname": varname, "defmap": defmap}
    fresh = _rewrite(blocks, labels, states, _ssa._FreshVarHandler())
    phimap = defaultdict(list)
    states = {"scope": scope, "varname": varname, "defmap": defmap, "phimap": phimap,
              "cfg": cfg, "phi_locations": _ssa._compute_phi_locations(df_plus, defmap)}
    fixed = _rewrite(fresh, labels, states, _ssa._FixSSAVars(list_vars))
    for label, philist in phimap.items():
        block = fixed.get(label)
        if block is None:
            old = blocks[label]
            block = fixed[label] = ir.Block(scope=old.scope, loc=old.loc)
            block.body = old.body  # replaced, not changed, on the next line
        block.body = philist + block.body
    return fixed


def run_ssa(blocks):
    """numba's ``_run_ssa`` (same arguments, same result), each variable's rewrites
    confined to the blocks that name it."""
    if not blocks:
        return {}
    cfg = compute_cfg_from_blocks(blocks)
    df_plus = _ssa._iterated_domfronts(cfg)
    violators = _ssa._find_defs_violators(blocks, cfg)
    list_vars = _ssa._CacheListVars()
    scope = _ssa._get_scope(blocks)
    where = naming_blocks(blocks)
    blocks = dict(blocks)
    for varname in violators:
        blocks.update(_fix_variable(blocks, where[varname], varname, scope, cfg, df_plus,
                                    list_vars))
    if compute_cfg_from_blocks(blocks) != cfg:
        raise errors.CompilerError("CFG mutated in SSA pass")
    return blocks


run_ssa.__wrapped__ = ORIGINAL


def apply(enabled: bool = True) -> bool:
    """Use :func:`run_ssa` (``enabled``, and numba's ssa module is the one it was written
    against) or numba's own; True if :func:`run_ssa` is in use afterwards."""
    ours = enabled and source_digest(_ssa) == NUMBA_SSA
    _ssa._run_ssa = run_ssa if ours else ORIGINAL
    return applied()


def applied() -> bool:
    """Whether numba's SSA reconstruction runs :func:`run_ssa`."""
    return _ssa._run_ssa is run_ssa
