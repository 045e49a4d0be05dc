"""How the suite shares the cores: ``pytest`` runs ``-n 2 --dist loadscope`` (pyproject.toml).

Most of a run from a fresh clone is numba compiling: each specialisation of a
kernel (``cache=True``: src/boringbar/kernels/__pycache__) compiles once, in the
first process that needs it, and every later process loads it from disk.
Measured cold (CPU seconds, kernels/compile.py ESTIMATE_S, 2026-11-24, with the
inliner fix of kernels/inline_copy.py): the exact kernel 100 s (212 s measured again on
2026-11-25, 112-120 s once numba's SSA, liveness and inlining were made linear, then
two kernels, harmonic and cut, of about 90 s each: docs/performance.md); the lock-step
batch kernels (one per mode count, case and batch size, kernels/rk4_batch.py)
6-9 s each; the single-run RK4 kernels 5-10 s each; the runs themselves about
220 s, of which test_paper's quick study 90 s.

The two workers take work in groups (:func:`kernel_group`), one group at a time
and in the order of ``ORDER``, so that the tests sharing specialisations compile
them once, on one worker, while the other worker compiles others: the one-mode
batch kernels, the two-mode batch kernels and the exact integrator's two kernels
(harmonic, and cuts) each have a group; test_paper's study, which reuses most
batch kernels, comes after them.
A test not named here runs with the rest of its module (``--dist loadscope``;
module fixtures are then built once).  pytest-xdist's own ``xdist_group`` marks
are not used: with pytest 9.2 they no longer group (pytest-xdist issue 1386).
"""

import pytest

import boringbar.kernels  # noqa: F401  locks numba's cache saves across the workers (kernels/cache.py)

ONE_MODE, TWO_MODES = "rk4-batch-1-mode", "rk4-batch-2-modes"
EXACT, EXACT_CUT = "exact", "exact-cut"
#: the groups in the order the workers take them; then the other modules, in file order
ORDER = (EXACT, EXACT_CUT, TWO_MODES, ONE_MODE, "test_paper.py", "test_kernel.py",
         "test_chatter.py")
#: modules whose tests all join a group
MODULE_GROUPS = {
    "test_basins.py": ONE_MODE,
    "test_cli.py": TWO_MODES,
    "test_cli_nonlinear.py": TWO_MODES,
    "test_runner.py": TWO_MODES,
    "test_exact.py": EXACT,
    "test_exact_regen.py": EXACT_CUT,
}
#: single tests that join another group than their module's
TEST_GROUPS = {
    "test_runner.py::test_exact_integrator_study_equals_the_in_process_sweep": EXACT,
}


def kernel_group(nodeid: str) -> str:
    """The group of the test ``nodeid`` (tests/test_x.py::test_y[params])."""
    path, _, test = nodeid.partition("::")
    module = path.rsplit("/", 1)[-1]
    key = f"{module}::{test.split('[')[0]}"
    if key in TEST_GROUPS:
        return TEST_GROUPS[key]
    if module == "test_batch.py":  # the two-mode runs are test_batch's physical-preset ones
        return TWO_MODES if "physical-2" in test else ONE_MODE
    return MODULE_GROUPS.get(module, module)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadscope`` with :func:`kernel_group` for scope, groups taken in collection
    order (sorted by ``ORDER`` in :func:`pytest_collection_modifyitems`)."""
    if config.getvalue("dist") != "loadscope":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class KernelGroups(LoadScopeScheduling):
        def _split_scope(self, nodeid):
            return kernel_group(nodeid)

    config.option.loadscopereorder = False  # ORDER, not the groups with most tests first
    return KernelGroups(config, log)


def pytest_collection_modifyitems(items):
    rank = {g: i for i, g in enumerate(ORDER)}
    keyed = sorted(enumerate(items), key=lambda ix: (
        rank.get(kernel_group(ix[1].nodeid), len(ORDER)), ix[0]))
    items[:] = [item for _, item in keyed]
