"""The package's small dense linear algebra runs on one BLAS thread.

Its matrices have a few to a few hundred rows: the bar's finite-element eigenproblem (about
90 degrees of freedom), the exact integrator's regimes and shooting's Jacobians (7 x 7 to
9 x 9). On such sizes a multithreaded BLAS (OpenBLAS, as NumPy and SciPy ship it) only wakes
its thread pool to spin: a new system and its first exact run take less wall time and less
CPU with one thread than with OpenBLAS's own, most of all beside a busy process, as in a
sweep's workers or under the design page's server (``benchmarks/bench_make_system.py``; its
figures in docs/performance.md). 15 continuation points took 18.8 s against 1.46 s on a
loaded machine (docs/continuation.md). The chatter orbits' correctors factorise up to 1700
unknowns densely, where OpenBLAS's second thread gains no wall time and spins a core: a
40-point branch took 3.2 s with one thread and 3.2-3.4 s with two idle, 3.4 s against
5.5-6.5 s beside a busy process. The limit holds only inside the decorated calls, so a
user's own large products keep their threads.
"""

from __future__ import annotations

from threadpoolctl import threadpool_limits

#: run the decorated function with the BLAS libraries loaded at the call limited to one thread
one_blas_thread = threadpool_limits.wrap(limits=1, user_api="blas")

__all__ = ["one_blas_thread"]
