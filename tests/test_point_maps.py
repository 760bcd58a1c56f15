"""Maps of points on links (collision-sphere centres): the per-link closed form against
automatic differentiation and finite differences."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from dynfab.fabric.maps import DifferentialMap
from dynfab.fabric.point_maps import link_point_maps
from dynfab.robots import load_robot


@pytest.mark.parametrize("name", ["panda", "boxer-panda"])
def test_point_maps_equal_automatic_differentiation_and_finite_differences(name: str) -> None:
    robot = load_robot(name)
    kin = robot.kinematics
    q, qdot = ca.SX.sym("q", kin.dof), ca.SX.sym("qdot", kin.dof)
    points = [(s.link, s.center) for s in robot.collision_spheres] + [("panda_link4", (0.0, 0.0, 0.0)),
                                                                     ("panda_hand", (0.03, -0.02, 0.05))]
    maps = link_point_maps(kin, q, qdot, points)
    reference = [DifferentialMap.from_expression(kin.position(q, link, offset=offset), q, qdot)
                 for link, offset in points]
    stacked = ca.Function("maps", [q, qdot], [ca.vertcat(*[m.phi for m in maps]), ca.vertcat(*[m.jacobian for m in maps]),
                                               ca.vertcat(*[m.jdot_qdot for m in maps])])
    expected = ca.Function("ad", [q, qdot], [ca.vertcat(*[m.phi for m in reference]),
                                             ca.vertcat(*[m.jacobian for m in reference]),
                                             ca.vertcat(*[m.jdot_qdot for m in reference])])
    rng = np.random.default_rng(4)
    h = 1e-6
    for _ in range(5):
        x, v = rng.uniform(-1.5, 1.5, kin.dof), rng.normal(0.0, 1.0, kin.dof)
        phi, jacobian, curvature = (np.array(value) for value in stacked(x, v))
        for mine, theirs in zip((phi, jacobian, curvature), expected(x, v)):
            np.testing.assert_allclose(mine, np.array(theirs), atol=1e-12)
        for i in range(kin.dof):  # J column by central differences of phi
            step = np.eye(kin.dof)[i] * h
            column = (np.array(stacked(x + step, v)[0]) - np.array(stacked(x - step, v)[0])) / (2 * h)
            np.testing.assert_allclose(jacobian[:, i:i + 1], column, atol=1e-7)
        # J̇ q̇ = d/dt (J q̇) along q̇ with q̇ fixed: central differences of J q̇ along q̇
        ahead, behind = np.array(stacked(x + h * v, v)[1]), np.array(stacked(x - h * v, v)[1])
        np.testing.assert_allclose(curvature, ((ahead - behind) @ v)[:, None] / (2 * h), atol=1e-6)


def test_planar_points_keep_x_and_y() -> None:
    robot = load_robot("boxer")
    kin = robot.kinematics
    q, qdot = ca.SX.sym("q", kin.dof), ca.SX.sym("qdot", kin.dof)
    (full,) = link_point_maps(kin, q, qdot, [("chassis_link", (0.25, 0.14, 0.1442))])
    (planar,) = link_point_maps(kin, q, qdot, [("chassis_link", (0.25, 0.14, 0.1442))], dims=2)
    assert planar.phi.shape == (2, 1) and planar.jacobian.shape == (2, kin.dof)
    values = ca.Function("f", [q, qdot], [full.phi[:2] - planar.phi, full.jdot_qdot[:2] - planar.jdot_qdot])
    for value in values([0.3, -0.2, 0.7], [0.5, 0.1, -0.4]):
        assert np.allclose(np.array(value), 0.0)


def test_per_link_form_costs_fewer_instructions_than_automatic_differentiation() -> None:
    robot = load_robot("panda")
    kin = robot.kinematics
    q, qdot = ca.SX.sym("q", kin.dof), ca.SX.sym("qdot", kin.dof)
    points = [(f"panda_link{i}", (0.01 * k, -0.02 * k, 0.03)) for i in range(3, 8) for k in range(5)]

    def instructions(maps: list[DifferentialMap]) -> int:
        outputs = [ca.vertcat(*[m.jacobian for m in maps]), ca.vertcat(*[m.jdot_qdot for m in maps])]
        return ca.Function("f", [q, qdot], outputs, {"cse": True}).n_instructions()

    closed_form = instructions(link_point_maps(kin, q, qdot, points))
    automatic = instructions([DifferentialMap.from_expression(kin.position(q, link, offset=offset), q, qdot)
                              for link, offset in points])
    assert closed_form < 0.65 * automatic, (closed_form, automatic)
