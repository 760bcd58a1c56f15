"""MotionBenchMaker's Panda problems, read from the bundled archive at run time.

The archive (``data/panda-problems.tar.bz2``, as KavrakiLab/vamp ships it, problems
0009-0100 of each type) holds ``problems/<type>_panda/scene<NNNN>.yaml`` (a MoveIt planning
scene) and ``request<NNNN>.yaml`` (a motion plan request) per problem; it is read with
:mod:`tarfile`, never unpacked.
"""

from __future__ import annotations

import re
import tarfile
from collections.abc import Sequence
from dataclasses import dataclass
from importlib.resources import as_file, files
from pathlib import Path

import yaml

from dynfab.benchmarks.mbm.moveit import ProblemError, SceneObject, joint_goal, scene_objects, start_positions

__all__ = ["PROBLEM_TYPES", "Problem", "bundled_archive", "load_problems", "problem_from_texts"]

#: The problem types of the archive, in report order.
PROBLEM_TYPES: tuple[str, ...] = ("bookshelf_small", "bookshelf_tall", "bookshelf_thin", "box", "cage",
                                  "table_pick", "table_under_pick")

#: libyaml's safe loader where PyYAML has it (10x faster than the pure-Python one).
_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)

_MEMBER = re.compile(r"problems/(?P<type>\w+)_panda/(?P<kind>scene|request)(?P<number>\d{4})\.yaml")


@dataclass(frozen=True)
class Problem:
    """One MBM problem.

    Attributes:
        type: Its type, one of :data:`PROBLEM_TYPES`.
        number: Its number within the type (9-100 in the bundled set).
        start: Start configuration of the 7 arm joints [rad].
        goal: Goal configuration of the 7 arm joints [rad].
        objects: The scene's collision objects, one per primitive.
    """

    type: str
    number: int
    start: tuple[float, ...]
    goal: tuple[float, ...]
    objects: tuple[SceneObject, ...]

    @property
    def name(self) -> str:
        """``<type>/<NNNN>``, e.g. ``cage/0009``."""
        return f"{self.type}/{self.number:04d}"


def bundled_archive() -> Path:
    """Path of the bundled archive."""
    with as_file(files("dynfab.benchmarks.mbm") / "data" / "panda-problems.tar.bz2") as path:
        return Path(path)


def load_problems(types: Sequence[str] = PROBLEM_TYPES, per_type: int | None = None,
                  archive: Path | None = None, skip: int = 0) -> tuple[Problem, ...]:
    """The problems of ``types`` (in that order, by number), the first ``per_type`` of each
    after the first ``skip``.

    ``archive``: a problems archive in VAMP's format (``problems/<type>_panda/scene<NNNN>.yaml``
    and ``request<NNNN>.yaml`` in a ``.tar.bz2``, e.g. VAMP's own
    ``resources/panda/problems.tar.bz2`` with the problems the bundled one leaves out); None:
    the bundled one.

    Raises:
        ValueError: An unknown type.
        ProblemError: A malformed problem file, a scene without its request, or an archive
            that is missing or not a ``.tar.bz2``.
    """
    unknown = [t for t in types if t not in PROBLEM_TYPES]
    if unknown:
        raise ValueError(f"unknown problem type {unknown[0]!r} (expected one of {', '.join(PROBLEM_TYPES)})")
    texts: dict[tuple[str, int], dict[str, str]] = {}
    path = bundled_archive() if archive is None else Path(archive)
    if not path.is_file():
        raise ProblemError(str(path), "archive", "no such file")
    try:
        with tarfile.open(path, "r:bz2") as tar:
            for member in tar:
                match = _MEMBER.fullmatch(member.name)
                if match is None or match["type"] not in types or not member.isfile():
                    continue
                handle = tar.extractfile(member)
                assert handle is not None  # a regular file
                texts.setdefault((match["type"], int(match["number"])), {})[match["kind"]] = handle.read().decode()
    except (tarfile.TarError, EOFError, OSError) as error:
        raise ProblemError(str(path), "archive", f"not a readable .tar.bz2 ({error})") from None
    problems = []
    for problem_type in types:
        numbers = sorted(number for t, number in texts if t == problem_type)
        for number in numbers[skip:][:per_type]:
            problems.append(problem_from_texts(problem_type, number, texts[(problem_type, number)]))
    return tuple(problems)


def problem_from_texts(problem_type: str, number: int, texts: dict[str, str]) -> Problem:
    """A problem from the YAML texts of its ``scene`` and ``request`` files.

    Raises:
        ProblemError: A file is missing, not YAML, or malformed (names file and field).
    """
    parsed = {}
    for kind in ("scene", "request"):
        file = f"problems/{problem_type}_panda/{kind}{number:04d}.yaml"
        if kind not in texts:
            raise ProblemError(file, kind, "missing from the archive")
        try:
            parsed[kind] = (yaml.load(texts[kind], Loader=_LOADER), file)
        except yaml.YAMLError as error:
            raise ProblemError(file, kind, f"not valid YAML ({str(error).splitlines()[0]})") from None
    request, request_file = parsed["request"]
    scene, scene_file = parsed["scene"]
    return Problem(problem_type, number, start_positions(request, request_file), joint_goal(request, request_file),
                   scene_objects(scene, scene_file))
