"""The built-in Panda without its fine spheres, for the guidance tests whose tight scenes (a
goal the spheres refuse, a way too narrow for them) are built on its planning spheres: the
fine spheres' second look (dynfab.robots.panda_fine_spheres) frees some of those, so these
tests would no longer test what they are about. The second look has its own tests
(tests/test_configuration_checker.py, tests/test_fine_spheres.py)."""

from __future__ import annotations

from dataclasses import replace

from dynfab.robots import load_robot
from dynfab.robots.robot import Robot


def panda_on_planning_spheres() -> Robot:
    """The built-in Panda, guidance checking its planning spheres alone."""
    return replace(load_robot("panda"), fine_spheres=None)
