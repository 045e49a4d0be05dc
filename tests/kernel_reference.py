"""Reference inputs and outputs of the integrator kernels: the core's bits, kept.

``tests/data/kernel_reference.npz`` holds, for each case of :func:`case_builders`
(219 of them: the 80 published harmonic cases with each integrator, regenerative cuts,
every bar, friction law, a rolling ball, record and batch size), the exact arguments one
kernel entry point was called with and everything the call wrote.  It is the compiled core's output;
before it was first written from the core, the core was confirmed to reproduce the
previous reference (captured at commit fb3fab0, before the C++ port) bit for bit.  For a
case named ``NAME`` the file has

- ``NAME/entry``: the entry point, "rk4", "rk4_batch" or "exact";
- the inputs: ``NAME/p`` (``NAME/P`` for a batch, one row a run), ``NAME/x0``, the
  scalar arguments as 0-d arrays (rk4: t0, dt, n_steps, steady_start, rec_every;
  rk4_batch: t0, dt, n_steps, steady_start; exact: t0, t_end, t_steady, rec_dt, dt),
  the shapes of the zeroed output arrays (``NAME/rec_shape``, ``imp_shape``,
  ``stick_shape``, ``strobe_shape``, and ``buf_shape``, a cut's delay history, for
  rk4) and the initial metric vector ``NAME/met0``;
- the outputs, ``NAME/out_x`` (the final state), ``out_met``, ``out_rec``,
  ``out_imp``, ``out_stick``, ``out_strobe`` and, for exact, ``out_t_reached``;
- for exact, ``NAME/prep_*``: what ``prepare(p)`` returned at capture (the regimes'
  matrices, diagonalised by LAPACK through NumPy).  ``replay(case, stored_prep=True)``
  hands the kernel the stored one, which holds the core alone to its bits;
  :func:`replay` without it lets the kernel prepare the run itself, as simulate's call
  does.  LAPACK's roundings are not the core's: OpenBLAS picks its kernels by the CPU
  (Haswell's and SkylakeX's give eigenvectors that differ in their last bits and in
  phase), and a rattling ball's run amplifies any rounding of its setup
  (``--sensitivity``).  So the kernel is held to its bits given the stored preparation,
  and ``prepare(p)`` to the stored one within roundings (:func:`prep_differences`);
  with OpenBLAS's kernels of the capture, ``OPENBLAS_CORETYPE=Haswell``, every case
  replays bit for bit as simulate runs it (``--as-simulate``).

``_names`` lists the cases in order, ``_met_names`` names the slots of ``met`` and
``_param_names`` the scalar slots of the stored ``p`` in order (simulate/layout.py),
for the messages of tests/test_kernel_reference.py and for :func:`current_params`.

Write (regenerate) the file from the core -- the inputs as
:func:`boringbar.simulate.simulate` packs them, through its ``setup_run``; each single
run checked against simulate's own kernel call, each batch against ``simulate_batch``::

    PYTHONPATH=src python tests/kernel_reference.py --write

Do so only when a change of the core is meant to change its bits, and say in the commit
by how much the runs changed (tests/test_kernel_reference.py otherwise holds the core to
these bits).

``--sensitivity`` replays each exact case with its setup moved by one rounding
(:func:`sensitivity`): a rattling ball's run is chaotic, and a change of the core that
moves any bit of its setup moves its RMS and peaks by as much as this shows.

Replay (:func:`replay`; without ``--write`` the script replays every case and prints
the differences) moves each stored ``p`` into the core's layout of today by slot name
(:func:`current_params`; slots added since capture are 0, as the captured runs had them)
and otherwise uses only the stored arrays and the three entry points imported in
the block below, so that the kernels can be repointed to another implementation by
editing that block alone.  Only capture calls into simulate.py.
"""

from __future__ import annotations

import argparse
import importlib
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_info

import boringbar.reference.stability as stability
from boringbar import Harmonic, Initial, Regenerative, State, make_system
from boringbar.simulate import layout as L

# the kernels under test: repoint these names to swap the implementation
from boringbar.simulate.kernels import (
    Records,
    Steps,
    prepare,
    run_exact,
    run_rk4,
    run_rk4_batch,
)
from boringbar.simulate.regimes import exact_setup, setup_fields

# the module (boringbar.simulate is also the name of its function), for capture only
sim = importlib.import_module("boringbar.simulate")

DATA = Path(__file__).parent / "data" / "kernel_reference.npz"
#: the zeroed arrays a call fills, by the name of their shape in the file
RECORDS = ("rec", "imp", "stick", "strobe")
#: the outputs every entry point writes (exact also returns the time reached)
OUTPUTS = ("x", "met", *RECORDS)

# the published harmonic grid, in the order of benchmarks/bench_grid.py's cases()
PRESETS = ("paper", "physical")
GAPS = (0.1e-3, 0.5e-3)
FRICTION = (False, True)
FORCES = (10.0, 20.0)
RATIOS = (0.95, 0.98, 1.00, 1.02, 1.05)
GRID_EXACT_S = 0.5  # the exact grid runs (s): the first impacts come at 0.02-0.33 s
GRID_RK4_S = 0.05  # the RK4 grid runs (s): the first impacts come at 0.02-0.04 s
FEATURE_RK4_S = 0.05  # the single-feature runs (s)
FEATURE_EXACT_S = 0.2
BATCH_S = 0.05
DT = 1e-6
RPM_FAST = 20000.0  # tau = 3 ms: 6.7 revolutions in 20 ms (tests/test_chatter.py)


# --- capture: the cases as simulate packs them ----------------------------------------
def _single(system, forcing, *, integrator, duration_s, dt_s=DT, initial=None, record_every=0,
            steady_fraction=0.8, strobe=False, stage_loop=False) -> dict:
    """The stored inputs of one run of :func:`simulate` (``setup_run``'s packing)."""
    su = sim.setup_run(system, forcing, duration_s, dt_s, initial, record_every, steady_fraction,
                    strobe, integrator)
    if stage_loop:
        su.p[L.STAGE_LOOP] = 1.0  # what simulate_stage_loop does
    case = {"entry": su.integrator, "p": su.p.copy(), "x0": su.x.copy(), "t0": su.t0,
            "met0": su.met.copy(), **_shapes(su.rec, su.imp, su.stick, su.stb)}
    if su.integrator == "exact":  # the arguments as _run_kernel computes them
        case.update(t_end=su.t0 + su.n_steps * su.dt, t_steady=su.t0 + su.steady_steps * su.dt,
                    rec_dt=su.record_every * su.dt, dt=su.dt, **_prep_arrays(su.p))
    else:
        buf = np.zeros((0, 2)) if su.buf is None else su.buf
        case.update(dt=su.dt, n_steps=su.n_steps, steady_start=su.steady_steps,
                    rec_every=su.record_every, buf_shape=np.array(buf.shape))
    case["_setup"] = su  # for the check against simulate's own call; not stored
    return case


def _prep_arrays(p: np.ndarray) -> dict:
    """``prepare(p)`` as arrays ``prep_*``: the preparation an exact case replays with."""
    return {f"prep_{k}": np.asarray(v) for k, v in setup_fields(prepare(p.copy())).items()}


def _shapes(rec, imp, stick, strobe) -> dict:
    return {f"{k}_shape": np.array(a.shape) for k, a in zip(RECORDS, (rec, imp, stick, strobe),
                                                            strict=True)}


def _batch(runs, *, duration_s, dt_s=DT, steady_fraction=0.8, strobe=False) -> dict:
    """The stored inputs of one lock-step batch, packed as simulate_batch packs it but
    not padded: ``runs`` (system, forcing, initial) are the batch's rows."""
    sus = [sim.setup_run(s, f, duration_s, dt_s, i, 0, steady_fraction, strobe, "rk4")
           for s, f, i in runs]
    nb, first = len(sus), sus[0]
    kwargs = {"duration_s": duration_s, "dt_s": dt_s, "steady_fraction": steady_fraction,
              "strobe": strobe}
    rows = {k: max(len(getattr(su, a)) for su in sus)
            for k, a in (("imp", "imp"), ("stick", "stick"), ("strobe", "stb"))}
    return {"entry": "rk4_batch", "P": np.array([su.p for su in sus]),
            "x0": np.array([su.x for su in sus]), "met0": np.array([su.met for su in sus]),
            "t0": first.t0, "dt": dt_s, "n_steps": first.n_steps,
            "steady_start": first.steady_steps, "rec_shape": np.array((0, 6)),
            "imp_shape": np.array((nb, rows["imp"], 3)),
            "stick_shape": np.array((nb, rows["stick"], 2)),
            "strobe_shape": np.array((nb, rows["strobe"], 5)),
            "_batch": (runs, kwargs)}  # for the check against simulate_batch; not stored


def _grid():
    """(label, system, forcing) of the 80 published harmonic cases."""
    out = []
    for preset in PRESETS:
        for gap in GAPS:
            for friction in FRICTION:
                s = make_system("ball", preset, gap_m=gap, friction=friction)
                for force in FORCES:
                    for ratio in RATIOS:
                        label = (f"{preset}-gap{gap * 1e3:.1f}-fric-{'on' if friction else 'off'}"
                                 f"-{force:.0f}N-r{ratio:.2f}")
                        out.append((label, s, Harmonic(force, ratio)))
    return out


def _grid_cases() -> dict:
    cases = {}
    for label, s, f in _grid():
        cases[f"grid-exact-{label}"] = lambda s=s, f=f: _single(
            s, f, integrator="exact", duration_s=GRID_EXACT_S)
    for label, s, f in _grid():
        cases[f"grid-rk4-{label}"] = lambda s=s, f=f: _single(
            s, f, integrator="rk4", duration_s=GRID_RK4_S)
    return cases


def _cut(system, depth, integrator, *, duration_s=0.02, dt_s=DT, rpm=RPM_FAST, initial=None,
         record_every=0, steady_fraction=0.8, **forcing):
    return _single(system, Regenerative(depth_m=depth, rpm=rpm, **forcing), integrator=integrator,
                   duration_s=duration_s, dt_s=dt_s, initial=initial, record_every=record_every,
                   steady_fraction=steady_fraction)


def _ball_cut(integrator):
    """tests/test_exact_regen.py's ball in a cut: 10 um gap, 3 x the bare bar's limit at
    1200 rpm, impacts and rolling friction in the first 14 ms."""
    s = make_system("ball", gap_m=10e-6)
    depth = 3.0 * float(stability.limit_at_speeds(s.bar, [1200.0])[0])
    return _cut(s, depth, integrator, rpm=1200.0, steady_fraction=1.0)


def _cut_cases() -> dict:
    """Regenerative cuts (tests/test_chatter.py's reference cases), RK4 and exact."""
    solid, tmd = make_system("solid"), make_system("tmd")
    locked = make_system("ball", locked=True, friction=False)
    kick = Initial(tip_velocity_m_s=0.02)
    cases = {}
    for ig in ("rk4", "exact"):
        cases |= {
            # first zero at 7.2 ms (third revolution), then h = 0 in many steps
            f"cut-{ig}-solid-cubic": lambda ig=ig: _cut(solid, 1e-3, ig),
            f"cut-{ig}-solid-linear": lambda ig=ig: _cut(solid, 1e-3, ig, interpolation="linear"),
            f"cut-{ig}-solid-stop-at-zero": lambda ig=ig: _cut(solid, 1e-3, ig,
                                                               stop_at_zero=True),
            f"cut-{ig}-solid-1rev-record": lambda ig=ig: _cut(solid, 1e-3, ig, revolutions=1,
                                                              record_every=10),
            # the surface before the cut is the static deflection; first zero at 16.4 ms
            f"cut-{ig}-locked-static": lambda ig=ig: _cut(locked, 1e-3, ig, start="static",
                                                          initial=kick),
            f"cut-{ig}-tmd-cubic": lambda ig=ig: _cut(tmd, 2e-3, ig),
            f"cut-{ig}-ball-impacts": lambda ig=ig: _ball_cut(ig),
        }
    return cases


def _bars() -> dict:
    """Systems of the single-feature cases, by name."""
    return {
        "solid": make_system("solid"),
        "solid-paper": make_system("solid", "paper"),
        "tmd": make_system("tmd"),
        "tmd-paper": make_system("tmd", "paper"),
        "locked": make_system("ball", locked=True),
        "ball-3modes": make_system("ball", n_modes=3, gap_m=0.1e-3),
        "ball-4modes": make_system("ball", n_modes=4, gap_m=0.1e-3),
        "solid-5modes": make_system("solid", n_modes=5),
        "ball-printed": make_system("ball", gap_m=0.5e-3, friction_force_n=2.0,
                                    friction_reaction="printed"),
        "ball-nofric": make_system("ball", gap_m=0.5e-3, friction=False),
        "paper": make_system("ball", "paper", gap_m=0.5e-3),
        "rolling": make_system("ball", motion="roll"),
        "rolling-3modes": make_system("ball", n_modes=3, gap_m=0.1e-3, motion="roll"),
    }


def _feature_cases() -> dict:
    """One feature a case, RK4 and exact."""
    b = _bars()
    h10, h20 = Harmonic(10.0, 1.0), Harmonic(20.0, 0.98)
    cont = State(np.array([2e-5, -1e-5, 1e-3, 0.02, 1e-4, -0.01]), 0.0123)
    start = Initial(tip_displacement_m=1e-4, tip_velocity_m_s=-0.01, ball_position_m=4e-5,
                    ball_velocity_m_s=0.005)
    common = {
        "solid": (b["solid"], h10, {}),
        "solid-paper-1mode": (b["solid-paper"], h10, {}),
        "tmd": (b["tmd"], h10, {}),
        "tmd-paper-1mode": (b["tmd-paper"], h20, {}),
        "locked": (b["locked"], h10, {}),
        "ball-3modes": (b["ball-3modes"], h20, {}),
        "ball-4modes": (b["ball-4modes"], h20, {}),
        "solid-5modes": (b["solid-5modes"], h10, {}),
        "printed-reaction": (b["ball-printed"], h20, {}),
        "strobe": (b["ball-printed"], h20, {"strobe": True}),
        "record": (b["paper"], h10, {"record_every": 50}),
        "initial-conditions": (b["ball-nofric"], h10, {"initial": start}),
        "continued-state": (b["ball-nofric"], h20, {"initial": cont}),
        # a rolling ball: it rattles and slips at 20 N, rolls and slips in turn at 0.05 N
        "rolling": (b["rolling"], h20, {}),
        "rolling-small-force": (b["rolling"], Harmonic(0.05, 1.0), {}),
        "rolling-3modes": (b["rolling-3modes"], h20, {}),
    }
    cases = {}
    for name, (s, f, kw) in common.items():
        cases[f"rk4-{name}"] = lambda s=s, f=f, kw=kw: _single(
            s, f, integrator="rk4", duration_s=FEATURE_RK4_S, **kw)
        cases[f"exact-{name}"] = lambda s=s, f=f, kw=kw: _single(
            s, f, integrator="exact", duration_s=FEATURE_EXACT_S, **kw)
    cases |= _rk4_only_cases(b) | _exact_only_cases()
    return cases


def _rk4_only_cases(b) -> dict:
    h10, h20 = Harmonic(10.0, 1.0), Harmonic(20.0, 1.0)
    rk4 = {"integrator": "rk4", "duration_s": FEATURE_RK4_S}
    return {
        "rk4-stage-loop-ball-nofric": lambda: _single(b["ball-nofric"], h20, stage_loop=True,
                                                      **rk4),
        "rk4-stage-loop-tmd": lambda: _single(b["tmd"], h10, stage_loop=True, **rk4),
        "rk4-rolling-cut": lambda: _cut(b["rolling"], 2e-4, "rk4", rpm=1200.0),
        # every step recorded (20 ms): the sgn() chatter of the paper's 20.4 N friction
        "rk4-paper-stick-record-every-step": lambda: _single(b["paper"], h10, integrator="rk4",
                                                             duration_s=0.02, record_every=1),
    }


def _exact_only_cases() -> dict:
    """True stick-slip (static_ratio > 1: impacts, stick intervals and slips) and a Zeno
    capture (tests/test_exact.py)."""
    slip = make_system("ball", gap_m=0.1e-3, friction_force_n=2.0, static_ratio=3.0)
    paper2 = make_system("ball", "paper", gap_m=0.5e-3, static_ratio=2.0)
    zeno = make_system("ball", gap_m=0.5e-3, friction=False, restitution=0.3)
    throw = Initial(tip_displacement_m=2e-4, ball_position_m=0.25e-3 - 1e-6)
    return {
        "exact-stick-slip-physical": lambda: _single(slip, Harmonic(20.0, 1.0),
                                                     integrator="exact", duration_s=0.2),
        "exact-stick-slip-paper": lambda: _single(paper2, Harmonic(20.0, 1.0),
                                                  integrator="exact", duration_s=0.2,
                                                  steady_fraction=0.5),
        "exact-zeno-contact": lambda: _single(zeno, Harmonic(0.0, 1.0), integrator="exact",
                                              duration_s=5e-3, steady_fraction=1.0,
                                              initial=throw),
    }


def _batch_cases() -> dict:
    """Batches of 4, 8 and 16 runs (the lock-step widths) and one of 5."""
    grid = _grid()
    paper = [(s, f, None) for _, s, f in grid if s.preset == "paper"]
    physical = [(s, f, None) for _, s, f in grid if s.preset == "physical"]
    tmd = make_system("tmd")
    ball4 = make_system("ball", n_modes=4, gap_m=0.1e-3)
    ratios = (0.96, 0.99, 1.0, 1.03)
    return {
        # 20 N at resonance, one run each of gap 0.1/0.5 mm x friction off/on
        "batch-4-paper": lambda: _batch([paper[i] for i in (7, 17, 27, 37)], duration_s=BATCH_S),
        "batch-8-physical": lambda: _batch(physical[20:28], duration_s=BATCH_S, strobe=True),
        "batch-16-paper": lambda: _batch(paper[::40 // 16][:16], duration_s=BATCH_S),
        "batch-5-paper-not-in-lanes": lambda: _batch(paper[30:35], duration_s=BATCH_S),
        "batch-4-tmd": lambda: _batch([(tmd, Harmonic(10.0, r), None) for r in ratios],
                                      duration_s=BATCH_S),
        "batch-4-ball-4modes": lambda: _batch([(ball4, Harmonic(20.0, r), None)
                                               for r in ratios], duration_s=BATCH_S),
    }


def case_builders() -> dict:
    """Every case's name and the function that packs its inputs."""
    return _grid_cases() | _cut_cases() | _feature_cases() | _batch_cases()


# --- replay: the stored inputs through the entry points ------------------------------
def current_params(stored: np.ndarray, param_names) -> np.ndarray:
    """A stored parameter vector (or the rows of a batch's P) in the core's layout today:
    ``param_names`` are the scalar slots of the stored layout, in order (the file's
    ``_param_names``), followed by the per-mode blocks (the first of L.PARAM_BLOCKS, as
    many as it holds); each stored slot goes where its name is now, slots added since stay
    0 (the linear cutting law, no force noise, the impact law) and a block added since
    is the one it defaults to (PSI_F: PSI_L)."""
    stored = np.asarray(stored, dtype=float)
    nmax, ns = L.NMAX, len(param_names)
    nblocks = (stored.shape[-1] - ns) // nmax
    if stored.shape[-1] != ns + nmax * nblocks or not 0 < nblocks <= len(L.PARAM_BLOCKS):
        raise ValueError(f"a stored p of {stored.shape[-1]} slots is not the stored layout")
    out = np.zeros(stored.shape[:-1] + (L.P_SIZE,))
    for i, name in enumerate(param_names):
        out[..., getattr(L, str(name))] = stored[..., i]
    for k, name in enumerate(L.PARAM_BLOCKS[:nblocks]):
        at = getattr(L, name)
        out[..., at:at + nmax] = stored[..., ns + k * nmax:ns + (k + 1) * nmax]
    if "PSI_F" not in L.PARAM_BLOCKS[:nblocks]:  # stored before it: the force at the tip
        out[..., L.PSI_F:L.PSI_F + nmax] = out[..., L.PSI_L:L.PSI_L + nmax]
    return out


def current_met(case: dict) -> np.ndarray:
    """The stored initial metrics ``met0`` (or a batch's rows) in the core's layout today:
    each stored slot where its name is now, the slots added since at 0, as setup_run
    starts them."""
    stored, names = case["met0"], case["_met_names"]
    out = np.zeros(stored.shape[:-1] + (L.MET_SIZE,))
    for i, name in enumerate(names):
        out[..., getattr(L, name)] = stored[..., i]
    return out


def stored_met(case: dict, met: np.ndarray) -> np.ndarray:
    """The metrics ``met`` in the stored layout: the slots the reference holds."""
    return np.stack([met[..., getattr(L, name)] for name in case["_met_names"]], axis=-1)


def _params(case: dict, key: str) -> np.ndarray:
    """The case's stored ``p`` (or ``P``) in the core's layout today."""
    return current_params(case[key], case["_param_names"])


def _records(case: dict) -> list[np.ndarray]:
    return [np.zeros(tuple(int(n) for n in case[f"{k}_shape"])) for k in RECORDS]


def _outputs(case: dict, x, met, records) -> dict:
    return dict(zip(OUTPUTS, (x, stored_met(case, met), *records), strict=True))


def _replay_rk4(case: dict) -> dict:
    x, met = case["x0"].copy(), current_met(case)
    rec, imp, stick, strobe = records = _records(case)
    shape = tuple(int(n) for n in case["buf_shape"])
    buf = np.zeros(shape) if shape[0] else None  # None: simulate's harmonic call
    steps = Steps(float(case["t0"]), float(case["dt"]), int(case["n_steps"]),
                  int(case["steady_start"]), int(case["rec_every"]))
    run_rk4(_params(case, "p"), x, steps, Records(rec, imp, stick, strobe, met), buf)
    return _outputs(case, x, met, records)


def _replay_batch(case: dict) -> dict:
    x, met = case["x0"].copy(), current_met(case)
    _, imp, stick, strobe = records = _records(case)
    steps = Steps(float(case["t0"]), float(case["dt"]), int(case["n_steps"]),
                  int(case["steady_start"]))
    run_rk4_batch(_params(case, "P"), x, steps, Records(records[0], imp, stick, strobe, met))
    return _outputs(case, x, met, records)


def stored_prep_of(case: dict) -> dict:
    """The stored result of ``prepare(p)`` of an exact case, its fields by name
    (:func:`exact_setup` makes it the ``core.ExactSetup`` that ``run_exact`` takes)."""
    return {k.removeprefix("prep_"): v.item() if v.ndim == 0 else v.copy()
            for k, v in case.items() if k.startswith("prep_")}


#: keys of prepare(p) that scale with an eigenvector (a column of V: V, Vh) or with its row
#: of the inverse (Vi, bq = Vi B): LAPACK fixes each eigenvector's scale only up to a phase
_BY_COLUMN = ("V", "Vh")
_BY_ROW = ("Vi", "bq")


def prep_differences(stored: dict, got: dict) -> dict:
    """How far ``got = prepare(p)`` is from the ``stored`` one, key by key: the largest
    difference relative to the key's largest stored magnitude per regime, with each
    eigenvector taken at the stored one's phase first (each column k of V is the stored
    one times a unit number c_k, row k of Vi the stored one over it); an integer key, or
    a shape, that differs gives inf.  Without that phase, two LAPACK builds (or one
    OpenBLAS picking its kernels by the CPU) agree to their roundings."""
    V, Vs = np.asarray(got["V"]), np.asarray(stored["V"])
    if V.shape != Vs.shape:
        return {"V": np.inf}
    overlap = np.einsum("rik,rik->rk", Vs.conj(), V)  # stored V's columns have unit norm
    size = np.abs(overlap)
    c = np.where(size > 0.5, overlap / size, 1.0)
    out = {"phase": float(np.max(np.abs(size - 1.0)))}
    for k, st in stored.items():
        g, st = np.asarray(got[k]), np.asarray(st)
        if g.shape != st.shape or g.dtype != st.dtype:
            out[k] = np.inf
        elif g.dtype.kind not in "fc":
            out[k] = 0.0 if np.array_equal(g, st) else np.inf
        else:
            if k in _BY_COLUMN:
                g = g / c[:, None, :]
            elif k in _BY_ROW:  # Vi (R, nz, nz) by its rows, bq (R, nz) by its entries
                g = g * (c if g.ndim == 2 else c[:, :, None])
            scale = np.max(np.abs(st).reshape(len(st), -1), axis=1) if st.ndim else abs(st)
            d = np.abs(g - st).reshape(len(st), -1).max(axis=1) if st.ndim else abs(g - st)
            out[k] = float(np.max(d / np.where(scale > 0, scale, 1.0)))
    return out


def same_bits(a, b) -> bool:
    """The two arrays (or numbers) have the same dtype, shape and bits."""
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def _replay_exact(case: dict, prep: dict | None = None) -> dict:
    x, met = case["x0"].copy(), current_met(case)
    rec, imp, stick, strobe = records = _records(case)
    t = run_exact(_params(case, "p"), x, exact_steps(case), Records(rec, imp, stick, strobe, met),
                  prep=None if prep is None else exact_setup(prep))
    return {**_outputs(case, x, met, records), "t_reached": np.float64(t)}


def exact_steps(case: dict) -> Steps:
    """The span of an exact case, stored as times (t_end, t_steady, rec_dt), in steps of
    its dt, as simulate gave them; refused if they do not give back the stored times."""
    t0, dt = float(case["t0"]), float(case["dt"])
    count = [round((float(case[k]) - t0) / dt) for k in ("t_end", "t_steady")]
    steps = Steps(t0, dt, *count, round(float(case["rec_dt"]) / dt))
    times = (t0 + steps.n_steps * dt, t0 + steps.steady_start * dt, steps.record_every * dt)
    if times != tuple(float(case[k]) for k in ("t_end", "t_steady", "rec_dt")):
        raise ValueError(f"the stored times {times} are not whole steps of dt = {dt}")
    return steps


_REPLAY = {"rk4": _replay_rk4, "rk4_batch": _replay_batch, "exact": _replay_exact}


def replay(case: dict, stored_prep: bool = False) -> dict:
    """The outputs of the case's entry point called with its stored inputs (an exact
    case with ``stored_prep``: given the stored ``prepare(p)``, not preparing it)."""
    if stored_prep:
        return _replay_exact(case, stored_prep_of(case))
    return _REPLAY[str(case["entry"])](case)


# --- the file ----------------------------------------------------------------------------
def load(path: Path = DATA) -> dict:
    """{case name: {key: array}} from the reference file."""
    with np.load(path, allow_pickle=False) as z:
        param_names = tuple(str(n) for n in z["_param_names"])
        met_names = tuple(str(n) for n in z["_met_names"])
        cases = {str(n): {"_param_names": param_names, "_met_names": met_names}
                 for n in z["_names"]}
        for key in z.files:
            name, _, item = key.rpartition("/")
            if name in cases:
                cases[name][item] = z[key]
    return cases


def names(path: Path = DATA) -> list[str]:
    with np.load(path, allow_pickle=False) as z:
        return [str(n) for n in z["_names"]]


def met_names(path: Path = DATA) -> list[str]:
    with np.load(path, allow_pickle=False) as z:
        return [str(n) for n in z["_met_names"]]


# --- comparison --------------------------------------------------------------------------
def differences(case_name: str, stored: dict, got: dict, slot_names=()) -> list[str]:
    """One message per stored output array that ``got`` does not equal bit for bit (two
    NaNs are equal whatever their payload) or lacks."""
    out = []
    for key in sorted(k.removeprefix("out_") for k in stored if k.startswith("out_")):
        if key not in got:
            out.append(f"{case_name}: {key}: not returned by the replay")
            continue
        msg = _difference(np.asarray(got[key]), stored[f"out_{key}"], slot_names, key)
        if msg:
            out.append(f"{case_name}: {key}: {msg}")
    return out


def _difference(a: np.ndarray, b: np.ndarray, slot_names, key: str) -> str:
    if a.shape != b.shape or a.dtype != b.dtype:
        return f"shape/dtype {a.shape} {a.dtype}, stored {b.shape} {b.dtype}"
    if a.dtype.kind != "f":
        bad = a != b
    else:
        bad = (a.view(np.uint64) != b.view(np.uint64)) & ~(np.isnan(a) & np.isnan(b))
    n = int(np.count_nonzero(bad))
    if not n:
        return ""
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        diff = np.abs(a[bad].astype(float) - b[bad].astype(float))
        rel = diff / np.maximum(np.abs(a[bad]), np.abs(b[bad]))
    first = tuple(int(i) for i in np.argwhere(bad)[0])
    slot = f" ({slot_names[first[-1]]})" if key == "met" and len(slot_names) else ""
    return (f"{n} of {a.size} entries differ; largest |difference| {np.nanmax(diff):.3g}, "
            f"largest relative {np.nanmax(rel):.3g}; first at {first}{slot}: "
            f"{a[first].item()!r}, stored {b[first].item()!r}")


# --- capture -------------------------------------------------------------------------------
def _check_against_simulate(name: str, case: dict, out: dict) -> None:
    """The replayed call equals simulate's own kernel call on the same setup (the exact
    integrator's STEPS_DONE is simulate's, written after the call)."""
    su = case["_setup"]
    sim.run_kernel(su)
    ref = {"x": su.x, "met": su.met.copy(), "rec": su.rec, "imp": su.imp, "stick": su.stick,
           "strobe": su.stb}
    if case["entry"] == "exact":
        ref["met"][L.STEPS_DONE] = out["met"][L.STEPS_DONE]
    counted = {"rec": L.N_REC, "imp": L.N_IMP_REC, "stick": L.N_STICK_REC,
               "strobe": L.N_STROBE}
    for key, a in ref.items():
        got = out[key]
        if key in counted:  # setup_run's record arrays hold rows only as far as met counts
            rows = int(su.met[counted[key]])
            a, got = a[:rows], got[:rows]
        if _difference(got, a, (), key):
            raise AssertionError(f"{name}: {key} replayed differs from simulate's call")


def _check_batch_against_simulate(name: str, case: dict, out: dict) -> None:
    """A batch gives each run's final state and records as simulate_batch does."""
    runs, kwargs = case["_batch"]
    for r, run in enumerate(sim.simulate_batch(runs, **kwargs)):
        for key, kept in (("x", run.final.x), ("imp", run.impacts), ("stick", run.sticks),
                          ("strobe", run.strobe)):
            got = out[key][r][:len(kept)]
            if _difference(got, kept, (), key):
                raise AssertionError(f"{name}: run {r}: {key} differs from simulate_batch's")


_CHECKS = {"rk4": _check_against_simulate, "exact": _check_against_simulate,
           "rk4_batch": _check_batch_against_simulate}


def capture(path: Path = DATA, check: bool = True) -> None:
    """Build every case, run it, and write inputs and outputs to ``path``."""
    arrays = {"_met_names": np.array(L.METRIC_NAMES), "_param_names": np.array(L.PARAM_NAMES)}
    done = []
    for name, build in case_builders().items():
        tic = time.perf_counter()
        case = build() | {"_param_names": L.PARAM_NAMES, "_met_names": L.METRIC_NAMES}
        out = replay(case)
        if check:
            _CHECKS[case["entry"]](name, case, out)
        for key, value in case.items():
            if key.startswith("_"):
                continue
            arrays[f"{name}/{key}"] = np.asarray(value)
        for key, value in out.items():
            arrays[f"{name}/out_{key}"] = np.asarray(value)
        done.append(name)
        print(f"{name:58s} {case['entry']:9s} {time.perf_counter() - tic:7.2f} s", flush=True)
    arrays["_names"] = np.array(done)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **arrays)
    print(f"{len(done)} cases -> {path} ({path.stat().st_size / 1e6:.2f} MB)")


def replay_all(path: Path = DATA) -> None:
    """Replay every stored case (an exact one given its stored preparation) and report
    differences and the time taken; then how far this machine's ``prepare(p)`` is from
    the stored ones, and how many exact cases it reproduces bit for bit."""
    cases, slots = load(path), met_names(path)
    tic = time.perf_counter()
    bad = [m for n, c in cases.items()
           for m in differences(n, c, replay(c, str(c["entry"]) == "exact"), slots)]
    print(f"{len(cases)} cases replayed in {time.perf_counter() - tic:.2f} s; "
          f"{len(bad)} differences")
    for m in bad:
        print(m)
    exact = [c for c in cases.values() if str(c["entry"]) == "exact"]
    worst, same = 0.0, 0
    for case in exact:
        stored = stored_prep_of(case)
        got = setup_fields(prepare(current_params(case["p"], case["_param_names"])))
        worst = max(worst, *prep_differences(stored, got).values())
        same += all(same_bits(got[k], v) for k, v in stored.items())
    print(f"prepare(p) here: {same} of {len(exact)} exact cases the stored bits; largest "
          f"difference {worst:.2e} (prep_differences)")


def blas_kernels() -> list[str]:
    """The kernel sets of the BLAS libraries loaded (OpenBLAS's: "Haswell", "SkylakeX")."""
    return sorted({f"{i.get('internal_api')} {i.get('architecture')}" for i in threadpool_info()
                   if i.get("user_api") == "blas"})


def replay_as_simulate(path: Path = DATA) -> int:
    """Replay every stored case as simulate calls the kernels, an exact one preparing its
    run itself; print the BLAS kernels and the differences; 1 if any.  With OpenBLAS's
    kernels of the capture (``OPENBLAS_CORETYPE=Haswell``) the preparation's bits, and so
    every run's, are the stored ones."""
    cases, slots = load(path), met_names(path)
    bad = [m for n, c in cases.items() for m in differences(n, c, replay(c), slots)]
    print(f"BLAS: {', '.join(blas_kernels())}; {len(cases)} cases replayed as simulate "
          f"calls the kernels; {len(bad)} differences")
    for m in bad:
        print(m)
    return 1 if bad else 0


def _observed(met: np.ndarray, met_names) -> np.ndarray:
    """The sum of W^2 (the RMS's), the steady peak-to-peak and the largest |W| of a run."""
    m = dict(zip((str(n) for n in met_names), met, strict=True))
    return np.array([m["SUM_W2"], m["STEADY_MAX_W"] - m["STEADY_MIN_W"], m["MAX_ABS_W"]])


def sensitivity(path: Path = DATA) -> None:
    """How much each exact case's RMS and peaks move when its setup moves by one rounding:
    the case replayed with its stored preparation, the forcing's response Z scaled by
    (1 + 2^-52), against its stored outputs.  A rattling ball's run is chaotic, so a
    change of the core that moves any bit of its setup moves these by as much; a change
    is judged against this, case by case."""
    cases = load(path)
    rows = []
    for name, case in cases.items():
        if str(case["entry"]) != "exact":
            continue
        prep = stored_prep_of(case)
        prep["Z"] = prep["Z"] * (1.0 + 2.0**-52)
        stored = _observed(case["out_met"], case["_met_names"])
        moved = _observed(_replay_exact(case, prep)["met"], case["_met_names"])
        rel = float(np.max(np.abs(moved - stored) / np.abs(stored)))
        impacts = int(case["out_met"][list(case["_met_names"]).index("N_IMP_ALL")])
        rows.append((rel, impacts, name))
    for rel, impacts, name in sorted(rows):
        print(f"{rel:9.2e} {impacts:6d} {name}")
    print(f"{len(rows)} exact cases; {sum(r[0] > 1e-12 for r in rows)} move by more than "
          "1e-12 (relative, RMS or peak) when Z moves by one rounding")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", "--capture", dest="write", action="store_true",
                    help="regenerate the reference file from the core")
    ap.add_argument("--file", type=Path, default=DATA, help="the reference file")
    ap.add_argument("--no-check", action="store_true",
                    help="skip the check of each run against simulate's own call")
    ap.add_argument("--sensitivity", action="store_true",
                    help="how much each exact case moves when its setup moves by one rounding")
    ap.add_argument("--as-simulate", action="store_true",
                    help="exact cases prepare their runs themselves (exit 1 on a difference)")
    args = ap.parse_args()
    if args.sensitivity:
        sensitivity(args.file)
    elif args.as_simulate:
        raise SystemExit(replay_as_simulate(args.file))
    elif args.write:
        capture(args.file, check=not args.no_check)
    else:
        replay_all(args.file)


if __name__ == "__main__":
    main()
