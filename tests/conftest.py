"""Session-wide test setup."""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest

# Offscreen rendering for MuJoCo videos: MuJoCo picks its OpenGL platform when it is first
# imported, which test collection does before any CLI call could choose it.
os.environ.setdefault("MUJOCO_GL", "egl")

# Planners on CasADi's VM unless the caller says otherwise: the suite builds hundreds of
# planners once each, and compiling each to C (the library's default) would cost more than
# it saves. tests/test_c_backend.py checks the C backend against the VM output for output,
# and tests/test_public_api.py that "c" is the default outside the suite.
os.environ.setdefault("DYNFAB_BACKEND", "vm")


@pytest.fixture(autouse=True, scope="session")
def collision_model_cache(request: pytest.FixtureRequest) -> Iterator[None]:
    """Automatic collision models (``collision_spheres: auto``) go to pytest's persistent
    cache folder, not the user's ``~/.cache/dynfab``; entries are keyed by content, so every
    test that fits the same arm shares one fit."""
    folder = str(request.config.cache.mkdir("dynfab-collision-models"))
    previous = os.environ.get("DYNFAB_CACHE_DIR")
    os.environ["DYNFAB_CACHE_DIR"] = folder
    yield
    if previous is None:
        os.environ.pop("DYNFAB_CACHE_DIR", None)
    else:
        os.environ["DYNFAB_CACHE_DIR"] = previous
