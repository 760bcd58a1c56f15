"""Where the files named in a URDF are: ``package://``, ``file://`` and relative URIs.

A robot description as it ships names its meshes ``package://NAME/sub/path.stl`` (a ROS
package), ``file:///abs/path.stl`` or a path relative to the URDF file. Without ROS the
package has to be found on disk; candidates, in this order:

1. every folder of ``package_dirs`` and of the ``DYNFAB_PACKAGE_PATH`` environment variable
   (``os.pathsep``-separated), as ``DIR/NAME/sub/path`` or, if ``DIR`` is itself named
   ``NAME``, ``DIR/sub/path``;
2. the URDF's folder and each of its parents, the same two ways (a description unpacked
   anywhere finds its own package: ``.../NAME/urdf/robot.urdf`` names ``package://NAME/...``);
3. the robot data that ships on PyPI, when installed: ``example-robot-data``
   (``package://example-robot-data/robots/ur_description/urdf/ur5_robot.urdf``) and
   ``pybullet_data`` (``package://pybullet_data/franka_panda/panda.urdf``).

A relative URI resolves against the URDF's folder. The first candidate that is a file wins.
"""

from __future__ import annotations

import functools
import importlib.metadata
import importlib.util
import os
from collections.abc import Iterator, Sequence
from pathlib import Path
from urllib.parse import unquote

__all__ = ["PACKAGE_PATH_VARIABLE", "package_search_dirs", "resolve_uri", "shipped_package_dirs"]

#: Environment variable with extra package folders, like ROS_PACKAGE_PATH.
PACKAGE_PATH_VARIABLE = "DYNFAB_PACKAGE_PATH"


def package_search_dirs(package_dirs: Sequence[str | os.PathLike[str]] = ()) -> list[Path]:
    """``package_dirs`` followed by the folders of ``DYNFAB_PACKAGE_PATH``."""
    extra = [part for part in os.environ.get(PACKAGE_PATH_VARIABLE, "").split(os.pathsep) if part]
    return [Path(d) for d in list(package_dirs) + extra]


@functools.cache
def shipped_package_dirs() -> tuple[Path, ...]:
    """The data folders of installed robot-description wheels (example-robot-data's
    ``share/example-robot-data``, ``pybullet_data``); empty if none is installed."""
    found = []
    try:
        distribution = importlib.metadata.distribution("example-robot-data")
        marker = next((f for f in distribution.files or () if str(f).endswith("/package.xml")
                       and "example-robot-data" in str(f)), None)
        if marker is not None:
            found.append(Path(str(distribution.locate_file(marker))).parent)
    except importlib.metadata.PackageNotFoundError:
        pass
    spec = importlib.util.find_spec("pybullet_data")
    if spec is not None and spec.origin is not None:
        found.append(Path(spec.origin).parent)
    return tuple(found)


def resolve_uri(uri: str, base_dir: str | os.PathLike[str] | None,
                package_dirs: Sequence[str | os.PathLike[str]] = ()) -> Path | None:
    """The file a URI names, or ``None`` if no candidate exists (module docstring).

    Args:
        uri: A ``filename`` of a URDF ``<mesh>``, or a URDF path in a scenario.
        base_dir: The folder relative paths start from (the URDF's, or the scenario's);
            ``None`` if there is none.
        package_dirs: Extra folders for ``package://`` URIs.
    """
    search = package_search_dirs(package_dirs) + list(shipped_package_dirs())
    for candidate in _candidates(uri.strip(), None if base_dir is None else Path(base_dir), search):
        if candidate.is_file():
            return candidate.resolve()
    return None


def _candidates(uri: str, base_dir: Path | None, search: list[Path]) -> Iterator[Path]:
    if uri.startswith("package://"):
        package, _, rest = uri[len("package://"):].partition("/")
        roots = list(search)
        if base_dir is not None:
            roots += [base_dir, *base_dir.resolve().parents]
        for root in roots:
            yield root / package / rest
            if root.name == package:
                yield root / rest
        return
    if uri.startswith("file://"):
        yield Path(unquote(uri[len("file://"):]))
        return
    path = Path(uri)
    if path.is_absolute():
        yield path
    elif base_dir is not None:
        yield base_dir / path
