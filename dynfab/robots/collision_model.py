"""A robot's collision model made automatically: spheres fitted to every link's
``<collision>`` geometry and the sphere pairs to keep apart, cached on disk.

The cache key is the SHA-256 of the URDF's bytes, the bytes of every collision mesh it
references, the fitting and pair-selection parameters and the active / locked joints, so
that any change refits and an unchanged robot loads in milliseconds. The cache folder is
``$DYNFAB_CACHE_DIR`` or ``~/.cache/dynfab``; entries are JSON files.

Where the cache has no entry, the entries that ship with dynfab (``data/collision_models``,
:data:`SHIPPED_DIR`) are looked in, by the same key: the fits of the URDF robots dynfab's
experiments and benchmarks name (example-robot-data 6.0's UR5, with and without its gripper,
Kinova j2s6s200, xArm7, Panda, Z1 and SO-100; a fit takes 20-70 s on this project's 2-core
machine), written by ``python -m dynfab.experiments.shipped_models``. Another version of a
URDF or of its meshes has another key and is fitted as any robot is.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import numpy as np
import trimesh

from dynfab.geometry.sphere_fitting import SphereFitParameters, fit_spheres

from .kinematics import Kinematics
from .link_meshes import LinkMeshError, link_collision_meshes
from .robot import CollisionSphere
from .self_collision import PairSelection, bodies, select_pairs
from .urdf import MeshFile, UrdfModel, load_urdf, urdf_path

__all__ = ["SHIPPED_DIR", "CollisionModel", "LinkFit", "auto_collision_model", "cache_dir", "entry_name",
           "fit_body_spheres", "fit_link_spheres"]

#: Bump when the fit or the file layout changes, so that old entries are not reused (and
#: rewrite the shipped ones: ``python -m dynfab.experiments.shipped_models``).
_CACHE_VERSION = 4
#: The fits that ship with dynfab (module docstring).
SHIPPED_DIR = Path(__file__).parent / "data" / "collision_models"


@dataclass(frozen=True)
class LinkFit:
    """The spheres of one link and how well they cover its collision meshes.

    Attributes:
        link: Link name.
        spheres: Its spheres, centres in the link frame [m].
        coverage: Largest distance of a mesh surface point outside all its spheres [m].
        bulge: Largest distance one of its spheres reaches out of the meshes [m].
    """

    link: str
    spheres: tuple[CollisionSphere, ...]
    coverage: float
    bulge: float


@dataclass(frozen=True)
class CollisionModel:
    """Spheres per link and the self-collision pairs between them.

    Attributes:
        links: One entry per link with collision geometry, in depth-first order.
        self_collision_pairs: Index pairs into :attr:`spheres`.
        from_cache: True if this was read from the disk cache.
    """

    links: tuple[LinkFit, ...]
    self_collision_pairs: tuple[tuple[int, int], ...]
    from_cache: bool = False

    @property
    def spheres(self) -> tuple[CollisionSphere, ...]:
        """All spheres, link by link."""
        return tuple(sphere for fit in self.links for sphere in fit.spheres)


def fit_link_spheres(kinematics: Kinematics,
                     parameters: SphereFitParameters = SphereFitParameters(),
                     per_link: Mapping[str, SphereFitParameters] = MappingProxyType({})) -> tuple[LinkFit, ...]:
    """Spheres for every link of the tree with ``<collision>`` geometry, fitted with
    ``per_link[link]`` where given, else with ``parameters``.

    Links welded to the root whose mesh files are missing are skipped (they never move
    and nothing can be learnt about them); for a link that moves it is an error.

    Raises:
        LinkMeshError: A moving link's collision mesh is missing or unreadable (names
            the link and the URI).
    """
    body_of = bodies(kinematics)
    fixed = body_of[kinematics.root_link]
    fits = []
    for link in kinematics.link_names:
        try:
            meshes = link_collision_meshes(kinematics.model, link)
        except LinkMeshError:
            if body_of[link] == fixed:
                continue
            raise
        if not meshes:
            continue
        fit = fit_spheres(meshes, per_link.get(link, parameters))
        spheres = tuple(CollisionSphere(link, s.center, s.radius) for s in fit.spheres)
        fits.append(LinkFit(link=link, spheres=spheres, coverage=fit.coverage, bulge=fit.bulge))
    return tuple(fits)


def fit_body_spheres(kinematics: Kinematics,
                     parameters: SphereFitParameters = SphereFitParameters()) -> tuple[LinkFit, ...]:
    """Spheres for every *body* (links welded by fixed or locked joints,
    :func:`~dynfab.robots.self_collision.bodies`) with collision geometry: the meshes of its
    links are fitted together, in the frame of its first link with geometry, which the
    spheres are attached to. Fewer spheres than :func:`fit_link_spheres` where welded links
    meet (a flange, a hand and its closed fingers).

    Raises:
        LinkMeshError: A collision mesh that is missing or unreadable.
    """
    body_of = bodies(kinematics)
    at_zero = np.zeros(kinematics.dof)
    grouped: dict[int, tuple[str, list[trimesh.Trimesh]]] = {}
    for link in kinematics.link_names:
        meshes = link_collision_meshes(kinematics.model, link)
        if not meshes:
            continue
        top, gathered = grouped.setdefault(body_of[link], (link, []))
        to_top = np.array(kinematics.transform(at_zero, link, parent=top))
        gathered.extend(mesh.copy().apply_transform(to_top) for mesh in meshes)
    fits = []
    for top, meshes in grouped.values():
        fit = fit_spheres(meshes, parameters)
        spheres = tuple(CollisionSphere(top, s.center, s.radius) for s in fit.spheres)
        fits.append(LinkFit(link=top, spheres=spheres, coverage=fit.coverage, bulge=fit.bulge))
    return tuple(fits)


def auto_collision_model(path: str | os.PathLike[str], joints: Sequence[str] | None = None,
                         locked: Mapping[str, float] | None = None,
                         package_dirs: Sequence[str | os.PathLike[str]] = (),
                         parameters: SphereFitParameters = SphereFitParameters(),
                         selection: PairSelection = PairSelection(),
                         spheres: Sequence[CollisionSphere] | None = None,
                         cache: Path | None = None, shipped: bool = True) -> CollisionModel:
    """Fitted spheres (unless ``spheres`` are given) and selected pairs of a URDF robot.

    The result is cached by content (the URDF, its meshes, the parameters); a fit, which
    takes seconds to a minute, prints one line on stderr before and one after.

    Args:
        path: URDF file, or a ``package://`` / ``file://`` URI of it.
        joints: Active joints (see :class:`~dynfab.robots.kinematics.Kinematics`).
        locked: Values of the other movable joints [rad or m].
        package_dirs: Where ``package://`` mesh URIs resolve.
        parameters: Sphere fitting parameters.
        selection: Pair selection parameters.
        spheres: Use these spheres (one pseudo-link entry each) and only select pairs.
        cache: Cache folder; :func:`cache_dir` if None.
        shipped: Whether the entries that ship with dynfab are looked in where the cache
            has none (:data:`SHIPPED_DIR`).

    Raises:
        OSError, UrdfError: The URDF cannot be read.
        LinkMeshError: A moving link's mesh is missing or unreadable, or no link has
            collision geometry.
        ValueError: Unknown joints or locked names.
    """
    model = load_urdf(path, package_dirs)
    kinematics = Kinematics(model, joints=joints, locked=locked)
    name = _entry_name(urdf_path(path, package_dirs), model, kinematics, parameters, selection, spheres)
    entry = (cache_dir() if cache is None else cache) / name
    for stored in (entry, SHIPPED_DIR / name) if shipped else (entry,):
        if stored.is_file():
            try:
                cached = _decode(json.loads(stored.read_text(encoding="utf-8")))
            except (ValueError, KeyError, TypeError):
                continue  # a damaged entry is refitted and overwritten
            if spheres is None:
                _check_not_empty(cached.links, path, kinematics)
            return cached
    if spheres is None:
        below = set(kinematics.link_names)
        if not any(link.collisions for link in model.links if link.name in below):
            _check_not_empty((), path, kinematics)  # raises before announcing a fit
        print(f"dynfab: fitting collision spheres to the meshes of {model.name or Path(path).name} "
              f"(once; cached in {entry.parent}) ...", file=sys.stderr, flush=True)
        start = time.perf_counter()
        links = fit_link_spheres(kinematics, parameters)
        _check_not_empty(links, path, kinematics)
        print(f"dynfab: fitted {sum(len(fit.spheres) for fit in links)} spheres in "
              f"{time.perf_counter() - start:.1f} s", file=sys.stderr, flush=True)
    else:
        links = tuple(LinkFit(s.link, (s,), float("nan"), float("nan")) for s in spheres)
    all_spheres = [s for fit in links for s in fit.spheres]
    result = CollisionModel(links=links,
                            self_collision_pairs=select_pairs(kinematics, all_spheres, selection))
    entry.parent.mkdir(parents=True, exist_ok=True)
    temporary = entry.with_suffix(f".{os.getpid()}.tmp")
    temporary.write_text(json.dumps(_encode(result)), encoding="utf-8")
    temporary.replace(entry)
    return result


def _check_not_empty(links: Sequence[LinkFit], path: str | os.PathLike[str], kinematics: Kinematics) -> None:
    """Raise if no link got a sphere: the URDF has no collision geometry to fit."""
    if not any(fit.spheres for fit in links):
        raise LinkMeshError(f"no link of {Path(path).name} below '{kinematics.root_link}' has <collision> "
                            "geometry to fit spheres to; give collision_spheres by hand")


def entry_name(path: str | os.PathLike[str], joints: Sequence[str] | None = None,
               locked: Mapping[str, float] | None = None, package_dirs: Sequence[str | os.PathLike[str]] = (),
               parameters: SphereFitParameters = SphereFitParameters(), selection: PairSelection = PairSelection(),
               spheres: Sequence[CollisionSphere] | None = None) -> str:
    """The file name of :func:`auto_collision_model`'s entry for these arguments (its key:
    the module docstring), without fitting anything.

    Raises:
        OSError, UrdfError: The URDF cannot be read.
        ValueError: Unknown joints or locked names.
    """
    model = load_urdf(path, package_dirs)
    kinematics = Kinematics(model, joints=joints, locked=locked)
    return _entry_name(urdf_path(path, package_dirs), model, kinematics, parameters, selection, spheres)


def cache_dir() -> Path:
    """``$DYNFAB_CACHE_DIR`` or ``~/.cache/dynfab``."""
    configured = os.environ.get("DYNFAB_CACHE_DIR")
    return Path(configured) if configured else Path.home() / ".cache" / "dynfab"


def _entry_name(path: Path, model: UrdfModel, kinematics: Kinematics, parameters: SphereFitParameters,
                selection: PairSelection, spheres: Sequence[CollisionSphere] | None) -> str:
    """``collision-<key>.json``, the key the SHA-256 over everything the result depends on."""
    digest = hashlib.sha256()
    digest.update(f"v{_CACHE_VERSION}\n".encode())
    digest.update(path.read_bytes())
    for link in model.links:
        for geometry in link.collisions:
            if isinstance(geometry.shape, MeshFile) and geometry.shape.path is not None:
                digest.update(Path(geometry.shape.path).read_bytes())
    described = {"fit": dataclasses.asdict(parameters), "pairs": dataclasses.asdict(selection),
                 "joints": list(kinematics.joint_names), "locked": sorted(kinematics.locked.items()),
                 "spheres": None if spheres is None else [dataclasses.asdict(s) for s in spheres]}
    digest.update(json.dumps(described, sort_keys=True).encode())
    return f"collision-{digest.hexdigest()}.json"


def _encode(model: CollisionModel) -> dict[str, object]:
    return {"links": [{"link": fit.link, "coverage": fit.coverage, "bulge": fit.bulge,
                       "spheres": [[*s.center, s.radius] for s in fit.spheres]} for fit in model.links],
            "self_collision_pairs": [list(pair) for pair in model.self_collision_pairs]}


def _decode(data: dict[str, object]) -> CollisionModel:
    links = tuple(LinkFit(link=fit["link"], coverage=float(fit["coverage"]), bulge=float(fit["bulge"]),
                          spheres=tuple(CollisionSphere(fit["link"], (x, y, z), r)
                                        for x, y, z, r in fit["spheres"]))
                  for fit in data["links"])  # type: ignore[union-attr]
    pairs = tuple((int(a), int(b)) for a, b in data["self_collision_pairs"])  # type: ignore[union-attr]
    return CollisionModel(links=links, self_collision_pairs=pairs, from_cache=True)
