"""The `bsv` console script routes its sub-commands and reports errors with an exit status."""

from __future__ import annotations

import pytest

from bsv.cli import main


def test_help_and_version(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--help"]) == 0
    assert "demo" in capsys.readouterr().out
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.startswith("bsv ")


def test_unknown_command_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["frobnicate"]) == 2
    assert "unknown command" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["demo", "process", "calibrate", "capture", "bench", "cohort"])
def test_every_command_has_help(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as e:
        main([command, "--help"])
    assert e.value.code == 0
    assert "usage" in capsys.readouterr().out.lower()


def test_process_without_capture_fails_cleanly(tmp_path, capsys: pytest.CaptureFixture[str]) -> None:  # type: ignore[no-untyped-def]
    code = main(["process", str(tmp_path / "missing"), "--calibration", str(tmp_path / "c.json"), "-o", str(tmp_path / "o")])
    assert code != 0
    assert "missing" in capsys.readouterr().err


@pytest.mark.parametrize("args", [["--subject", "-1"], ["--seed", "-5"], ["--subject", "two"]])
def test_demo_refuses_negative_or_non_numeric_indices(args: list[str], tmp_path, capsys: pytest.CaptureFixture[str]) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(SystemExit) as e:
        main(["demo", "-o", str(tmp_path / "out"), *args])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and args[0] in err
    assert not (tmp_path / "out").exists()
