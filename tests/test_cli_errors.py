"""Only input errors become `gpmotion: error: ...` and exit 2; a bug shows its traceback."""
import json

import pytest

from gpmotion import cli


def _command_raising(monkeypatch, exc_factory):
    def command(args):
        raise exc_factory()
    monkeypatch.setitem(cli.COMMANDS, "show", command)


@pytest.mark.parametrize("exc", [lambda: KeyError("lost key"), lambda: RuntimeError("broken"),
                                 lambda: TypeError("bad call"), lambda: json.loads("{")])
def test_a_bug_is_not_dressed_up_as_an_input_error(monkeypatch, exc):
    """KeyError / RuntimeError / TypeError, and a ValueError raised inside the
    standard library (json), propagate with their traceback."""
    _command_raising(monkeypatch, exc)
    with pytest.raises(Exception) as info:
        cli.main(["show", "lamp_hop"])
    assert not isinstance(info.value, SystemExit)


def _bad_number():
    from gpmotion.records import validate_number
    return validate_number("--thing", -1, lo=0)          # raises inside gpmotion: input


@pytest.mark.parametrize("exc, needle", [
    (_bad_number, "--thing"),
    (lambda: FileNotFoundError(2, "No such file or directory", "x.json"), "x.json")])
def test_our_input_errors_are_one_line_and_exit_2(monkeypatch, capsys, exc, needle):
    _command_raising(monkeypatch, exc)
    assert cli.main(["show", "lamp_hop"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gpmotion: error:") and needle in err and "\n" not in err


def test_an_unknown_task_is_still_one_line(capsys):
    assert cli.main(["show", "lamp_hopp"]) == 2
    assert "did you mean 'lamp_hop'" in capsys.readouterr().err
