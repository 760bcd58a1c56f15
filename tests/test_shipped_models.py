"""The collision models that ship with dynfab (dynfab/experiments/shipped_models.py): the
folder holds exactly the entries of the robots listed, a first load reads them without
fitting, and a fresh fit of the smallest one's spheres equals its entry."""

from __future__ import annotations

import importlib.metadata
import json
from pathlib import Path

import numpy as np
import pytest

from dynfab.experiments.arms import installed_urdf
from dynfab.experiments.shipped_models import SHIPPED_ROBOTS, shipped_names
from dynfab.robots.collision_model import SHIPPED_DIR, auto_collision_model, entry_name, fit_link_spheres
from dynfab.robots.kinematics import Kinematics
from dynfab.robots.urdf import load_urdf

#: The example-robot-data the shipped entries were fitted to (another version has other keys).
FITTED_ON = "6.0.0"

pytestmark = pytest.mark.skipif(importlib.metadata.version("example-robot-data") != FITTED_ON,
                                reason=f"the shipped fits are of example-robot-data {FITTED_ON}")


def test_the_folder_holds_exactly_the_entries_of_the_robots_listed() -> None:
    names = shipped_names()
    assert len(names) == len(SHIPPED_ROBOTS) == 8
    assert {path.name for path in SHIPPED_DIR.glob("*.json")} == set(names)


def test_a_listed_robot_loads_from_its_entry_without_fitting_or_writing(tmp_path: Path) -> None:
    robot = next(r for r in SHIPPED_ROBOTS if r.urdf.endswith("ur5_gripper.urdf"))
    model = auto_collision_model(installed_urdf(robot.urdf), robot.joints, dict(robot.locked), cache=tmp_path)
    assert model.from_cache and len(model.spheres) == 71 and len(model.self_collision_pairs) == 128
    assert list(tmp_path.iterdir()) == []


def test_a_fresh_fit_of_the_smallest_listed_robot_has_the_spheres_of_its_entry() -> None:
    """Z1 (33 spheres, 6 s); its pairs (a selection over 6000 configurations, half a minute) are not fitted again."""
    robot = next(r for r in SHIPPED_ROBOTS if r.urdf.endswith("z1.urdf"))
    urdf = installed_urdf(robot.urdf)
    stored = json.loads((SHIPPED_DIR / entry_name(urdf, robot.joints, dict(robot.locked))).read_text())
    fitted = fit_link_spheres(Kinematics(load_urdf(urdf), joints=robot.joints, locked=dict(robot.locked)))
    assert [fit.link for fit in fitted] == [entry["link"] for entry in stored["links"]]
    for fit, entry in zip(fitted, stored["links"], strict=True):
        np.testing.assert_allclose([[*s.center, s.radius] for s in fit.spheres], entry["spheres"], atol=1e-9)
