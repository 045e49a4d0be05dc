"""numba's liveness analysis on bit sets instead of Python sets (compile time only).

numba recomputes the variables live at each block's entry
(numba/core/analysis.py, ``compute_live_map``) every time it post-processes a
function's IR: after each rewrite, inlining and typing pass, about 2,700 times in
the exact kernel's cold compile.  Its first fixed point (which variables reach
each block) unions Python sets of variable names along every edge; in the
kernel's inlined driver those sets hold thousands of names, and the analysis
took about 18 s of the compile.

:func:`compute_live_map` solves the same two fixed points over the same blocks in
the same order, with each set a Python integer (bit ``i`` for the ``i``-th
variable name met), so that a union or intersection is one machine-word loop in
C; it returns numba's result, a set of names per block.  Both fixed points are the
least solutions of monotone equations, so any order of iteration reaches the same
sets (``tests/test_numba_intrinsics.py`` compares the two on a function's IR).
Where numba's function is not the text this module was written against (another
numba), nothing is changed and :func:`applied` says so, and that test fails
loudly.
"""

from numba.core import analysis, ir_utils

from boringbar.kernels.numba_source import source_digest

#: SHA-256 of the source of numba 0.68's ``numba.core.analysis.compute_live_map``
NUMBA_LIVE_MAP = "713c4c094977e93b7ade48a478eb9b94168786ad9b440906b8e95b7fc0487a2a"
#: numba's own (unwrapped if this module was loaded before)
ORIGINAL = getattr(analysis.compute_live_map, "__wrapped__", analysis.compute_live_map)


class _Bits:
    """Variable names as bit positions, in the order first met."""

    def __init__(self):
        self.index: dict[str, int] = {}
        self.names: list[str] = []

    def of(self, names) -> int:
        bits = 0
        for name in names:
            i = self.index.get(name)
            if i is None:
                i = self.index[name] = len(self.names)
                self.names.append(name)
            bits |= 1 << i
        return bits

    def names_of(self, bits: int) -> set:
        out = set()
        while bits:
            low = bits & -bits
            out.add(self.names[low.bit_length() - 1])
            bits ^= low
        return out


def _reaching(order, edges, seed):
    """Least fixed point of reach[b] >= seed[b], reach[s] >= reach[b] along b -> s."""
    reach = dict.fromkeys(order, 0)
    changed = True
    while changed:
        changed = False
        for b in order:
            r = reach[b] | seed[b]
            reach[b] = r
            for s in edges[b]:
                old = reach.get(s, 0)
                if old | r != old:
                    reach[s] = old | r
                    changed = True
    return reach


def _live(order, preds, live, reach, defs):
    """Least fixed point of live[p] >= (live[b] & reach[p]) - defs[p] along p -> b."""
    changed = True
    while changed:
        changed = False
        for b in reversed(order):
            here = live[b]
            for p in preds[b]:
                old = live[p]
                new = old | (here & reach.get(p, 0) & ~defs[p])
                if new != old:
                    live[p] = new
                    changed = True
    return live


def compute_live_map(cfg, blocks, var_use_map, var_def_map):
    """numba's ``compute_live_map`` (same arguments, same result) on bit sets."""
    bits = _Bits()
    order = cfg.topo_order()
    labels = list(blocks.keys())  # the CFG's nodes: order and preds are among them
    uses = {b: bits.of(var_use_map[b]) for b in labels}
    defs = {b: bits.of(var_def_map[b]) for b in labels}
    seed = {b: uses[b] | defs[b] for b in order}
    edges = {b: [s for s, _ in cfg.successors(b)] for b in order}
    reach = _reaching(order, edges, seed)
    preds = {b: [p for p, _ in cfg.predecessors(b)] for b in order}
    live = _live(order, preds, dict(uses), reach, defs)
    return {b: bits.names_of(live[b]) for b in labels}


compute_live_map.__wrapped__ = ORIGINAL


def apply(enabled: bool = True) -> bool:
    """Use :func:`compute_live_map` (``enabled``, and numba's is the one it was written
    against) or numba's own; True if ours is in use afterwards."""
    fn = compute_live_map if enabled and source_digest(ORIGINAL) == NUMBA_LIVE_MAP else ORIGINAL
    analysis.compute_live_map = fn
    ir_utils.compute_live_map = fn
    return applied()


def applied() -> bool:
    """Whether numba's liveness analysis runs :func:`compute_live_map`."""
    return analysis.compute_live_map is compute_live_map
