"""kernels/compile.py: the notice before a long compile, and the list compile_all works through."""

import io
import os
import subprocess
import sys

import pytest
from numba import types
from numba.core import compiler, event, ir
from numba.core.inline_closurecall import InlineWorker
from numba.core.registry import cpu_target

from boringbar.cli.main import main
from boringbar.kernels import compile as C
from boringbar.kernels import rk4, rk4_batch
from boringbar.kernels.exact import driver


def test_specs_name_every_specialisation_once():
    names = [s.name for s in C.specs()]
    assert len(names) == len(set(names)) == 2 + 6 + 13 * len(rk4_batch.LANES)
    assert [s.kind for s in C.specs(["rk4"])] == ["rk4"] * 6
    with pytest.raises(ValueError):
        C.specs(["rk5"])


def test_every_dispatched_kernel_maps_to_a_spec():
    """The kernels run_rk4 and run_rk4_batch dispatch to are the ones compile_all compiles."""
    known = set(C.specs())
    singles = [*rk4._BY_MODES.values(), *rk4._BALL_BY_MODES.values(), rk4._rk4_any]
    assert {C._spec_of(d, ()) for d in singles} == set(C.specs(["rk4"]))
    for size in rk4_batch.LANES:
        lanes = (types.UniTuple(types.int64, size),)
        for d in [*rk4_batch._SPECIALISED.values(), rk4_batch._b_any]:
            assert C._spec_of(d, lanes) in known
    assert C._spec_of(None, ()) is None
    # the exact integrator's two kernels, harmonic and cut (kernels/exact/driver.py)
    assert {C._spec_of(d, ()) for d in (driver._exact, driver._exact_cut)} == set(
        C.specs(["exact"]))


def _untyped_globals(dispatcher) -> set[str]:
    """The names of the globals in ``dispatcher``'s IR after numba's untyped passes (its
    inlining and dead-branch pruning among them), as numba runs them to inline it."""
    tyctx, tgctx = cpu_target.typing_context, cpu_target.target_context
    flags = compiler.Flags()
    pipeline = compiler.Compiler(tyctx, tgctx, None, None, None, flags, None)
    worker = InlineWorker(tyctx, tgctx, {}, pipeline, flags, None)
    func_ir = worker.run_untyped_passes(dispatcher.py_func, enable_ssa=True)
    return {getattr(st.value.value, "__name__", "") for blk in func_ir.blocks.values()
            for st in blk.find_insts(ir.Assign) if isinstance(st.value, (ir.Global, ir.FreeVar))}


def test_the_harmonic_exact_kernel_leaves_the_cuts_code_out():
    """The exact kernel of harmonic runs is the shared body with ``regen`` a constant
    False, and numba prunes a cut's code before typing it (10-16 % of the cold compile,
    docs/performance.md): the cut's knots, surface and flows are gone from its IR, while
    the harmonic segment integrals are there.  A ``regen`` that stops being a constant
    (read from an argument, say) fails this."""
    names = _untyped_globals(driver._exact)
    assert {"segment_integrals", "segment_integrals_1", "wall_step"} <= names
    assert not names & {"add_knot", "_cut_segment", "_cut_flows", "quad_cut", "surface_piece"}


def _fire(dispatcher, args=()):
    with event.trigger_event("numba:compile", data={"dispatcher": dispatcher, "args": args,
                                                     "return_type": None}):
        pass


def test_announce_prints_one_line_at_the_first_kernel_compile_only():
    out = io.StringIO()
    with C.announce(out):
        pass  # nothing compiled: nothing printed
    assert out.getvalue() == ""
    with C.announce(out):
        _fire(rk4._rk4_ball2)
        _fire(rk4._rk4_n1)  # nested or later compiles in the same call: no second line
    lines = out.getvalue().splitlines()
    assert lines == [C.notice(C.Spec("rk4", 2, "ball"))]
    assert lines[0].startswith("boringbar: compiling the RK4 kernel (2 modes, ball damper) "
                               "(first use on this machine, about ")
    _fire(rk4._rk4_ball2)  # outside announce: nothing
    assert len(out.getvalue().splitlines()) == 1


def test_announce_is_silenced_by_notices_off():
    out = io.StringIO()
    C.notices(False)
    try:
        with C.announce(out):
            _fire(rk4._rk4_ball2)
    finally:
        C.notices(True)
    assert out.getvalue() == ""


def test_notice_durations():
    assert C.notice(C.Spec("exact")).endswith(" min; cached afterwards)")
    assert "the exact integrator for cuts" in C.notice(C.Spec("exact", case="cut"))
    assert C._duration(9.0) == "10 s" and C._duration(1.0) == "5 s"
    assert C._duration(170) == "3 min"


@pytest.mark.slow
def test_a_cold_compile_announces_and_a_cached_load_does_not(tmp_path):
    """End to end in fresh processes on an empty cache: the 1-mode RK4 kernel compiles with
    one notice, then loads from the cache silently."""
    code = ("import sys; from boringbar.kernels import compile as C\n"
            "with C.announce(): r = C.compile_one(C.Spec('rk4', 1, 'ball'))\n"
            "print(r.status)")
    env = {"NUMBA_CACHE_DIR": str(tmp_path), "PATH": "/usr/bin:/bin"}
    runs = [subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           env=env, timeout=600) for _ in range(2)]
    assert [r.stdout.strip() for r in runs] == ["compiled", "cached"], runs[0].stderr
    assert runs[0].stderr.splitlines() == [C.notice(C.Spec("rk4", 1, "ball"))]
    assert runs[1].stderr == ""


def test_every_specialisation_has_a_measured_estimate():
    assert set(C.ESTIMATE_S) == {s.name for s in C.specs()}


_BACKGROUND = """
import io, sys, time
from boringbar.kernels import compile as C
spec = C.Spec("rk4", 1)
assert not C.await_background(spec)  # none started
C.compile_in_background(spec)
C.compile_in_background(spec)  # once
out = io.StringIO()
tic = time.perf_counter()
ok = C.await_background(spec, stream=out)
here = C.compile_one(spec)  # compiles if the background did not put it in the cache
print(ok, here.status, bool(out.getvalue()), round(time.perf_counter() - tic, 1))
"""


def test_a_background_compile_is_awaited_and_the_kernel_then_loads(tmp_path):
    """On an empty cache, a kernel compiled in another process (as ``boringbar paper``
    compiles the exact kernel while its first steps run) is waited for, with a line that
    says so, and then loads from the cache instead of compiling a second time."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    out = subprocess.run([sys.executable, "-c", _BACKGROUND], capture_output=True, text=True,
                         env=env, timeout=600)
    assert out.returncode == 0, out.stderr
    ok, status, said, _ = out.stdout.split()
    assert (ok, status, said) == ("True", "cached", "True")


def test_a_quiet_command_line_leaves_the_notices_as_they_were(tmp_path):
    """``--quiet`` silences the compile notice for its own command only: main() run in
    process (the tests, a notebook) must not silence every later announce."""
    from boringbar.cli.main import main

    assert main(["modes", "--out", str(tmp_path), "--quiet"]) == 0
    assert C.notices(True) is True  # as before the call
