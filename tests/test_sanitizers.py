"""The compiled core under AddressSanitizer and UndefinedBehaviorSanitizer.

The core is built a second time, with ``-DBORINGBAR_SANITIZE=ON`` (CMakeLists.txt), into a
folder of its own, and the kernel tests run against that build in a new process: the
stored reference outputs (every integrator, every bar), the bindings' hypothesis test
(wrong arrays and values of every kind) and the equations of motion as matrices
(tests/test_dynamics.py: every bar, and bad parameter vectors), RK4's stick law
(tests/test_stick_law.py), the Hertz contact (tests/test_contact.py) and the impact
pattern's loops on random, jittered and malformed sequences (tests/test_patterns.py).  An
out-of-bounds access, a use after free or undefined behaviour (signed overflow, a float
cast out of range, ...) aborts that process, and this test fails with the sanitizer's
report.  It needs CMake, Ninja or Make, a C++ compiler and nanobind in the environment (the
test extra installs nanobind).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: the tests run against the sanitized core
KERNEL_TESTS = ("tests/test_kernel_reference.py", "tests/test_core_bindings.py",
                "tests/test_dynamics.py", "tests/test_stick_law.py", "tests/test_contact.py",
                "tests/test_patterns.py")

#: imports the sanitized module as boringbar.core before anything imports the real one
RUNNER = """
import importlib.util, sys
spec = importlib.util.spec_from_file_location("boringbar.core", sys.argv[1])
core = importlib.util.module_from_spec(spec)
sys.modules["boringbar.core"] = core
spec.loader.exec_module(core)
import boringbar
boringbar.core = core
import pytest
sys.exit(pytest.main(["-q", "-p", "no:xdist", "-p", "no:cacheprovider", "-o", "addopts=",
                      "-m", "not slow", *sys.argv[2:]]))
"""


def _runtime(name: str) -> str:
    path = subprocess.run(["g++", f"-print-file-name={name}"], capture_output=True, text=True,
                          check=True).stdout.strip()
    if not os.path.isabs(path):
        pytest.skip(f"no {name} for this compiler")
    return path


def _build(where: Path) -> Path:
    generator = ["-G", "Ninja"] if shutil.which("ninja") else []
    subprocess.run(["cmake", "-S", str(ROOT), "-B", str(where / "build"), *generator,
                    f"-DPython_EXECUTABLE={sys.executable}", "-DBORINGBAR_SANITIZE=ON",
                    f"-DBORINGBAR_OUTPUT_DIR={where / 'module'}"],
                   check=True, capture_output=True, text=True)
    subprocess.run(["cmake", "--build", str(where / "build")], check=True, capture_output=True,
                   text=True)
    return next((where / "module").glob("core*.so"))


@pytest.mark.skipif(shutil.which("cmake") is None or shutil.which("g++") is None,
                    reason="needs CMake and g++")
def test_kernel_tests_pass_under_address_and_undefined_behavior_sanitizers(tmp_path):
    module = _build(tmp_path)
    # the Python executable links neither runtime: ASan must come first, and libstdc++
    # before the module, or ASan's interceptor of C++ throws finds no __cxa_throw
    preload = f"{_runtime('libasan.so')} {_runtime('libstdc++.so')}"
    env = dict(os.environ, LD_PRELOAD=preload,
               ASAN_OPTIONS="detect_leaks=0:abort_on_error=1:verify_asan_link_order=0:"
                            "handle_abort=1",
               UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1")
    out = subprocess.run([sys.executable, "-c", RUNNER, str(module), *KERNEL_TESTS],
                         cwd=ROOT, env=env, capture_output=True, text=True)
    tail = (out.stdout + out.stderr)[-6000:]
    assert out.returncode == 0, tail
    assert "passed" in out.stdout and "failed" not in out.stdout, tail
