"""The compiled core's boundary: whatever Python hands it, a clear exception, never a crash.

Each entry point of ``boringbar.core`` (``run_rk4``, ``run_rk4_batch``, ``run_exact``)
takes one run description (``RK4Run``, ``RK4Batch``, ``ExactRun``) and gets a valid one (a
short published ball-damper run), then hypothesis corrupts one of its fields: a wrong
dtype, rank, shape or layout, a read-only output, a NaN or an infinity in a parameter, the
state or a scalar, an out-of-range count.  Setting the field or running must either work
(a corruption the core can take, such as a larger output array) or raise ``ValueError`` /
``TypeError`` naming the field; a crash of the core would take the test process with it, a
hang would stall the suite.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from boringbar import Harmonic, Regenerative, core, make_system
from boringbar.simulate import engine, setup_run
from boringbar.simulate import layout as L
from boringbar.simulate.kernels import prepare
from boringbar.simulate.regimes import (
    GRID_LEVELS,
    SYSTEM_SLOTS,
    cut_tables,
    exact_setup,
    history_step,
    setup_fields,
    system_regimes,
)

SETTINGS = settings(max_examples=150, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow])


#: a cut through Kienzle's law with noise at its extremes: the largest seed, an interval
#: of 3 steps, a std at which the gain is often clamped at 0
KIENZLE_NOISE = {"workpiece": "steel", "force_noise": 0.9, "noise_interval_s": 3e-6,
                 "noise_seed": 2**53}


def rk4_args(cut: bool = False, law: dict | None = None) -> dict:
    s = make_system("ball", "paper", gap_m=0.1e-3, friction=True)
    f = Regenerative(depth_m=1e-3, rpm=1200.0, **(law or {})) if cut else Harmonic(10.0, 1.0)
    su = setup_run(s, f, 2e-3, 1e-6, None, 10, 0.5, True, "rk4")
    return {"p": su.p, "x": su.x, "t0": su.t0, "dt": su.dt, "n_steps": su.n_steps,
            "steady_start": su.steady_steps, "rec_every": su.record_every, "rec": su.rec,
            "imp": su.imp, "stick": su.stick, "strobe": su.stb, "met": su.met,
            "buf": su.buf if su.buf is not None else np.zeros((0, 2))}


def batch_args() -> dict:
    a = rk4_args()
    nb = 4
    rows = lambda v: np.repeat(v[None], nb, axis=0)  # noqa: E731
    return {"P": rows(a["p"]), "x": rows(a["x"]), "t0": a["t0"], "dt": a["dt"],
            "n_steps": a["n_steps"], "steady_start": a["steady_start"],
            "imp": rows(a["imp"]), "stick": rows(a["stick"]), "strobe": rows(a["strobe"]),
            "met": rows(a["met"])}


def exact_args(cut: bool = False, motion: str = "slide") -> dict:
    # a cut that chatters with impacts and stays bounded: deeper (1 mm), a corrupted
    # t_end of 3 s grows the vibration to 1e15 m through 3.5 million events (25 s; most
    # of the sanitizer run's time), at 0.1 mm it takes 1.9 s
    s = make_system("ball", "physical", gap_m=0.1e-3, friction=True, motion=motion)
    f = Regenerative(depth_m=0.1e-3, rpm=1200.0) if cut else Harmonic(10.0, 1.0)
    su = setup_run(s, f, 2e-3, 1e-6, None, 10, 0.5, True, "exact")
    prep = prepare(su.p)
    H = history_step(float(su.p[L.TAU]), su.dt) if cut else 0.0
    tab_e, tab_p = cut_tables(prep, su.p, H) if cut else (np.zeros((1, 5, 1), complex),
                                                           np.zeros((1, 5, 4, 1), complex))
    t_end = su.t0 + su.n_steps * su.dt
    return {"p": su.p, "x": su.x, "t0": su.t0, "t_end": t_end,
            "t_steady": su.t0 + su.steady_steps * su.dt, "rec_dt": su.record_every * su.dt,
            "rec": su.rec, "imp": su.imp, "stick": su.stick, "strobe": su.stb, "met": su.met,
            "prep": setup_fields(prep), "dt": su.dt, "H": H, "tabE": tab_e, "tabP": tab_p}


#: each entry point's run description
DESCRIPTIONS = {"run_rk4": core.RK4Run, "run_rk4_batch": core.RK4Batch,
                "run_exact": core.ExactRun}

ENTRIES = {
    "run_rk4": rk4_args,
    "run_rk4 cut": lambda: rk4_args(cut=True),
    "run_rk4 cut kienzle noise": lambda: rk4_args(cut=True, law=KIENZLE_NOISE),
    "run_rk4_batch": batch_args,
    "run_exact": exact_args,
    "run_exact cut": lambda: exact_args(cut=True),
    "run_exact rolling": lambda: exact_args(motion="roll"),
}
BASE = {}


def call(entry: str, args: dict):
    """The entry point run with a description whose fields are ``args``."""
    name = entry.split()[0]
    run = DESCRIPTIONS[name]()
    for field, value in args.items():
        # prep's fields, each set on its ExactSetup (a refused one is the same clear error)
        setattr(run, field, exact_setup(value) if isinstance(value, dict) else value)
    return getattr(core, name)(run)


def fresh(entry: str) -> dict:
    if entry not in BASE:
        BASE[entry] = ENTRIES[entry]()
    out = {}
    for k, v in BASE[entry].items():
        out[k] = {kk: vv.copy() if isinstance(vv, np.ndarray) else vv for kk, vv in v.items()} \
            if isinstance(v, dict) else (v.copy() if isinstance(v, np.ndarray) else v)
    return out


@pytest.mark.parametrize("entry", list(ENTRIES))
def test_a_valid_call_runs(entry):
    args = fresh(entry)
    call(entry, args)
    assert args["met"][..., L.STEPS_DONE].min() > 0 or "exact" in entry
    assert np.all(np.isfinite(args["x"]))


BAD_SCALARS = [np.nan, np.inf, -np.inf, -1.0, 0.0, 1e300, -1e300, 2.0 ** 63, -(2 ** 40)]
BAD_INTS = [-1, 0, 3, 2 ** 40, -(2 ** 40)]


def corrupt_array(draw, a: np.ndarray) -> object:
    kind = draw(st.sampled_from(["dtype", "rank", "shape", "strided", "readonly", "value",
                                 "list", "none"]))
    if kind == "dtype":
        return a.astype(draw(st.sampled_from([np.int64, np.float32, np.complex128, bool,
                                              np.int32])))
    if kind == "rank":
        return a.reshape(-1) if a.ndim > 1 else a.reshape(1, -1)
    if kind == "shape":
        dims = draw(st.lists(st.integers(0, 40), min_size=a.ndim, max_size=a.ndim))
        return np.zeros(dims, a.dtype)
    if kind == "strided":
        big = np.zeros(tuple(2 * n for n in a.shape), a.dtype)
        view = big[tuple(slice(None, None, 2) for _ in a.shape)]
        view[...] = a
        return view if view.size > 1 else big
    if kind == "readonly":
        b = a.copy()
        b.flags.writeable = False
        return b
    if kind == "value":
        b = a.copy()
        if b.size:
            flat = b.reshape(-1)
            bad = BAD_INTS if b.dtype.kind in "iu" else BAD_SCALARS  # (prep's kstep, levmax)
            flat[draw(st.integers(0, b.size - 1))] = draw(st.sampled_from(bad))
        return b
    return [] if kind == "list" else None


@st.composite
def corrupted(draw, entry: str):
    args = fresh(entry)
    name = draw(st.sampled_from(sorted(args)))
    v = args[name]
    if isinstance(v, np.ndarray):
        args[name] = corrupt_array(draw, v)
    elif isinstance(v, dict):
        key = draw(st.sampled_from(sorted(v)))
        if draw(st.booleans()):
            del v[key]
        elif isinstance(v[key], np.ndarray):
            v[key] = corrupt_array(draw, v[key])
        else:
            v[key] = draw(st.sampled_from(BAD_SCALARS + ["x", None]))
    else:
        args[name] = draw(st.sampled_from(BAD_SCALARS + [None, "x", 3 if name != "p" else 0]))
    return name, args


@pytest.mark.parametrize("entry", list(ENTRIES))
@pytest.mark.filterwarnings("ignore::RuntimeWarning", "ignore::numpy.exceptions.ComplexWarning")
@SETTINGS
@given(data=st.data())
def test_any_corrupted_argument_is_a_clear_error_or_a_run(entry, data):
    name, args = data.draw(corrupted(entry))
    try:
        call(entry, args)
    except (ValueError, TypeError) as exc:
        assert str(exc), f"{entry}: {name}: an exception without a message"


SLOTS = ["N_MODES", "CASE", "FORCING", "N_REV", "TAU", "OMEGA", "HALF_GAP", "BALL_MASS",
         "RESTITUTION", "M_EFF", "STROBE_PERIOD", "INTERP", "FRICTION", "STATIC_FRICTION",
         "CUT_MC", "NOISE_STD", "NOISE_INTERVAL", "NOISE_SEED", "ROLL", "ROLL_STATIC",
         "ROLL_KINETIC", "REACTION"]


@pytest.mark.parametrize("entry", list(ENTRIES))
@SETTINGS
@given(slot=st.sampled_from(SLOTS), value=st.sampled_from(
    BAD_SCALARS + [9.0, 100.0, 3.5, 1e-300, 4.0, 60.0, 51.0]))
def test_any_parameter_slot_out_of_range_is_a_clear_error_or_a_run(entry, slot, value):
    args = fresh(entry)
    p = args["P"] if "P" in args else args["p"]
    p[..., getattr(L, slot)] = value
    try:
        call(entry, args)
    except (ValueError, TypeError) as exc:
        assert str(exc)


def test_a_massless_ball_with_friction_runs_in_bounded_work():
    """BALL_MASS = 0 (only a corrupted slot gives it) with friction: after a y' = 0 switch
    the ball's y' leaves zero the wrong way.  The search for a y' that comes to zero and
    back inside a grid step must not take that for a return, which would end segment
    after segment a few ulp long (an earlier version ran for minutes); the 2 ms run takes
    4 events."""
    args = fresh("run_exact")
    args["p"][L.BALL_MASS] = 0.0
    assert call("run_exact", args) == pytest.approx(args["t_end"])
    assert args["met"][L.METRIC_NAMES.index("N_EVENTS")] < 100


@pytest.mark.parametrize("entry", ["run_rk4", "run_rk4_batch", "run_exact"])
def test_a_refused_field_is_named(entry):
    run = DESCRIPTIONS[entry]()
    readonly = np.zeros(3)
    readonly.flags.writeable = False
    with pytest.raises(ValueError, match="'x' must be a writable float64 array"):
        run.x = readonly
    with pytest.raises(ValueError, match="'t0' must be a number"):
        run.t0 = "x"
    with pytest.raises(ValueError, match="'p' was not set" if entry != "run_rk4_batch"
                       else "'P' was not set"):
        getattr(core, entry)(run)


def test_the_exact_setup_is_typed_field_by_field():
    """prepare's setup is a typed description as the runs are: a field refuses a value of
    another type when it is set, naming it; a run holds the setup it is given and reads its
    fields when it starts; it refuses a setup with a field unset, and a prep that is not a
    setup (a dict of its fields, as the setup once was)."""
    args = fresh("run_exact")
    setup = exact_setup(args["prep"])
    with pytest.raises(ValueError, match="'kstep' must be an int64 array; got dtype float64"):
        setup.kstep = np.ones(3)
    with pytest.raises(ValueError, match="'lam' must be a complex128 array; got dtype float64"):
        setup.lam = np.zeros((3, 4))
    with pytest.raises(ValueError, match="'nreg' must be an integer"):
        setup.nreg = 2.5
    with pytest.raises(ValueError, match="'prep' must be an ExactSetup"):
        call("run_exact", {**args, "prep": setup_fields(setup).items()})
    # the run holds the setup itself, and reads its fields when it starts
    run = core.ExactRun()
    run.prep = setup
    assert run.prep is setup
    setup.levmax = np.full_like(args["prep"]["levmax"], 9)
    for name, value in args.items():
        if name != "prep":
            setattr(run, name, value)
    with pytest.raises(ValueError, match="prep.levmax's entries must be in"):
        core.run_exact(run)
    del args["prep"]["bnd"]
    with pytest.raises(ValueError, match="'bnd' was not set"):
        call("run_exact", args)


def read_only(a: np.ndarray) -> np.ndarray:
    b = a.copy()
    b.flags.writeable = False
    return b


#: (entry, field, the value given from the valid one, what the refusal says): each array
#: field declares its dtype, and is never converted (a converted output would take the
#: run's writes and drop them)
REFUSED_WHEN_SET = [
    ("run_rk4", "p", lambda v: v.astype(np.float32),
     r"'p' must be a float64 array; got dtype float32"),
    ("run_rk4", "p", lambda v: v.astype(np.int64), r"'p' must be a float64 array; got dtype int64"),
    ("run_rk4", "x", read_only, r"'x' must be a writable float64 array; got a read-only array"),
    ("run_rk4", "met", lambda v: read_only(np.zeros(v.shape, np.int32)),
     r"'met' must be a writable float64 array; got dtype int32, read-only"),
    ("run_rk4", "rec", lambda v: v.astype(complex),
     r"'rec' must be a writable float64 array; got dtype complex128"),
    ("run_rk4", "buf", lambda v: v.tolist(),
     r"'buf' must be a writable float64 array; got type list"),
    ("run_rk4", "modes", lambda v: read_only(np.zeros((3, 2))),
     r"'modes' must be a writable float64 array; got a read-only array"),
    ("run_rk4", "contact", lambda v: np.zeros((4, 6), np.int64),
     r"'contact' must be a writable float64 array; got dtype int64"),
    ("run_rk4_batch", "P", lambda v: v.astype(np.int64),
     r"'P' must be a float64 array; got dtype int64"),
    ("run_rk4_batch", "strobe", read_only,
     r"'strobe' must be a writable float64 array; got a read-only array"),
    ("run_exact", "p", lambda v: None, r"'p' must be a float64 array; got None"),
    ("run_exact", "imp", lambda v: v.astype(bool),
     r"'imp' must be a writable float64 array; got dtype bool"),
    ("run_exact", "tabE", lambda v: v.real.copy(),
     r"'tabE' must be a complex128 array; got dtype float64"),
    ("run_exact", "tabP", lambda v: v.astype(np.complex64),
     r"'tabP' must be a complex128 array; got dtype complex64"),
]


@pytest.mark.parametrize(("entry", "field", "value", "message"), REFUSED_WHEN_SET)
def test_an_array_of_another_dtype_or_read_only_output_is_refused_when_set(entry, field,
                                                                           value, message):
    """The refusal comes at the assignment, names the field, what it must be and what it
    got; the description keeps the array it had."""
    args = fresh(entry)
    run = DESCRIPTIONS[entry]()
    valid = args.get(field)
    if valid is not None:
        setattr(run, field, valid)
    with pytest.raises(ValueError, match="^core: " + message + "$"):
        setattr(run, field, value(valid))
    if valid is not None:
        assert getattr(run, field) is valid


@pytest.mark.parametrize("entry", ["run_rk4", "run_exact"])
def test_a_field_is_the_callers_own_array(entry):
    """An input may be read-only; neither an input nor an output is copied, so the run
    writes into the caller's arrays."""
    args = fresh(entry)
    args["p"] = read_only(args["p"])
    run = DESCRIPTIONS[entry]()
    for field, value in args.items():
        # prep's fields, each set on its ExactSetup (a refused one is the same clear error)
        setattr(run, field, exact_setup(value) if isinstance(value, dict) else value)
        if isinstance(value, np.ndarray):
            assert getattr(run, field) is value, field
    getattr(core, entry)(run)
    assert args["met"][L.STEPS_DONE] > 0 or entry == "run_exact"
    assert not np.array_equal(args["x"], fresh(entry)["x"])


def test_the_signatures_show_the_fields_dtypes():
    """help() shows a property's doc, the stubs its getter's and setter's signatures: each
    gives the field's dtype, and whether it may be read-only (an input) or None."""
    field = lambda cls, name: vars(cls)[name]  # noqa: E731
    p, x, modes = (field(core.RK4Run, k) for k in ("p", "x", "modes"))
    assert "ndarray[dtype=float64, device='cpu', writable=False]" in p.__doc__
    assert "dtype=float64" in x.__doc__ and "writable" not in x.__doc__
    assert modes.__doc__.endswith("ndarray[dtype=float64, device='cpu'] | None")
    assert "dtype=complex128" in field(core.ExactRun, "tabE").__doc__
    assert "dtype=float64" in field(core.RK4Batch, "P").__doc__
    sig = x.fset.__nb_signature__[0][0]
    assert sig == "def x(self, value: ndarray[dtype=float64, device='cpu'], /) -> None"
    assert p.fget.__nb_signature__[0][0].endswith("writable=False]")


def test_a_scalar_out_of_range_names_its_value_and_range():
    args = fresh("run_rk4")
    args["dt"] = -1.0
    with pytest.raises(ValueError, match=r"dt = -1 must be finite and > 0"):
        call("run_rk4", args)


# --- the cut orbit's history map ------------------------------------------------------
def history_map_args(m: int = 7, s: int = 3, k: int = 2, depth: int = 5) -> dict:
    rng = np.random.default_rng(3)
    base = rng.integers(-depth, 0, size=(m, k)) + np.arange(m)[:, None] // 2
    return {"d": rng.standard_normal((m, s, s)), "cols": rng.standard_normal((m, k, s)),
            "base": np.minimum(base, np.arange(m)[:, None] - 1).astype(np.int64),
            "weights": rng.standard_normal((m, k, 4)), "c": rng.standard_normal(s),
            "cv": rng.standard_normal(s), "v": rng.standard_normal(2 * depth + s),
            "periods": 3}


def history_map_by_hand(a: dict) -> np.ndarray:
    """The recursion of core.cut_history_map written out over whole states: every node's
    full state kept, W and W' formed where a delay reads them."""
    m, s, _ = a["d"].shape
    depth = (a["v"].size - s) // 2
    pairs = {j - depth: a["v"][2 * j:2 * j + 2] for j in range(depth)}
    nodes = {0: a["v"][2 * depth:]}

    def wwd(j):
        return pairs[j] if j < 0 else np.array([a["c"] @ nodes[j], a["cv"] @ nodes[j]])

    for p in range(a["periods"]):
        for i in range(m):
            x = a["d"][i] @ nodes[p * m + i]
            for t in range(a["cols"].shape[1]):
                j = p * m + int(a["base"][i, t])
                w = a["weights"][i, t]
                x = x + a["cols"][i, t] * (w[:2] @ wwd(j) + w[2:] @ wwd(j + 1))
            nodes[p * m + i + 1] = x
    end = a["periods"] * m
    return np.concatenate([*(wwd(j) for j in range(end - depth, end)), nodes[end]])


def test_the_history_map_is_its_recursion():
    a = history_map_args()
    got = core.cut_history_map(**a)
    assert np.allclose(got, history_map_by_hand(a), rtol=1e-13, atol=1e-13 * np.abs(got).max())


@pytest.mark.parametrize(("field", "value", "message"), [
    ("base", lambda a: a["base"] - 10, "outside"),
    ("base", lambda a: a["base"] + np.arange(7)[:, None] + 1, "outside"),
    ("d", lambda a: a["d"][:, :2], "shape"),
    ("cols", lambda a: a["cols"][:5], "shape"),
    ("weights", lambda a: a["weights"][:, :, :3], "shape"),
    ("c", lambda a: a["c"][:2], "entries"),
    ("v", lambda a: a["v"][:-1], "pairs"),
    ("periods", lambda a: 0, "periods"),
])
def test_a_bad_history_map_argument_is_a_clear_error(field, value, message):
    assert_refused(core.cut_history_map, history_map_args(), field, value, message)


def assert_refused(call, a: dict, field: str, value, message: str) -> dict:
    """``call(**a)`` with ``a[field]`` replaced by ``value(a)`` is a ValueError matching
    ``message``; returns the arguments it was given."""
    a[field] = value(a)
    with pytest.raises(ValueError, match=message):
        call(**a)
    return a


def forcing_setup_args(omega=700.0, f0=10.0) -> dict:
    """The per-system arrays of the published ball bar's regimes, as prepare passes them."""
    p = engine.pack(make_system("ball"), omega, f0, 1e-6, "sgn")
    s = system_regimes(p[SYSTEM_SLOTS].tobytes())
    return {"A": s.A, "B": s.B, "lam": s.lam, "mode_sums": s.mode_sums,
            "mode_bounds": s.mode_bounds, "psis": s.psi, "hi": s.hi, "lo": s.lo,
            "omega": omega, "f0": f0, "levels": GRID_LEVELS}


def forcing_setup(omega, f0, levels, **regimes):
    """core.forcing_setup of the regimes whose arrays (core.Regimes's) are given by name."""
    return core.forcing_setup(core.Regimes(**regimes), omega=omega, f0=f0, levels=levels)


def test_the_forced_response_solves_its_equations():
    """Z of each regime solves (i Omega I - A) Z = B F0 as well as LAPACK's solve does
    (relative residual), and agrees with it to the problem's conditioning."""
    a = forcing_setup_args()
    Z = forcing_setup(**a)[0]
    nz = a["A"].shape[1]
    for r in range(a["A"].shape[0]):
        M, b = 1j * a["omega"] * np.eye(nz) - a["A"][r], a["B"][r] * a["f0"]
        ref = np.linalg.solve(M, b)
        assert np.linalg.norm(M @ Z[r] - b) <= 8 * np.finfo(float).eps * np.linalg.norm(b)
        assert np.allclose(Z[r], ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


@pytest.mark.parametrize(("field", "value", "message"), [
    ("A", lambda a: a["A"][:, :2], "A must be"),
    ("B", lambda a: a["B"][:2], "B must be"),
    ("lam", lambda a: a["lam"][:, :1], "lam must be"),
    ("mode_sums", lambda a: a["mode_sums"][:, :2], "mode_sums must be"),
    ("mode_bounds", lambda a: a["mode_bounds"][:, :3], "mode_bounds must be"),
    ("psis", lambda a: a["psis"][:1], "psis must be"),
    ("hi", lambda a: a["hi"][:1], "hi and lo"),
    ("omega", lambda a: -1.0, "Omega"),
    ("f0", lambda a: float("nan"), "F0"),
    ("levels", lambda a: 0, "levels"),
    ("A", lambda a: np.zeros_like(a["A"]), "singular"),
])
def test_a_bad_forcing_setup_argument_is_a_clear_error(field, value, message):
    a = forcing_setup_args()
    if message == "singular":
        a["omega"] = 0.0  # -A = 0 has no inverse
    assert_refused(forcing_setup, a, field, value, message)


def impact_period_args() -> dict:
    """A symmetric one-period sequence of a +1 and a -1 wall, as classify passes it."""
    times = (np.arange(60)[:, None] + np.array([0.2, 0.7])[None, :]).ravel() * 1e-3
    walls = np.tile([1.0, -1.0], 60)
    return {"times": times, "walls": walls, "tail_start": 0.0, "tail_end": 0.06,
            "period": 1e-3, "tol": 1e-6, "max_k": 8, "min_periods": 3}


def test_the_impact_period_of_a_known_sequence():
    assert core.impact_period(**impact_period_args()) == (2, 1, True)
    a = impact_period_args()
    a["walls"] = np.tile([1.0, 1.0], 60)  # both on one wall: periodic, not symmetric
    assert core.impact_period(**a) == (2, 1, False)


@pytest.mark.parametrize(("field", "value", "message"), [
    ("times", lambda a: a["times"][::2], "non-contiguous"),
    ("times", lambda a: a["times"].astype(np.float32), "float64"),
    ("walls", lambda a: a["walls"][:-1], "shape"),
    ("walls", lambda a: a["walls"].astype(np.int64), "float64"),
    ("period", lambda a: 0.0, "period"),
    ("period", lambda a: float("nan"), "period"),
    ("max_k", lambda a: 0, "max_k"),
    ("min_periods", lambda a: 1, "min_periods"),
])
def test_a_bad_impact_period_argument_is_a_clear_error(field, value, message):
    a = assert_refused(core.impact_period, impact_period_args(), field, value, message)
    if field in ("times", "walls"):
        with pytest.raises(ValueError, match=message):
            core.impact_fault(a["times"], a["walls"], 0.0, 0.06)
