"""A clean install (issue 13 item 5): the wheel builds without a warning, installs into a
fresh virtual environment and runs ``dynfab demo`` there; the optional extras exist; and
``./run`` works from any directory with paths relative to the caller.

The fresh environment downloads dynfab's core dependencies from the package registry
(pip's cache makes a second run fast); it does not install the optional extras.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tomllib
import venv
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
EXTRAS = {"mujoco", "view", "robots", "cluster"}


def _quiet_env() -> dict[str, str]:
    """The environment without this test run's virtual environment on the path."""
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH")}
    env["PIP_DISABLE_PIP_VERSION_CHECK"] = "1"
    return env


def _warnings(text: str) -> list[str]:
    return [line for line in text.splitlines() if "warning" in line.lower() or "deprecat" in line.lower()]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """dynfab's wheel, built from a copy of the sources the way ``pip wheel`` builds it."""
    source = tmp_path_factory.mktemp("source")
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy(REPO / name, source / name)
    shutil.copytree(REPO / "dynfab", source / "dynfab", ignore=shutil.ignore_patterns("__pycache__"))
    out = tmp_path_factory.mktemp("wheel")
    build = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-w", str(out), str(source)],
                           capture_output=True, text=True, env=_quiet_env(), timeout=600)
    assert build.returncode == 0, build.stderr[-2000:]
    assert not _warnings(build.stdout + build.stderr), _warnings(build.stdout + build.stderr)
    wheels = list(out.glob("dynfab-*.whl"))
    assert len(wheels) == 1
    return wheels[0]


def test_the_wheel_installs_into_a_fresh_venv_and_runs_the_demo(wheel: Path, tmp_path: Path) -> None:
    env_dir = tmp_path / "venv"
    venv.create(env_dir, with_pip=True)
    python = env_dir / "bin" / "python"
    install = subprocess.run([str(python), "-m", "pip", "install", "--quiet", str(wheel)],
                             capture_output=True, text=True, env=_quiet_env(), timeout=1200)
    assert install.returncode == 0, install.stderr[-2000:]
    work = tmp_path / "work"
    work.mkdir()
    demo = subprocess.run([str(env_dir / "bin" / "dynfab"), "demo", "--json"], cwd=work, capture_output=True,
                          text=True, env=_quiet_env(), timeout=600)
    assert demo.returncode == 0, demo.stderr[-2000:]
    assert '"success": true' in demo.stdout
    assert not _warnings(demo.stderr), _warnings(demo.stderr)
    assert (work / "dynfab-demo.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the core stays small: no optional extra came with it
    listed = subprocess.run([str(python), "-m", "pip", "list", "--format=freeze"], capture_output=True, text=True,
                            env=_quiet_env()).stdout.lower()
    for package in ("mujoco", "viser", "optuna", "distributed", "pybullet"):
        assert f"\n{package}==" not in "\n" + listed, f"{package} installed without its extra"


def test_the_optional_extras_are_declared() -> None:
    project = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert EXTRAS <= set(project["optional-dependencies"])
    assert isinstance(project["license"], str)  # an SPDX expression, not the deprecated table


def test_run_works_from_another_directory_with_caller_relative_paths(tmp_path: Path) -> None:
    elsewhere, here = tmp_path / "elsewhere", tmp_path / "here"
    elsewhere.mkdir()
    here.mkdir()
    shutil.copy(REPO / "examples" / "panda_spheres.yaml", elsewhere / "x.yaml")
    result = subprocess.run([str(REPO / "run"), "dynfab", "run", "../elsewhere/x.yaml", "--json", "--plot", "x.png"],
                            cwd=here, capture_output=True, text=True, env=_quiet_env(), timeout=600)
    assert result.returncode == 0, result.stderr[-2000:]
    assert '"success": true' in result.stdout
    assert (here / "x.png").is_file()
