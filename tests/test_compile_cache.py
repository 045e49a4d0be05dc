"""Several processes compiling one cached numba function at once (kernels/cache.py)."""

import multiprocessing as mp
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor

import pytest
from numba.core import caching

from boringbar.kernels import cache


def _race(tmp_path, monkeypatch, locked):
    """Every signature of tests/cache_probe.py's function compiled by its own process, all
    at once, into an empty cache; then what a fresh process finds in the cache."""
    import cache_probe  # tests/ is on sys.path (rootdir conftest); spawned processes inherit it

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba-cache"))
    ctx = mp.get_context("spawn")
    n = len(cache_probe.SAMPLES)
    with ctx.Manager() as manager:
        barrier = manager.Barrier(n)
        with ProcessPoolExecutor(n, mp_context=ctx) as pool:
            compiled = list(pool.map(cache_probe.compile_one, range(n), [locked] * n,
                                     [barrier] * n))
    assert all(compiled)  # each process compiled its signature (the cache was empty)
    with ProcessPoolExecutor(1, mp_context=ctx) as pool:
        return pool.submit(cache_probe.load_all).result()


def cache_probe_samples():
    import cache_probe

    return [type(x).__name__ for x in cache_probe.SAMPLES]


def test_the_package_locks_numba_cache_saves():
    assert cache.cache_saves_locked()
    # the layout the lock relies on (numba/core/caching.py); a numba that changes it fails here
    assert hasattr(caching.IndexDataCacheFile, "save")
    assert caching.IndexDataCacheFile.save.__wrapped__ is cache._ORIGINAL_SAVE
    f = caching.IndexDataCacheFile("/nonexistent", "f-1.py311", ("stamp", 0))
    assert f._index_path.endswith("f-1.py311.nbi")


def test_concurrent_cold_compiles_all_land_in_the_cache(tmp_path, monkeypatch):
    loaded = _race(tmp_path, monkeypatch, locked=True)
    assert loaded == [(False, True)] * len(loaded), loaded  # every signature loads, none compiles


@pytest.mark.slow
def test_without_the_lock_concurrent_compiles_lose_entries(tmp_path, monkeypatch):
    """numba's own saves, raced as above: entries are lost (compiled again) or name another
    signature's code.  A race: it shows in most runs, not in all (slow: not by default)."""
    for k in range(5):
        loaded = _race(tmp_path / str(k), monkeypatch, locked=False)
        bad = [s for s, (c, ok) in zip(cache_probe_samples(), loaded, strict=True) if c or not ok]
        print(f"round {k}: {len(bad)} of {len(loaded)} signatures not loaded right: {bad}")
        if bad:
            return
    pytest.fail("five unlocked races lost nothing")


_CALLER = '''
from numba import njit
from probe_tree.helper import value

@njit(cache=True)
def f():
    return value()
'''
_HELPER = '''
from numba import njit

@njit(cache=True, inline="always")
def value():
    return {}
'''
_RUN = '''
import sys
from pathlib import Path
from boringbar.kernels import cache
root = Path(sys.argv[1])
if sys.argv[2] == "stamped":
    assert cache.stamp_tree(cache.tree_locators(root / "probe_tree"))
sys.path.insert(0, str(root))
from probe_tree.caller import f
print(f(), f.stats.cache_hits and 1 or 0)
'''


def _probe(root, mode):
    out = subprocess.run([sys.executable, "-c", _RUN, str(root), mode], capture_output=True,
                         text=True, check=True).stdout.split()
    return int(out[0]), int(out[1])  # the value, whether it came from the cache


@pytest.mark.parametrize("mode", ["stamped", "numba"])
def test_an_edit_to_an_inlined_helper_reaches_its_callers_cache(tmp_path, mode):
    """numba stamps a cached function with its own file only: after an edit to an inlined
    helper in another file, the caller loads its old code (``numba``).  The tree's stamp
    (kernels/cache.py, on for every kernel) compiles it again (``stamped``)."""
    pkg = tmp_path / "probe_tree"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "caller.py").write_text(_CALLER)
    (pkg / "helper.py").write_text(_HELPER.format(1))
    assert _probe(tmp_path, mode) == (1, 0)  # compiled
    assert _probe(tmp_path, mode) == (1, 1)  # loaded from the cache
    (pkg / "helper.py").write_text(_HELPER.format(2))
    assert _probe(tmp_path, mode) == ((2, 0) if mode == "stamped" else (1, 1))


def test_every_kernel_is_stamped_with_the_kernel_tree():
    assert cache.tree_stamped()  # importing boringbar.kernels put the locators first
    assert [c.__name__ for c in cache.SALTED] == [
        "TreeUserProvidedCacheLocator", "TreeInTreeCacheLocator", "TreeUserWideCacheLocator"]
    from boringbar.kernels.core import count_impact

    locator = caching.FunctionCache(count_impact.py_func)._impl.locator
    assert type(locator) in cache.SALTED
    assert locator.get_source_stamp()[1] == cache.tree_stamp()
