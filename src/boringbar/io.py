"""Files out: NetCDF, JSON and figures, each written atomically.

Every writer writes to a temporary file in the destination's directory,
flushes and fsyncs it, then ``os.replace``s it onto the destination, so a
reader (or a crash) never sees a half-written file: the path holds either
the old content or the complete new one.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np

# read once at import (os.umask can only be read by setting it)
_UMASK = os.umask(0o022)
os.umask(_UMASK)


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path next to ``path``; on success move it onto ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    os.chmod(tmp, 0o666 & ~_UMASK)  # mkstemp makes 0600; give what open() would
    try:
        yield Path(tmp)
        _fsync_file(tmp)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    fsync_dir(path.parent)


def remove_stale_temporaries(folder) -> list[Path]:
    """Delete what :func:`atomic_path` left in ``folder`` when its process was killed
    mid-write (``.NAME.XXXXXXXX.tmp``); call it only where no other writer is at work.
    Returns the paths removed."""
    stale = sorted(Path(folder).glob(".*.tmp"))
    for p in stale:
        with contextlib.suppress(FileNotFoundError):
            p.unlink()
    return stale


def _fsync_file(path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def fsync_dir(path) -> None:
    """fsync the directory ``path``: makes a rename in it durable (not possible on
    every platform; silently skipped there)."""
    with contextlib.suppress(OSError):
        _fsync_file(path)


def write_netcdf_atomic(ds, path) -> Path:
    """Write the xarray Dataset ``ds`` to ``path`` (NetCDF4) atomically."""
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp)
    return Path(path)


def jsonable(obj):
    """``obj`` with numpy scalars/arrays as Python values and NaN/inf as None
    (strict JSON has no NaN)."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, Path):
        return str(obj)
    return obj


def write_json_atomic(obj, path) -> Path:
    """Write ``obj`` as indented, strict JSON (see :func:`jsonable`) atomically."""
    text = json.dumps(jsonable(obj), indent=2, allow_nan=False) + "\n"
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def save_figure_atomic(fig, path, **savefig_kw) -> Path:
    """Save the matplotlib Figure ``fig`` to ``path`` atomically; the format
    comes from the suffix of ``path`` (PNG if it has none)."""
    fmt = Path(path).suffix.lstrip(".").lower() or "png"
    savefig_kw.setdefault("dpi", 150)
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        fig.savefig(f, format=fmt, **savefig_kw)
    return Path(path)
