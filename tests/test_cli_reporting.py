"""How a batch of runs (experiment, benchmark, tuning) ends on the command line: its
result, or an exit status with the reason on stderr (``dynfab.cli_arguments.reported``)."""

from __future__ import annotations

import pytest

from dynfab.cli_arguments import ExitStatus, reported
from dynfab.experiments.series import RunError


class _BadInput(ValueError):
    pass


def _raising(error: BaseException):
    def work() -> None:
        raise error
    return work


def test_a_batch_that_finishes_gives_its_result() -> None:
    assert reported(lambda: [1, 2], (_BadInput,), "resume") == [1, 2]


@pytest.mark.parametrize(("error", "code", "message"), [
    (_BadInput("--problems: expected 1 or more"), 2, "dynfab: error: --problems: expected 1 or more"),
    (RunError("scenarios/box_0017.yaml raised"), 1, "dynfab: run failed: scenarios/box_0017.yaml raised"),
    (KeyboardInterrupt(), 130, "dynfab: interrupted; finished runs are in out/runs.jsonl"),
])
def test_a_failed_batch_gives_its_exit_status_and_says_why(error: BaseException, code: int, message: str,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    assert reported(_raising(error), (_BadInput,), "finished runs are in out/runs.jsonl") == ExitStatus(code)
    assert message in capsys.readouterr().err


def test_an_error_that_is_not_bad_input_is_not_swallowed() -> None:
    with pytest.raises(ZeroDivisionError):
        reported(_raising(ZeroDivisionError("bug")), (_BadInput,), "resume")
