"""The numba kernels and what they need at the numba level.

Importing this package makes numba's on-disk cache safe for several processes
compiling at once and stale after an edit to any kernel file
(:mod:`boringbar.kernels.cache`), and its inliner's copies of
the inlined IR linear in its size (:mod:`boringbar.kernels.inline_copy`), and its SSA
reconstruction confined to the blocks that name each variable
(:mod:`boringbar.kernels.ssa_blocks`) and its liveness analysis on bit sets
(:mod:`boringbar.kernels.live_bits`).
"""

from boringbar.kernels import inline_copy, live_bits, ssa_blocks
from boringbar.kernels.cache import lock_cache_saves, stamp_tree

lock_cache_saves()
stamp_tree()
inline_copy.apply()
ssa_blocks.apply()
live_bits.apply()
