"""Where the mesh files named in a URDF are: ``package://``, ``file://`` and relative URIs.

A robot description as it ships names its meshes ``package://NAME/sub/path.stl`` (a ROS
package), ``file:///abs/path.stl`` or a path relative to the URDF file. Without ROS the
package has to be found on disk; candidates, in this order:

1. every folder of ``package_dirs`` and of the ``DYNFAB_PACKAGE_PATH`` environment variable
   (``os.pathsep``-separated), as ``DIR/NAME/sub/path`` or, if ``DIR`` is itself named
   ``NAME``, ``DIR/sub/path``;
2. the URDF's folder and each of its parents, the same two ways (a description unpacked
   anywhere finds its own package: ``.../NAME/urdf/robot.urdf`` names ``package://NAME/...``).

A relative URI resolves against the URDF's folder. The first candidate that is a file wins.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from pathlib import Path
from urllib.parse import unquote

__all__ = ["PACKAGE_PATH_VARIABLE", "package_search_dirs", "resolve_mesh_uri"]

#: Environment variable with extra package folders, like ROS_PACKAGE_PATH.
PACKAGE_PATH_VARIABLE = "DYNFAB_PACKAGE_PATH"


def package_search_dirs(package_dirs: Sequence[str | os.PathLike[str]] = ()) -> list[Path]:
    """``package_dirs`` followed by the folders of ``DYNFAB_PACKAGE_PATH``."""
    extra = [part for part in os.environ.get(PACKAGE_PATH_VARIABLE, "").split(os.pathsep) if part]
    return [Path(d) for d in list(package_dirs) + extra]


def resolve_mesh_uri(uri: str, base_dir: str | os.PathLike[str] | None,
                     package_dirs: Sequence[str | os.PathLike[str]] = ()) -> Path | None:
    """The file a mesh URI names, or ``None`` if no candidate exists (module docstring).

    Args:
        uri: The ``filename`` attribute of a URDF ``<mesh>``.
        base_dir: The URDF's folder (``None`` if the URDF came from a string).
        package_dirs: Extra folders for ``package://`` URIs.
    """
    for candidate in _candidates(uri.strip(), None if base_dir is None else Path(base_dir),
                                 package_search_dirs(package_dirs)):
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
