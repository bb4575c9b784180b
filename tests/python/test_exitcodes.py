"""The one error-to-exit-status rule shared by every front end (bsv.exitcodes)."""

from __future__ import annotations

import pytest

from bsv import errors
from bsv.exitcodes import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE, exit_code, run_command


@pytest.mark.parametrize(
    ("exc", "code"),
    [
        (errors.OutputExistsError("out exists"), EXIT_USAGE),
        (errors.InputError("bad array"), EXIT_USAGE),
        (errors.RegistrationParameterError("bad alpha"), EXIT_USAGE),
        (errors.BenchError("bad config"), EXIT_USAGE),
        (errors.FormatError("bad file"), EXIT_FAILED),
        (errors.RegistrationNumericError("diverged"), EXIT_FAILED),
        (errors.CalibrationFileError("no calibration"), EXIT_FAILED),
        (KeyboardInterrupt(), EXIT_INTERRUPTED),
    ],
)
def test_exit_code_rule(exc: BaseException, code: int) -> None:
    assert exit_code(exc) == code


def test_run_command_prints_one_line_and_returns_the_status(capsys: pytest.CaptureFixture[str]) -> None:
    def fails() -> int:
        raise errors.OutputExistsError("report.html already exists; pass --overwrite")

    assert run_command("bsv demo", fails) == EXIT_USAGE
    err = capsys.readouterr().err
    assert err == "bsv demo: error: report.html already exists; pass --overwrite\n"
    assert run_command("bsv demo", lambda: None) == EXIT_OK
    assert run_command("bsv demo", lambda: 1) == EXIT_FAILED


def test_run_command_turns_ctrl_c_into_130(capsys: pytest.CaptureFixture[str]) -> None:
    def interrupted() -> int:
        raise KeyboardInterrupt

    assert run_command("bsv process", interrupted) == EXIT_INTERRUPTED
    assert "interrupted" in capsys.readouterr().err


def test_run_command_lets_programming_errors_through() -> None:
    def bug() -> int:
        raise ZeroDivisionError

    with pytest.raises(ZeroDivisionError):
        run_command("bsv demo", bug)
