"""A tiny cached numba function for tests/test_compile_cache.py, importable by spawned processes.

Each process sets ``NUMBA_CACHE_DIR`` (inherited from the test) before numba is
imported, so every run starts from an empty cache directory of its own.
"""

import numba
import numpy as np
from numba import njit
from numba.core import event

from boringbar.kernels import cache

#: the argument each signature is compiled for (one numba type each)
SAMPLES = (np.int64(3), np.int32(3), np.int16(3), np.int8(3), np.uint64(3), np.uint32(3),
           np.uint16(3), np.uint8(3), np.float64(3), np.float32(3), np.complex128(3),
           np.complex64(3))


@njit(cache=True)
def probe(x):
    return x * 2 + 1


def compile_one(i, locked, barrier):
    """Compile :func:`probe` for ``SAMPLES[i]`` once ``barrier`` lets every process go;
    True if this process compiled it (not loaded it)."""
    cache.lock_cache_saves(locked)
    barrier.wait()
    with event.install_recorder("numba:compile") as rec:
        assert probe(SAMPLES[i]) == SAMPLES[i] * 2 + 1
    return bool(rec.buffer)


def load_all():
    """For each sample, in a fresh process: (compiled instead of loaded, result right)."""
    out = []
    for x in SAMPLES:
        with event.install_recorder("numba:compile") as rec:
            y = probe(x)
        sigs = [cres.signature.args for cres in probe.overloads.values()]
        right = y == x * 2 + 1 and sigs[-1] == (numba.typeof(x),)
        out.append((bool(rec.buffer), bool(right)))
    return out
