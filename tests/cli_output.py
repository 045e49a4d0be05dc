"""Reading the CLI's --json output in tests."""

import json


def json_out(capsys) -> dict:
    """The one JSON object the command printed on stdout."""
    captured = capsys.readouterr()
    lines = captured.out.strip().splitlines()
    assert len(lines) == 1, captured.out  # exactly one JSON object on stdout
    return json.loads(lines[0])


def assert_one_line_error(main, argv, out, name, capsys) -> None:
    """The command exits 2 with one line on stderr naming ``name``, no traceback,
    and writes nothing to ``out``."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("boringbar: error:") and name in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not out.exists()  # nothing written
