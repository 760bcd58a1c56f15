"""``--archive``: MotionBenchMaker problems read from another archive in VAMP's format (the
problems 1-8 the bundled archive leaves out ship in VAMP's own)."""

from __future__ import annotations

import io
import tarfile
from pathlib import Path

import pytest

from dynfab.benchmarks.mbm.moveit import ProblemError
from dynfab.benchmarks.mbm.problems import bundled_archive, load_problems
from dynfab.cli import main


def _renumbered_archive(path: Path, problem_type: str, number: int, as_number: int) -> Path:
    """An archive with one problem of the bundled one, renumbered ``as_number``."""
    with tarfile.open(bundled_archive(), "r:bz2") as source, tarfile.open(path, "w:bz2") as target:
        for kind in ("scene", "request"):
            handle = source.extractfile(f"problems/{problem_type}_panda/{kind}{number:04d}.yaml")
            assert handle is not None
            data = handle.read()
            info = tarfile.TarInfo(f"problems/{problem_type}_panda/{kind}{as_number:04d}.yaml")
            info.size = len(data)
            target.addfile(info, io.BytesIO(data))
    return path


def test_problems_come_from_the_given_archive(tmp_path: Path) -> None:
    archive = _renumbered_archive(tmp_path / "problems.tar.bz2", "box", 10, 3)
    (bundled,) = load_problems(["box"], per_type=1, skip=1)  # box/0010
    (problem,) = load_problems(["box"], archive=archive)
    assert (problem.number, bundled.number) == (3, 10)
    assert (problem.start, problem.goal, problem.objects) == (bundled.start, bundled.goal, bundled.objects)
    assert load_problems(["cage"], archive=archive) == ()


@pytest.mark.parametrize("content", [None, b"not an archive"])
def test_a_missing_or_unreadable_archive_names_the_file(tmp_path: Path, content: bytes | None) -> None:
    path = tmp_path / "problems.tar.bz2"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(ProblemError, match="problems.tar.bz2: archive: " + ("no such file" if content is None
                                                                            else "not a readable")):
        load_problems(["box"], archive=path)


def test_the_command_refuses_a_missing_archive(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["benchmark", "mbm", "--archive", str(tmp_path / "none.tar.bz2"), "--types", "box", "--problems", "1",
                 "--out", str(tmp_path / "out")])
    assert code == 2
    assert "none.tar.bz2: archive: no such file" in capsys.readouterr().err
