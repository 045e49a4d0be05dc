"""The integrator kernels reproduce the stored reference outputs bit for bit.

tests/data/kernel_reference.npz holds the inputs and outputs of the compiled core for
the cases of tests/kernel_reference.py (the published harmonic grid with both
integrators, cuts, every bar, friction law, record and batch size).  The core was
confirmed bit-identical to the numba kernels of commit fb3fab0 before the reference
was regenerated from it.
Each case is replayed through the entry points imported in kernel_reference.py and
every output array (final state, metrics, history, impacts, sticks, strobe, and the
exact integrator's time reached) must equal the stored one bit for bit; a failure
names the case, the array, how many entries differ and the largest absolute and
relative difference.
"""

from __future__ import annotations

import kernel_reference as kr
import numpy as np
import pytest

from boringbar.simulate.kernels import prepare
from boringbar.simulate.regimes import system_regimes

NAMES = kr.names()


@pytest.fixture(scope="module")
def reference():
    return kr.load(), kr.met_names()


def test_the_reference_covers_every_entry_point(reference):
    cases, _ = reference
    entries = {str(c["entry"]) for c in cases.values()}
    assert entries == {"rk4", "rk4_batch", "exact"}


@pytest.mark.parametrize("name", NAMES)
def test_kernel_reproduces_the_reference(name, reference):
    cases, slots = reference
    case = cases[name]
    problems = kr.differences(name, case, kr.replay(case), slots)
    if problems and str(case["entry"]) == "exact":
        problems.append(_with_stored_prep(name, case, slots))
    if problems:  # the messages alone: a traceback would print the whole reference
        pytest.fail("\n".join(problems), pytrace=False)


def _with_stored_prep(name: str, case: dict, slots) -> str:
    """Whether the exact kernel given the stored prepare(p) reproduces the reference:
    tells a change of the preparation (LAPACK) from a change of the kernel."""
    rest = kr.differences(name, case, kr.replay(case, stored_prep=True), slots)
    verdict = "reproduces the reference" if not rest else f"still differs ({len(rest)} arrays)"
    return f"{name}: given the stored prepare(p), the kernel {verdict}"


def test_prepare_reproduces_the_stored_preparation(reference):
    """prepare(p) of every exact case equals the stored prep_* bit for bit, with its
    system's part computed (the memo emptied first) and kept (the second call)."""
    cases, _ = reference
    system_regimes.cache_clear()
    bad = []
    for name, case in cases.items():
        if str(case["entry"]) != "exact":
            continue
        stored = kr.stored_prep_of(case)
        for call in ("first", "second"):
            got = prepare(kr.current_params(case["p"], case["_param_names"]))
            bad += [f"{name} ({call} call): {k}" for k, v in stored.items()
                    if np.asarray(got[k]).dtype != np.asarray(v).dtype
                    or np.asarray(got[k]).tobytes() != np.asarray(v).tobytes()]
    assert not bad, "\n".join(bad)
