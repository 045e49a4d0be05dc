"""The numba kernels and what they need at the numba level.

Importing this package makes numba's on-disk cache safe for several processes
compiling at once (:mod:`boringbar.kernels.cache`).
"""

from boringbar.kernels.cache import lock_cache_saves

lock_cache_saves()
