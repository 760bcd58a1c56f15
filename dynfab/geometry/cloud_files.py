"""Point-cloud files read into raw (N, 3) arrays, in bounded time and memory.

- ``.npy``: an (N, 3) array of numbers [m] (numpy's format; no pickled objects), read
  memory-mapped so that :meth:`~dynfab.geometry.point_cloud.PointCloud.from_points` reduces
  it chunk by chunk;
- ``.ply``: the vertices of a PLY file, ASCII or binary (trimesh; faces, if any, ignored);
- ``.pcd``: the ``x y z`` fields of a Point Cloud Library file, ``DATA ascii`` or
  ``binary`` (a strict reader here; ``binary_compressed`` is refused: re-save it uncompressed).

A file larger than :data:`MAX_CLOUD_BYTES` is refused before it is read. NaN or infinite
rows are kept here (the cloud drops and counts them).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from dynfab.geometry.bounded_files import bounded_file

__all__ = ["MAX_CLOUD_BYTES", "CloudFileError", "read_points"]

#: Largest cloud file read [bytes] (4·10⁷ points of three float32, or 2·10⁷ of float64).
MAX_CLOUD_BYTES = 500_000_000

_PCD_TYPES = {("F", 4): "f4", ("F", 8): "f8", ("I", 1): "i1", ("I", 2): "i2", ("I", 4): "i4", ("I", 8): "i8",
              ("U", 1): "u1", ("U", 2): "u2", ("U", 4): "u4", ("U", 8): "u8"}
_PCD_KEYS = ("VERSION", "FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "VIEWPOINT", "POINTS", "DATA")


class CloudFileError(ValueError):
    """A point-cloud file that is missing, too large, malformed, or of an unknown format."""


def read_points(path: str | os.PathLike[str]) -> NDArray[np.floating]:
    """The raw points (N, 3) [m] of a ``.npy``, ``.ply`` or ``.pcd`` file (module docstring).

    Raises:
        CloudFileError: the file is missing, larger than :data:`MAX_CLOUD_BYTES`, of another
            format, or malformed; the message says which.
    """
    path = bounded_file(path, MAX_CLOUD_BYTES, "a point-cloud file", "downsample it", CloudFileError)
    suffix = path.suffix.lower()
    readers = {".npy": _read_npy, ".ply": _read_ply, ".pcd": _read_pcd}
    if suffix not in readers:
        raise CloudFileError(f"{path.name}: unknown point-cloud format {suffix or '(no extension)'} "
                             "(expected .npy, .ply or .pcd)")
    points = readers[suffix](path)
    if points.ndim != 2 or points.shape[1] != 3 or not np.issubdtype(points.dtype, np.number):
        raise CloudFileError(f"{path.name}: expected an (N, 3) array of numbers, got shape {points.shape} "
                             f"of {points.dtype}")
    return points


def _read_npy(path: Path) -> NDArray[np.floating]:
    try:
        return np.load(path, mmap_mode="r", allow_pickle=False)
    except (ValueError, OSError, EOFError) as error:
        raise CloudFileError(f"{path.name} cannot be read as a .npy array ({_first_line(error)})") from None


def _read_ply(path: Path) -> NDArray[np.floating]:
    import trimesh

    try:
        loaded = trimesh.load(str(path), file_type="ply", process=False)
    except Exception as error:  # trimesh raises many kinds of errors on bad files
        raise CloudFileError(f"{path.name} cannot be read as a PLY file ({type(error).__name__}: "
                             f"{_first_line(error)})") from None
    vertices = getattr(loaded, "vertices", None)
    if vertices is None:
        raise CloudFileError(f"{path.name}: a PLY file without vertices")
    return np.asarray(vertices, dtype=float).reshape(-1, 3) if len(vertices) else np.zeros((0, 3))


def _read_pcd(path: Path) -> NDArray[np.floating]:
    with path.open("rb") as file:
        header: dict[str, list[str]] = {}
        while "DATA" not in header:
            line = file.readline(4096)
            if not line:
                raise CloudFileError(f"{path.name}: PCD header ends before its DATA line")
            text = line.decode("ascii", errors="replace").strip()
            if not text or text.startswith("#"):
                continue
            key, *values = text.split()
            if key not in _PCD_KEYS:
                raise CloudFileError(f"{path.name}: PCD header line {text[:40]!r} is not one of {', '.join(_PCD_KEYS)}")
            header[key] = values
        body = file.read()
    return _pcd_points(path.name, header, body)


def _pcd_points(name: str, header: dict[str, list[str]], body: bytes) -> NDArray[np.floating]:
    """The x, y, z columns of a PCD body under its header."""
    for key in ("FIELDS", "SIZE", "TYPE", "POINTS"):
        if key not in header:
            raise CloudFileError(f"{name}: PCD header has no {key} line")
    fields, sizes, types = header["FIELDS"], header["SIZE"], header["TYPE"]
    counts = header.get("COUNT", ["1"] * len(fields))
    if not len(fields) == len(sizes) == len(types) == len(counts):
        raise CloudFileError(f"{name}: PCD header's FIELDS, SIZE, TYPE and COUNT differ in length")
    missing = [axis for axis in "xyz" if axis not in fields]
    if missing:
        raise CloudFileError(f"{name}: PCD has no {', '.join(missing)} field (FIELDS {' '.join(fields)})")
    try:
        count = int(header["POINTS"][0])
        dtypes = [(f"{field}_{k}", _PCD_TYPES[(kind, int(size))], (int(number),))
                  for k, (field, size, kind, number) in enumerate(zip(fields, sizes, types, counts))]
    except (KeyError, ValueError, IndexError):
        raise CloudFileError(f"{name}: PCD header has a bad SIZE, TYPE, COUNT or POINTS value") from None
    record = np.dtype([(label, "<" + code, shape) for label, code, shape in dtypes])
    columns = [f"{field}_{fields.index(field)}" for field in "xyz"]
    mode = header["DATA"][0] if header["DATA"] else ""
    if mode == "binary":
        if len(body) < count * record.itemsize:
            raise CloudFileError(f"{name}: PCD binary data holds {len(body)} bytes, fewer than the "
                                 f"{count * record.itemsize} of its {count} points")
        table = np.frombuffer(body, dtype=record, count=count)
        return np.stack([table[column][:, 0].astype(float) for column in columns], axis=1)
    if mode == "ascii":
        width = sum(int(number) for number in counts)
        try:
            values = np.array(body.split(), dtype=float)
        except ValueError:
            raise CloudFileError(f"{name}: PCD ascii data holds something other than numbers") from None
        if values.size != count * width:
            raise CloudFileError(f"{name}: PCD ascii data holds {values.size} numbers, not the {count} x {width} "
                                 "its header gives")
        offsets = np.cumsum([0] + [int(number) for number in counts])
        table = values.reshape(count, width)
        return np.stack([table[:, offsets[fields.index(axis)]] for axis in "xyz"], axis=1)
    raise CloudFileError(f"{name}: PCD DATA {mode or '(none)'} is not read (expected ascii or binary; "
                         "re-save a binary_compressed file uncompressed)")


def _first_line(error: Exception) -> str:
    text = str(error)
    return text.splitlines()[0] if text else type(error).__name__
