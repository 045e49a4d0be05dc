"""The Poincare strobe's interpolation inside a step, with its roundings pinned.

Both RK4 kernels (``rk4.py``, one run; ``rk4_batch.py``, a batch in
lock-step) interpolate the tip at a strobe time inside a step: W and W' by
the cubic Hermite on the step's end values, the ball's (or absorber's)
displacement and velocity linearly.  Under ``fastmath={"contract"}`` LLVM
may fuse any ``a * b + c`` into one fused multiply-add, and which product
it fuses depends on the code around the expression, so the same expression
in the two kernels could round differently.  Here every multiply-add is an
explicit ``fma`` and no plain product feeds a sum, so the result is the
same wherever these functions are inlined.
"""

from numba import njit, types
from numba.extending import intrinsic


@intrinsic
def fma(typingctx, a, b, c):
    """a * b + c rounded once (llvm.fma)."""
    def codegen(context, builder, signature, args):
        return builder.fma(*args)

    return types.float64(types.float64, types.float64, types.float64), codegen


@njit(cache=True, error_model="numpy", fastmath={"contract"}, inline="always")
def hermite(s, dt, w0, wd0, w1, wd1):
    """(W, W') at s in [0, 1] of a step of ``dt`` from (w0, wd0) to (w1, wd1)."""
    s2 = s * s
    s3 = s2 * s
    h00 = fma(2.0, s3, -(3.0 * s2)) + 1.0  # 2 s^3 - 3 s^2 + 1
    h10 = fma(-2.0, s2, s3) + s  # s^3 - 2 s^2 + s
    h01 = fma(-2.0, s3, 3.0 * s2)  # -2 s^3 + 3 s^2
    h11 = s3 - s2
    w = fma(h11 * dt, wd1, fma(h01, w1, fma(h10 * dt, wd0, h00 * w0)))
    g = fma(6.0, s2, -(6.0 * s)) / dt  # (6 s^2 - 6 s) / dt
    d0 = fma(3.0, s2, -(4.0 * s)) + 1.0  # 3 s^2 - 4 s + 1
    d1 = fma(3.0, s2, -(2.0 * s))  # 3 s^2 - 2 s
    wd = fma(d1, wd1, fma(d0, wd0, g * (w0 - w1)))
    return w, wd


@njit(cache=True, error_model="numpy", fastmath={"contract"}, inline="always")
def lerp(s, a0, a1):
    """(1 - s) a0 + s a1."""
    return fma(1.0 - s, a0, s * a1)
