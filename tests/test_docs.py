"""The documentation builds without a warning, and the repository is self-contained.

The model page (docs/model.md) replaced an external specification; these
tests keep every citation inside the repository.  Nothing here imports the
package or compiles a kernel: mkdocstrings reads the sources statically.
"""

import importlib.util
import os
import shutil
import subprocess
import sys

import pytest

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REFS_TOOL = os.path.join(REPO, "tools", "model_refs.py")
# Spelled in pieces so that this file does not itself cite the external spec.
EXTERNAL = ("MODEL" + ".md", "shared/" + "spec")
#: files allowed to name the external spec: the rewriting tool and this test
ALLOWED = {"tools/model_refs.py", "tests/test_docs.py"}


def _missing_docs_tools() -> str | None:
    for module in ("mkdocs", "mkdocstrings", "mkdocstrings_handlers.python"):
        try:
            found = importlib.util.find_spec(module) is not None
        except ModuleNotFoundError:
            found = False
        if not found:
            return (f"{module} is not importable: install the test extra "
                    "(pip install -e '.[test]') to build the docs")
    return None


def test_mkdocs_build_is_strict_clean(tmp_path):
    """``mkdocs build --strict``: broken links, unknown anchors and docstrings
    mkdocstrings cannot render are errors."""
    missing = _missing_docs_tools()
    if missing:
        pytest.skip(missing)
    out = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict",
         "-f", os.path.join(REPO, "mkdocs.yml"), "-d", str(tmp_path / "site")],
        capture_output=True, text=True, timeout=300, cwd=REPO,
    )
    log = out.stdout + out.stderr
    warnings = [line for line in log.splitlines() if "WARNING" in line]
    assert out.returncode == 0 and not warnings, log
    assert (tmp_path / "site" / "api.html").is_file()


def _tracked_files() -> list[str]:
    if shutil.which("git") is None:
        pytest.skip("git is not installed")
    out = subprocess.run(["git", "ls-files", "-z"], cwd=REPO, capture_output=True)
    if out.returncode != 0:
        pytest.skip("not a git checkout: " + out.stderr.decode(errors="replace").strip())
    return [p for p in out.stdout.decode().split("\0") if p]


def test_no_tracked_file_refers_to_the_external_spec():
    offenders = []
    for rel in _tracked_files():
        if rel in ALLOWED:
            continue
        try:
            with open(os.path.join(REPO, rel), encoding="utf-8", errors="ignore") as f:
                for i, line in enumerate(f, 1):
                    if any(name in line for name in EXTERNAL):
                        offenders.append(f"{rel}:{i}: {line.strip()}")
        except (IsADirectoryError, FileNotFoundError):  # submodule or deleted in the tree
            continue
    assert not offenders, ("files still cite the external spec; run python3 "
                           "tools/model_refs.py . :\n" + "\n".join(offenders))


def test_model_refs_rewrites_every_form_once(tmp_path):
    """tools/model_refs.py on a small tree: every citation form, links relative
    to each file, anchors read from the page, and a second run changes nothing."""
    name, folder = EXTERNAL
    (tmp_path / "docs").mkdir()
    shutil.copy(os.path.join(REPO, "docs", "model.md"), tmp_path / "docs" / "model.md")
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "mod.py").write_text(
        f'"""Walls ({name} section 2.5), the cut ({name} sec. 4) and\n'
        f'the study ({name} 6.1); see {name} eq. (3) and {name}.\n"""\n'
        f'HELP = ("a sweep ({name} section "\n        "6)")\n',
        encoding="utf-8")
    (tmp_path / "README.md").write_text(
        f"The model ([`{name}`](../{folder}/{name})); {name} sections 1-3, 5.\n"
        f"Lobes ({name} section\n6.3). Code: `{name} section 4`.\n",
        encoding="utf-8")
    (tmp_path / "pkg" / "notes.md").write_text(f"See {name} section 9.9.\n", encoding="utf-8")

    run = subprocess.run([sys.executable, REFS_TOOL, str(tmp_path)], capture_output=True,
                         text=True, timeout=60)
    assert run.returncode == 0, run.stdout + run.stderr
    py = (tmp_path / "pkg" / "mod.py").read_text(encoding="utf-8")
    compile(py, "mod.py", "exec")
    assert "(docs/model.md, section 2.5)" in py
    assert "(docs/model.md, section 4)" in py
    assert "(docs/model.md, section 6.1)" in py
    assert "docs/model.md, eq. (3) and docs/model.md." in py
    assert '(docs/model.md, section "' in py
    readme = (tmp_path / "README.md").read_text(encoding="utf-8")
    assert "[`docs/model.md`](docs/model.md)" in readme
    assert "[1](docs/model.md#1-the-bar)-[3](docs/model.md#3-the-tuned-mass-damper)" in readme
    assert "[model, section\n6.3](docs/model.md#63-stability-lobes)" in readme
    assert "`docs/model.md, section 4`" in readme
    notes = (tmp_path / "pkg" / "notes.md").read_text(encoding="utf-8")
    assert "[model, section 9.9](../docs/model.md)" in notes  # no such section: the page
    assert "warning: " in run.stdout

    again = subprocess.run([sys.executable, REFS_TOOL, str(tmp_path), "--check"],
                           capture_output=True, text=True, timeout=60)
    assert again.returncode == 0, again.stdout
    assert "0 reference(s)" in again.stdout


def test_model_refs_fails_while_references_remain(tmp_path):
    (tmp_path / "docs").mkdir()
    shutil.copy(os.path.join(REPO, "docs", "model.md"), tmp_path / "docs" / "model.md")
    (tmp_path / "x.txt").write_text(f"the folder {EXTERNAL[1]}/ is gone\n", encoding="utf-8")
    run = subprocess.run([sys.executable, REFS_TOOL, str(tmp_path)], capture_output=True,
                         text=True, timeout=60)
    assert run.returncode == 1
    assert "x.txt:1" in run.stdout
