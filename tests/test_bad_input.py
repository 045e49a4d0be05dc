"""Bad input, thrown at the CLI as a new user would (issue #7 point 7).

Hypothesis builds command lines of every subcommand and study files with ONE bad
value among valid ones (NaN, inf, negative, zero, huge, not a number, out of range,
unknown choice or key) and runs them in process through ``boringbar.cli.main.main``.
Each must end with exit code 2, exactly one stderr line ``boringbar: error: ...``
naming the option or key, no traceback, and no file in the output directory.  The
errors come before any kernel is compiled or run, so the whole module takes seconds
(a hole would show as a slow example that writes files).
"""

import contextlib
import io
import math
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from boringbar.cli.main import main
from boringbar.studies.registry import ANALYSES
from boringbar.studies.schema import SETTINGS

SETTINGS_PROFILE = settings(max_examples=150, deadline=None, derandomize=True,
                            suppress_health_check=[HealthCheck.too_slow])

NOT_FINITE = ("nan", "inf", "-inf", "NaN")
WORDS = ("abc", "", "1,2", "--")

#: (command prefix, option, bad values): every numeric option of every command.
BAD_OPTIONS = {
    "simulate": (["simulate"], {
        "--duration-s": (*NOT_FINITE, "-1", "0", "1e12", "1e300", *WORDS),
        "--dt-s": (*NOT_FINITE, "-1e-6", "0", "1", "1e300", "abc"),
        "--force-n": (*NOT_FINITE, "-1", "1e300", "abc"),
        "--ratio": (*NOT_FINITE, "-1", "0", "1e300", "abc"),
        "--gap-mm": (*NOT_FINITE, "-0.5", "0", "2.5", "1e6", "abc"),
        "--restitution": (*NOT_FINITE, "-0.1", "1.5", "abc"),
        "--friction-force-n": (*NOT_FINITE, "-1", "1e300"),
        "--friction-number": (*NOT_FINITE, "-1", "1e300"),
        "--static-ratio": (*NOT_FINITE, "0.5", "-1"),
        "--modes": ("0", "-1", "9", "1.5", "nan", "abc"),
        "--tip-displacement-mm": (*NOT_FINITE, "1e300", "-1e300"),
        "--tip-velocity-m-s": (*NOT_FINITE, "1e300", "-1e300"),
        "--ball-position-mm": (*NOT_FINITE, "0.3", "-1", "1e300"),
        "--ball-velocity-m-s": (*NOT_FINITE, "1e300", "-1e300"),
        "--record-every": ("0", "-1", "1.5", "1e30", "nan", "abc"),
        "--bar": ("plate", "ball,solid", ""),
        "--preset": ("paperback",),
        "--integrator": ("euler",),
        "--ball": ("glass",),
        "--friction": ("maybe",),
    }),
    "cut": (["simulate", "--rpm", "1200", "--depth-mm", "0.05"], {
        "--rpm": (*NOT_FINITE, "0", "-1", "1e-3", "1e9", "abc"),
        "--depth-mm": (*NOT_FINITE, "0", "-1", "1e6"),
        "--kr-mpa": (*NOT_FINITE, "0", "-1", "1e300"),
        "--feed-mm": (*NOT_FINITE, "0", "-1", "1e300"),
        "--revolutions": ("0", "-1", "51", "1.5", "abc"),
        "--bounded-fraction": (*NOT_FINITE, "0", "-1"),
        "--delay-interp": ("quadratic",),
        "--start": ("moving",),
        "--duration-s": (*NOT_FINITE, "0", "1e12"),
    }),
    "continue-cut": (["continue", "--cut", "--bar", "solid", "--rpm", "1200",
                      "--parameter", "depth-mm", "--range", "0:0.1"], {
        "--rpm": (*NOT_FINITE, "0", "-1", "1e-3", "1e9", "abc"),
        "--range": ("nan:1", "1:0", "0.1:0.1", "-1:1", "0:inf", "0:2000", "a", "1", "0:1:2"),
        "--lobe": ("-1", "201", "abc", "1.5"),
        "--max-points": ("0", "1", "-1", "abc", "100000"),
        "--kr-mpa": (*NOT_FINITE, "0", "-1", "1e300"),
        "--feed-mm": (*NOT_FINITE, "0", "-1", "1e300"),
        "--revolutions": ("0", "-1", "51", "1.5", "abc"),
        "--parameter": ("force-n", "ratio"),
        "--depth-mm": ("0.05",),
    }),
    "continue-cut-speed": (["continue", "--cut", "--bar", "solid", "--parameter", "rpm",
                            "--depth-mm", "0.05", "--range", "1000:1400"], {
        "--depth-mm": (*NOT_FINITE, "0", "-1", "1e6", "abc"),
        "--range": ("0:1400", "1400:1000", "-1:1000", "1000:inf", "1000:2e6", "a", "1000"),
        "--rpm": (*NOT_FINITE, "0", "-1", "1e-3", "1e9"),
    }),
    "sweep": (["sweep"], {
        "--ratios": (*NOT_FINITE, "0", "-1", "1e300", "0:inf:1", "0:1:1e-300", "1:0:0.1",
                     "nan:1:0.1", "a,b", "1:2"),
        "--force-n": (*NOT_FINITE, "-1", "1e300", "x", "10,nan"),
        "--gap-mm": (*NOT_FINITE, "0", "5", "-1", "0.5,inf"),
        "--workers": ("0", "-1", "1e9", "abc"),
        "--duration-s": (*NOT_FINITE, "0", "1e12"),
        "--dt-s": ("1", "1e-3", "0", "nan"),
        "--friction": ("maybe",),
    }),
    "lobes": (["lobes", "--bar", "solid"], {
        "--rpm": (*NOT_FINITE, "0", "-1", "1e-3", "5", "0:inf:1", "900:1600:0"),
        "--at-rpm": ("1e-6", "5", "0"),
        "--depth-step-mm": (*NOT_FINITE, "0", "-1", "1e-9"),
        "--max-depth-mm": (*NOT_FINITE, "0.0005", "1e6", "-1"),
        "--successive": ("0", "101", "-1", "abc"),
        "--workers": ("0", "-1"),
        "--kr-mpa": (*NOT_FINITE, "0", "1e300"),
        "--method": ("guess",),
    }),
    "lobes-analytic": (["lobes", "--analytic", "--bar", "solid"], {
        "--rpm": ("1e-9", "5", "0", "-1", "nan"),
        "--at-rpm": ("1e-6", "5", "0"),
        # a simulated cut's options, which the closed form would leave unread
        "--tolerance-um": ("-1", "5"),
        "--knock-um": ("1",),
        "--depth-step-mm": ("0.01",),
    }),
    "basins": (["basins"], {
        "--displacement-mm": ("nan:1:3", "-1:1:0", "-1:1:1e9", "-1e300:1:3", "1:-1:3",
                              "-1:1:100000", "-1:1", "abc"),
        "--velocity-m-s": ("nan:1:3", "-1:inf:3", "-1:1:0", "-1e300:1:3", "-1:1:100000"),
        "--poincare-from": ("nan,0", "1e300,0", "0,inf", "1", "a,b"),
        "--steady-fraction": (*NOT_FINITE, "0", "1.5", "-0.1"),
        "--force-n": (*NOT_FINITE, "-1", "1e300"),
        "--dt-s": ("1", "0", "nan"),
        "--workers": ("0",),
    }),
    "bifurcation": (["bifurcation"], {
        "--force-n": ("5:inf:1", "nan", "-5:5:1", "5:1e300:1e-300", "1e300"),
        "--ratio": ("nan", "0.9:1.1:0", "-1", "1e300"),
        "--gap-mm": ("0.1:5:0.1", "nan", "0"),
        "--restitution": ("0.5:1.5:0.1", "nan"),
        "--steady-fraction": (*NOT_FINITE, "0"),
    }),
    "sensitivity": (["sensitivity", "restitution"], {
        "--values": ("nan", "2", "-1", "0.5,inf", "abc"),
        "--ratios": ("nan", "0:inf:1"),
        "--cut-rpm": (*NOT_FINITE, "0", "1e-3"),
        "--depths-mm": ("nan", "0", "0:inf:1", "1e300"),
        "--workers": ("0",),
        "--starts": ("1", "65", "-1", "2.5"),
    }),
}

#: Valid options mixed in (every command takes them).
VALID_EXTRAS = (("--preset", "paper"), ("--preset", "physical"), ("--quiet",), ("--json",),
                ("--dt-s", "1e-6"), ("--duration-s", "0.5"))


def _run(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def _assert_refused(argv, name, out_dir: Path, allowed_files=()):
    code, _, err = _run(argv)
    assert code == 2, (argv, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1, (argv, err)
    assert lines[0].startswith("boringbar: error:"), (argv, err)
    assert name in lines[0], (argv, name, err)
    assert "Traceback" not in err
    written = sorted(p.name for p in out_dir.iterdir()) if out_dir.exists() else []
    assert written == sorted(allowed_files), (argv, written)


@st.composite
def bad_command_lines(draw):
    command = draw(st.sampled_from(sorted(BAD_OPTIONS)))
    prefix, options = BAD_OPTIONS[command]
    option = draw(st.sampled_from(sorted(options)))
    value = draw(st.sampled_from(options[option]))
    extras = draw(st.lists(st.sampled_from(VALID_EXTRAS), max_size=3, unique=True))
    # (--analytic runs no cut, and refuses a cut's step)
    extras = [e for e in extras if e[0] != option
              and not (command == "lobes-analytic" and e[0] == "--dt-s")]
    keep = {e[0]: e for e in extras}  # one value per option
    argv = list(prefix)
    for e in keep.values():
        argv += list(e)
    if option == "--ball-position-mm":
        argv += ["--gap-mm", "0.5"]
    argv.append(f"{option}={value}")  # the = form: values like -1 stay values
    return argv, option


@SETTINGS_PROFILE
@given(bad_command_lines())
def test_bad_option_values_are_one_line_errors(case):
    argv, option = case
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        _assert_refused([*argv, "--out", str(out)], option, out)


# --- study files ------------------------------------------------------------------------

def _toml(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return '"' + value + '"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + "}"
    return str(value)


def _bad_values(spec) -> list:
    """Values the schema setting ``spec`` must refuse."""
    kind = spec.kind
    if kind in ("bool", "onoff"):
        return ["yes", 1, 0.5]
    if kind == "str":
        return [1.5, True] + (["bogus"] if spec.choices else [])
    bad = [math.nan, math.inf, -math.inf, "abc", True]
    if spec.lo is not None:
        bad.append(spec.lo if spec.lo_open else spec.lo - 1)
    if spec.hi is not None:
        bad.append(spec.hi * 10 + 1)
    if kind == "int":
        bad.append((spec.lo or 0) + 0.5)
    return bad


#: (section, key, bad value, name in the message): every schema key.
STUDY_CASES = [(section, key, v, f"'{section}.{key}'")
               for section, keys in SETTINGS.items() if section != "study"
               for key, spec in keys.items() for v in _bad_values(spec)]
STUDY_CASES += [
    ("run", "duration_s", 1e300, "'run.duration_s'"),  # 1e308 steps
    ("run", "ball_position_mm", 0.3, "'run.ball_position_mm'"),  # beyond a 0.5 mm gap / 2
    ("study", "out", "x.csv", "'study.out'"),
    ("study", "out", "x", "'study.out'"),
    ("study", "out", "x.nc.txt", "'study.out'"),
    ("study", "preset", "paperback", "'study.preset'"),
    ("study", "analysis", "lobe", "'study.analysis'"),
    ("study", "colour", "red", "'study.colour'"),
    ("damper", "diameter_mm", 15.0, "'damper.diameter_mm'"),
    ("grid", "ratio", {"start": 0.9, "stop": math.inf, "step": 0.01}, "'grid.ratio'"),
    ("grid", "ratio", {"start": 0.9, "stop": 1.1, "step": 1e-300}, "'grid.ratio'"),
    ("grid", "force_n", [10.0, math.nan], "'grid.force_n'"),
    ("grid", "gap_mm", [0.5, 5.0], "'grid.gap_mm'"),
]
#: (analysis, key, bad value): the analyses' own options.
ANALYSIS_CASES = [
    ("bifurcation", "values", [5.0, math.nan]),
    ("bifurcation", "values", {"start": 5, "stop": math.inf, "step": 1}),
    ("bifurcation", "values", {"start": 5, "stop": 50, "step": 1e-300}),
    ("bifurcation", "tol", math.nan),
    ("bifurcation", "max_k", 0),
    ("basins", "displacement_mm", {"start": math.nan, "stop": 1.5, "count": 3}),
    ("basins", "displacement_mm", {"start": -1.5, "stop": 1.5, "count": 0}),
    ("basins", "velocity_m_s", {"start": -1.5, "stop": 1.5, "count": 10**9}),
    ("lobes", "depth_step_mm", math.nan),
    ("lobes", "max_depth_mm", math.inf),
    ("lobes", "max_depth_mm", 0.0005),  # below the geometric grid's first depth, 1 um
    ("lobes", "depth_tolerance", math.nan),
    ("lobes", "depth_tolerance", 0.9),
    ("lobes", "successive", 0),
    ("sensitivity", "depths_mm", [0.05, math.inf]),
    ("sensitivity", "kind", "colour"),
    ("sweep", "anything", 1.0),
]


def _study_text(analysis: str, section: str, key: str, value) -> str:
    tables = {"study": {"analysis": analysis}}
    if section == "study":
        tables["study"][key] = value
    else:
        tables.setdefault(section, {})[key] = value
    lines = []
    for name, table in tables.items():
        lines.append(f"[{name}]")
        lines += [f"{k} = {_toml(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


@st.composite
def bad_studies(draw):
    if draw(st.booleans()):
        analysis, key, value = draw(st.sampled_from(ANALYSIS_CASES))
        return _study_text(analysis, "analysis", key, value), f"'analysis.{key}'"
    section, key, value, name = draw(st.sampled_from(STUDY_CASES))
    analysis = draw(st.sampled_from(sorted(ANALYSES)))
    if section == "study" and key == "analysis":
        return _study_text(value, "study", "name", "bad"), name
    return _study_text(analysis, section, key, value), name


@SETTINGS_PROFILE
@given(bad_studies(), st.sampled_from([(), ("--out", "result.nc"), ("--quiet",)]))
def test_bad_study_files_are_one_line_errors(case, extra):
    text, name = case
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        study = tmp / "study.toml"
        study.write_text(text)
        extra = [str(tmp / e) if e.endswith(".nc") else e for e in extra]
        _assert_refused(["run", str(study), "--executor", "serial", *extra], name, tmp,
                        allowed_files=["study.toml"])


def test_bad_run_options_are_one_line_errors(tmp_path):
    """boringbar run's own options: --out must be .nc or .zarr; counts >= 1."""
    study = tmp_path / "study.toml"
    study.write_text('[study]\nanalysis = "sweep"\n')
    for option, value in (("--out", "x.csv"), ("--out", str(tmp_path / "x")),
                          ("--workers", "0"), ("--chunk-size", "0"), ("--dask-local", "0"),
                          ("--workers", "-3")):
        _assert_refused(["run", str(study), f"{option}={value}"], option, tmp_path,
                        allowed_files=["study.toml"])
