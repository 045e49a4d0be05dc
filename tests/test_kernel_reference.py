"""The integrator kernels reproduce the stored reference outputs bit for bit.

tests/data/kernel_reference.npz holds the inputs and outputs of the compiled core for
the cases of tests/kernel_reference.py (the published harmonic grid with both
integrators, cuts, every bar, friction law, record and batch size).  The core was
confirmed bit-identical to the numba kernels of commit fb3fab0 before the reference
was regenerated from it.
Each case is replayed through the entry points imported in kernel_reference.py (an
exact case given its stored preparation, the regimes' LAPACK eigen-decomposition) and
every output array (final state, metrics, history, impacts, sticks, strobe, and the
exact integrator's time reached) must equal the stored one bit for bit; a failure
names the case, the array, how many entries differ and the largest absolute and
relative difference.  The preparation itself must agree with the stored one within
LAPACK's roundings, which depend on the CPU (kernel_reference.py).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import kernel_reference as kr
import numpy as np
import pytest

from boringbar.simulate import layout as L
from boringbar.simulate.kernels import impact_mass, prepare
from boringbar.simulate.regimes import setup_fields, system_regimes

NAMES = kr.names()


@pytest.fixture(scope="module")
def reference():
    return kr.load(), kr.met_names()


def test_the_reference_covers_every_entry_point(reference):
    cases, _ = reference
    entries = {str(c["entry"]) for c in cases.values()}
    assert entries == {"rk4", "rk4_batch", "exact"}


def test_the_stored_impact_masses_are_the_cores_carrying_term(reference):
    """Every stored ball's m_eff (p[M_EFF]) is the inverse of the core's carrying term at
    the full share, bit for bit, as the packing computes it now: the reference's inputs
    are what simulate packs (229 parameter vectors; a changed rounding of the carrying term
    would move every impacting run's bits)."""
    cases, _ = reference
    checked = 0
    for name, case in cases.items():
        P = kr.current_params(case["P" if "P" in case else "p"], case["_param_names"])
        for p in np.atleast_2d(P):
            if p[L.BALL_MASS] > 0 and int(p[L.CASE]) in (L.BALL, L.LOCKED):
                assert impact_mass(p) == p[L.M_EFF], name
                checked += 1
    assert checked > 200


@pytest.mark.parametrize("name", NAMES)
def test_kernel_reproduces_the_reference(name, reference):
    """An exact case is given its stored preparation: LAPACK's roundings are not the
    core's (kernel_reference.py says why), and prepare(p) has its own test below."""
    cases, slots = reference
    case = cases[name]
    got = kr.replay(case, stored_prep=str(case["entry"]) == "exact")
    problems = kr.differences(name, case, got, slots)
    if problems:  # the messages alone: a traceback would print the whole reference
        pytest.fail("\n".join(problems), pytrace=False)


#: how far prepare(p) may be from the stored one (kr.prep_differences): the largest seen
#: between OpenBLAS's Haswell and SkylakeX kernels is 1e-11 (bq, four modes), while a
#: real change of the setup moves entries by their own size
PREP_TOLERANCE = 1e-9


#: prepare(p)'s arrays that LAPACK computes (the eigen-decomposition); the rest follows
#: from them by the package's and the core's own arithmetic
LAPACK_KEYS = ("lam", "V", "Vi")


def test_prepare_agrees_with_the_stored_preparation(reference):
    """prepare(p) of every exact case is the stored one within LAPACK's roundings and the
    eigenvectors' phases, and where LAPACK gives the stored eigen-decomposition bit for
    bit (every case with the reference's OpenBLAS kernels, 44 of 106 with others), the
    rest of it is the stored bits too (the core's forcing setup among it); with its
    system's part computed (the memo emptied first) and kept (the second call)."""
    cases, _ = reference
    system_regimes.cache_clear()
    bad = []
    for name, case in cases.items():
        if str(case["entry"]) != "exact":
            continue
        stored = kr.stored_prep_of(case)
        for call in ("first", "second"):
            got = setup_fields(prepare(kr.current_params(case["p"], case["_param_names"])))
            bad += [f"{name} ({call} call): {k} differs by {d:.2e}"
                    for k, d in kr.prep_differences(stored, got).items()
                    if not d <= PREP_TOLERANCE]
            if all(kr.same_bits(got[k], stored[k]) for k in LAPACK_KEYS):
                bad += [f"{name} ({call} call): {k} is not the stored bits, though LAPACK's "
                        "eigen-decomposition is" for k, v in stored.items()
                        if not kr.same_bits(got[k], v)]
    assert not bad, "\n".join(bad)


def _haswell_kernels_available() -> bool:
    """NumPy's BLAS is OpenBLAS and the CPU can run its Haswell kernels (AVX2, FMA)."""
    try:
        flags = Path("/proc/cpuinfo").read_text().split()
    except OSError:
        return False
    return ("avx2" in flags and "fma" in flags
            and any(k.startswith("openblas ") for k in kr.blas_kernels()))


@pytest.mark.skipif(not _haswell_kernels_available(),
                    reason="needs NumPy's OpenBLAS on an x86-64 CPU with AVX2 and FMA")
def test_with_the_capture_s_blas_kernels_every_run_is_the_stored_bits_as_simulate_runs_it():
    """With OpenBLAS's Haswell kernels, those of the capture, every case replays bit for
    bit with its exact runs preparing themselves, as simulate's calls do: the package's
    setup arithmetic held to its bits on any CPU that can run those kernels."""
    env = {**os.environ, "OPENBLAS_CORETYPE": "Haswell"}
    out = subprocess.run([sys.executable, str(Path(kr.__file__)), "--as-simulate"], env=env,
                         capture_output=True, text=True, timeout=600)
    assert "BLAS: openblas Haswell;" in out.stdout, out.stdout + out.stderr[-2000:]
    assert out.returncode == 0, out.stdout[-4000:]
