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

numba's cache also checks only the source file of the function it compiled
(``get_source_stamp``: the file's SHA-256), not the files of the functions it
calls or inlines: after an edit to ``core.py``, or an upgrade that changes it,
the kernels that use it would load their old machine code.  The locators of
:func:`stamp_tree` add one more stamp to every kernel under
``boringbar/kernels``: the SHA-256 of every source file there, so a change to
any of them compiles every kernel again.
"""

import functools
import hashlib
import os
from pathlib import Path

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


#: the kernels' source tree, whose every file a kernel's cache entry depends on
KERNEL_TREE = Path(__file__).resolve().parent


def tree_stamp(root: Path = KERNEL_TREE) -> str:
    """SHA-256 of every ``.py`` file under ``root`` (names and contents, in sorted order)."""
    stats = tuple((str(f), f.stat().st_mtime_ns, f.stat().st_size)
                  for f in sorted(root.rglob("*.py")))
    return _hash_files(stats, str(root))


@functools.lru_cache(maxsize=8)
def _hash_files(stats, root):
    h = hashlib.sha256()
    for name, _, _ in stats:
        h.update(os.path.relpath(name, root).encode() + b"\0")
        h.update(Path(name).read_bytes())
    return h.hexdigest()


def _in_tree(py_file, root: Path) -> bool:
    try:
        return Path(py_file).resolve().is_relative_to(root)
    except (OSError, TypeError, ValueError):
        return False


def _salted(base, root: Path):
    """``base`` (a numba locator) for the files under ``root`` only, stamped with the tree's
    stamp too."""

    class Salted(base):
        @classmethod
        def from_function(cls, py_func, py_file):
            if not _in_tree(py_file, root):
                return None
            return super().from_function(py_func, py_file)

        def get_source_stamp(self):
            return (super().get_source_stamp(), tree_stamp(root))

    Salted.__name__ = Salted.__qualname__ = f"Tree{base.__name__}"
    return Salted


#: numba's file-backed locators, in numba's order
_BASES = tuple(c for c in (getattr(caching, n, None) for n in (
    "UserProvidedCacheLocator", "InTreeCacheLocator", "UserWideCacheLocator"))
    if c is not None)


def tree_locators(root: Path) -> tuple:
    """numba's file-backed locators for the functions under ``root``, each stamped with
    :func:`tree_stamp` of ``root`` besides the function's own file."""
    return tuple(_salted(c, root) for c in _BASES)


#: the kernels' locators
SALTED = tree_locators(KERNEL_TREE)


def stamp_tree(locators: tuple = SALTED) -> bool:
    """Put ``locators`` first among numba's cache locators (once).  Returns whether they are
    in place (False where numba's layout differs: tests/test_compile_cache.py fails
    loudly then)."""
    impl = getattr(caching, "CacheImpl", None)
    if impl is None or len(_BASES) != 3 or not isinstance(
            getattr(impl, "_locator_classes", None), list):
        return False
    if not any(c in locators for c in impl._locator_classes):
        impl._locator_classes[:0] = locators
    return tree_stamped(locators)


def tree_stamped(locators: tuple = SALTED) -> bool:
    """Whether numba's cache locators include all three of ``locators``."""
    classes = getattr(getattr(caching, "CacheImpl", None), "_locator_classes", [])
    return all(c in classes for c in locators) and len(locators) == 3
