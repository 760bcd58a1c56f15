"""Files read whole into memory (meshes, point clouds): found, and not larger than a bound."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["bounded_file"]


def bounded_file(path: str | os.PathLike[str], max_bytes: int, kind: str, advice: str,
                 error: type[Exception]) -> Path:
    """``path`` if it is a file of at most ``max_bytes``.

    Args:
        path: The file.
        max_bytes: The largest size accepted [bytes].
        kind: What the file holds, for the message (e.g. ``"a mesh file"``).
        advice: What to do with a larger file (e.g. ``"simplify it"``).
        error: The exception type raised.

    Raises:
        error: The file is missing, or larger than ``max_bytes``; the message says which.
    """
    path = Path(path)
    if not path.is_file():
        raise error(f"file not found: {path}")
    size = path.stat().st_size
    if size > max_bytes:
        raise error(f"{path.name} is {size / 1e6:.0f} MB, more than the {max_bytes / 1e6:.0f} MB {kind} may have "
                    f"({advice})")
    return path
