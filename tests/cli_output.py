"""Reading the CLI's --json output in tests."""

import json


def json_out(capsys) -> dict:
    """The one JSON object the command printed on stdout."""
    captured = capsys.readouterr()
    lines = captured.out.strip().splitlines()
    assert len(lines) == 1, captured.out  # exactly one JSON object on stdout
    return json.loads(lines[0])
