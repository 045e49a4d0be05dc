"""The source distribution builds a wheel, and the wheel installs and runs where no compiler is.

What a user without a C++ compiler meets (the wheels cibuildwheel builds: pyproject.toml,
.github/workflows/wheels.yml), checked on this machine:

1. ``python -m build --sdist``: the sdist holds every tracked file of the compiled core
   (core/), the build (CMakeLists.txt, pyproject.toml) and the package with its data
   (src/boringbar/: templates, system files, designs);
2. ``pip wheel .`` in the unpacked sdist builds the wheel (the core compiled by
   scikit-build-core: a minute or two on two cores), which holds the compiled core and
   the package's data;
3. a fresh venv (``python -m venv``) installs the wheel with no compiler to be found
   (PATH holds the venv's own scripts only, CC and CXX are /bin/false) and no index;
4. tests/wheel_smoke.py runs there, outside the source tree: the package and its core
   are the venv's, and short runs of the published bar give finite results.

The venv takes the wheel's dependencies (NumPy, SciPy, ...) from this environment
through a .pth file, written after the install, so nothing is downloaded for it.
Slow (it compiles the core): ``pytest -m slow tests/test_wheel.py``.
"""

from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
import tarfile
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def run(cmd, **kw) -> subprocess.CompletedProcess:
    out = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, timeout=1800,
                         **kw)
    assert out.returncode == 0, f"{cmd} failed:\n{(out.stdout + out.stderr)[-6000:]}"
    return out


def tracked(*folders: str) -> set[str]:
    out = run(["git", "ls-files", *folders], cwd=ROOT)
    return {line for line in out.stdout.splitlines() if line}


@pytest.mark.slow
def test_the_sdist_builds_a_wheel_that_installs_and_runs_without_a_compiler(tmp_path):
    # 1. the sdist and what it must hold
    run([sys.executable, "-m", "build", "--sdist", "--outdir", tmp_path / "dist", ROOT])
    (sdist,) = (tmp_path / "dist").glob("boringbar-*.tar.gz")
    with tarfile.open(sdist) as tar:
        names = {name.split("/", 1)[1] for name in tar.getnames() if "/" in name}
        # (the "data" filter: Python 3.11.4 and later; the sdist is our own)
        extra = {"filter": "data"} if hasattr(tarfile, "data_filter") else {}
        tar.extractall(tmp_path / "src", **extra)
    needed = tracked("core", "src/boringbar") | {"CMakeLists.txt", "pyproject.toml",
                                                 "README.md", "LICENSE"}
    assert needed - names == set()

    # 2. the wheel, built from the unpacked sdist
    (unpacked,) = (tmp_path / "src").iterdir()
    run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-w", tmp_path / "wheelhouse", "."],
        cwd=unpacked)
    (wheel,) = (tmp_path / "wheelhouse").glob("boringbar-*.whl")
    with zipfile.ZipFile(wheel) as zf:
        in_wheel = set(zf.namelist())
    data = {name.removeprefix("src/") for name in tracked("src/boringbar")
            if not name.endswith(".py")}
    assert data and data - in_wheel == set()
    assert any(name.startswith("boringbar/core.") for name in in_wheel)
    assert any(".dist-info/" in name and name.endswith("/LICENSE") for name in in_wheel)

    # 3. a fresh venv, and the install with no compiler and no index
    venv = tmp_path / "venv"
    run([sys.executable, "-m", "venv", venv])
    scripts = venv / ("Scripts" if os.name == "nt" else "bin")
    python = scripts / ("python.exe" if os.name == "nt" else "python")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV"))}
    env.update(PATH=str(scripts), CC="/bin/false", CXX="/bin/false", PIP_NO_INDEX="1")
    run([python, "-m", "pip", "install", "--no-deps", "--no-build-isolation", wheel], env=env)

    # 4. the smoke test in the venv, its dependencies from this environment's site-packages
    site = Path(run([python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                    env=env).stdout.strip())
    ours = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    (site / "_this_environment.pth").write_text("\n".join(sorted(ours)) + "\n")
    out = run([python, ROOT / "tests" / "wheel_smoke.py"], cwd=tmp_path, env=env)
    assert "wheel smoke test passed" in out.stdout, out.stdout
    core_line = next(line for line in out.stdout.splitlines() if line.startswith("core: "))
    assert Path(core_line.removeprefix("core: ")).is_relative_to(venv), out.stdout
