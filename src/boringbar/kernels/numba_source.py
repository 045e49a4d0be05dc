"""The SHA-256 of numba's own source, by which each compile-time replacement of a numba
pass (:mod:`.inline_copy`, :mod:`.ssa_blocks`, :mod:`.live_bits`) checks that numba is
the one it was written against before it replaces anything."""

import hashlib
import inspect


def source_digest(obj) -> str:
    """SHA-256 of a module's or function's source text ('' when it has none)."""
    try:
        return hashlib.sha256(inspect.getsource(obj).encode()).hexdigest()
    except (OSError, TypeError):
        return ""
