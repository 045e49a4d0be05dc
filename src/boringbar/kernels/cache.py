"""Concurrent cold-cache compilation by several processes, made safe.

Every kernel is compiled with ``cache=True``: numba writes each compiled
signature of a function to a data file (``*.nbc``) and keeps one index per
function (``*.nbi``) naming the data file of each signature
(numba/core/caching.py, ``IndexDataCacheFile``).  Saving a signature reads the
index, takes the first free file number, rewrites the index and then writes the
data file, without a lock.  Two processes saving different signatures of one
function at the same moment (the sweep's workers, the test workers,
:func:`boringbar.kernels.compile.compile_all`'s processes) would both take the
same number: one entry is lost (compiled again later) and the index may name
the other signature's code for it.  Each file is replaced atomically, so one
signature saved by two processes at once is harmless, and so is reading while
another process saves.

:func:`lock_cache_saves` wraps ``IndexDataCacheFile.save`` in an exclusive
``flock`` on ``<index>.lock`` beside the index; ``boringbar.kernels`` applies it
when it is imported.  Where there is no ``fcntl`` (Windows) or numba's layout
differs, saves stay as numba makes them (tests/test_compile_cache.py fails
loudly on the latter).
"""

import functools

try:
    import fcntl
except ImportError:  # Windows: no flock; numba as it is
    fcntl = None

from numba.core import caching

#: numba's own save (unwrapped if this module was loaded before: a second lock on the
#: same file from one process would wait for itself)
_ORIGINAL_SAVE = getattr(caching.IndexDataCacheFile.save, "_boringbar_unlocked",
                         caching.IndexDataCacheFile.save)


def _locked_save(self, key, data):
    index = getattr(self, "_index_path", None)
    if index is None or fcntl is None:
        return _ORIGINAL_SAVE(self, key, data)
    with open(index + ".lock", "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        return _ORIGINAL_SAVE(self, key, data)


functools.update_wrapper(_locked_save, _ORIGINAL_SAVE)
_locked_save._boringbar_unlocked = _ORIGINAL_SAVE


def lock_cache_saves(enabled: bool = True) -> bool:
    """Serialise numba's cache saves across processes (``enabled``) or restore numba's own
    (tests only).  Returns whether saves are locked."""
    caching.IndexDataCacheFile.save = _locked_save if enabled else _ORIGINAL_SAVE
    return cache_saves_locked()


def cache_saves_locked() -> bool:
    """Whether numba's cache saves go through the lock of this module."""
    return fcntl is not None and caching.IndexDataCacheFile.save is _locked_save
