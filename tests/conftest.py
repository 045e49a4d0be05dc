"""How the suite shares the cores: ``pytest`` runs ``-n 2 --dist loadscope`` (pyproject.toml).

A module's tests run on one worker (module fixtures are built once).  The longest modules
start first (``FIRST``), so that neither worker is left running one of them alone at
the end.
"""

#: the modules started first, longest first; then the others in file order
FIRST = ("test_sanitizers.py", "test_paper.py", "test_runner.py", "test_basins.py",
         "test_cli_nonlinear.py")


def pytest_collection_modifyitems(items):
    rank = {name: i for i, name in enumerate(FIRST)}
    keyed = sorted(enumerate(items), key=lambda ix: (
        rank.get(ix[1].nodeid.partition("::")[0].rsplit("/", 1)[-1], len(FIRST)), ix[0]))
    items[:] = [item for _, item in keyed]
