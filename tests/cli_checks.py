"""How the CLI tests check a refusal: exit code 2 and one clear error line."""
import re

from gpmotion.cli import main

_TMP = re.compile(r"/tmp/pytest-of-[^/]+/pytest-\d+/[^/]+")


def one_line_error(capsys, *needles):
    """The captured stderr is one "gpmotion: error:" line naming every needle
    (pytest's tmp folders, named for the test, read as <tmp> on both sides: a
    needle is not found in a test's name)."""
    err = capsys.readouterr().err.strip()
    assert err.startswith("gpmotion: error:") and "\n" not in err, err
    for n in needles:
        assert _TMP.sub("<tmp>", n) in _TMP.sub("<tmp>", err), (n, err)
    return err


def refused(capsys, argv, *needles):
    """``gpmotion ARGV`` exits 2 with one error line naming every needle."""
    capsys.readouterr()                 # only what this call prints
    assert main(argv) == 2
    return one_line_error(capsys, *needles)


def refused_before_the_directory(capsys, argv, out, *needles):
    """As :func:`refused`, and the run directory ``out`` is never made."""
    err = refused(capsys, argv, *needles)
    assert not out.exists()
    return err
