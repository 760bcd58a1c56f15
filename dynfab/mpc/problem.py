"""The MPC baseline's nonlinear program, built once and solved with IPOPT or fatrop.

Model (:mod:`dynfab.mpc.model`): state ``x = (q, u)`` with ``u`` the robot's velocity
coordinates, input ``u̇`` held constant over each stage of length h [s],
``x_{k+1} = F(x_k, u̇_k)``:

- holonomic robots, ``u = q̇``, a second-order integrator per joint (exact):

      q_{k+1} = q_k + h q̇_k + ½ h² q̈_k,        q̇_{k+1} = q̇_k + h q̈_k;

- robots on a differential-drive base, ``q = (x, y, θ, arm)``, ``u = (v, ω, arm rates)``:
  ``u_{k+1} = u_k + h u̇_k``, the arm as above, the base pose along the unicycle arc of
  the stage's mid-point speeds (``ẏ cos θ − ẋ sin θ = 0`` holds by construction).

Over stages k = 0..H at times t_k = t + k h, with one slack ``s_k ≥ 0`` per stage:

    min   Σ_{k=1..H} [ w_g Σ_i ω_i ||e_i(q_k) − r_i(t_k)||² + w_v ||u_k||² + w_s s_k ]
        + Σ_{k=0..H-1} w_u ||u̇_k||²
    s.t.  (q_0, u_0) = (q(t), u(t))                                        initial state
          x_{k+1} = F(x_k, u̇_k),                                          k = 0..H-1
          ||p_j(q_k) − c_o(t_k)|| − r_j − r_o ≥ δ − s_k  every robot sphere j, obstacle o
          q_min ≤ q_k ≤ q_max,  |u_k| ≤ u_max                             k = 1..H
          |u̇_k| ≤ a_max                                                    k = 0..H-1

``e_i`` is the position of the goal point (the link origin plus a link-frame offset) on
the goal's axes in its parent link's frame [m] (or the joint vector for joint goals
[rad]; or, for orientation goals, the stacked world directions ``R a`` of link axes ``a``,
so that ``||e_i − r_i||`` is the chord between unit directions), ``r_i(t_k)`` the goal's reference at the
stage time, ``p_j`` a collision sphere's centre and ``c_o(t_k)`` an obstacle's centre
at the stage time, ``δ ≥ 0`` the collision margin (``MpcConfig.collision_margin``,
0 in the benchmark); planar robots (the point robot, ``boxer``) measure distances in x-y
only. ``q_min``, ``q_max`` are the URDF's joint limits (infinite ones left out: on a base,
the yaw is free and x, y keep the URDF's ±10 m); ``u_max`` and ``a_max`` are the robot's velocity
and acceleration limits (``robot.limits``; on a base, ``v`` and ``ω`` first).
Stage 0 carries no collision or limit constraint and no goal cost: its state is fixed
by the measurement, so they could only make the problem infeasible. Spheres that no
joint moves are left out for the same reason. Distances are smoothed,
``sqrt(||d||² + ε²)`` with ε = 1e-6 m, so that their gradient exists at ``d = 0``. As in
the benchmark, collisions are constrained at the stage times only: in between, a sphere
moving a distance L per stage past an obstacle at the constraint's boundary can cut up
to about L² / (8 (r_j + r_o)) into it (millimetres at 1 m/s; a turning base moves its
front discs faster than ``v``: in Experiment 4 up to 2.1 m/s, L = 0.21 m, up to 11 mm
past a disc of 0.3 m; measured at most 7.3 mm on seeds 0..9). ``MpcConfig.collision_margin``
can ask for that much clearance at the stage times instead.

Decision variables and constraints are ordered stage by stage (x_0, u̇_0, x_1, u̇_1, ...,
gap-closing rows ``x_{k+1} − F(x_k, u̇_k) = 0`` first in each stage), the layout fatrop's
``structure_detection: auto`` recognises; IPOPT does not care.

Scaling of the slack: the solver's variable is ``s̃ = s / σ`` with ``σ = min(1, 1e4 / w_s)``
(the problem is unchanged). Unscaled, with the benchmark's w_s = 1e10, the multiplier of
``s ≥ 0`` is 1e10 whenever no collision row is active; both solvers divide the dual
infeasibility by the mean multiplier size before testing convergence, so they stopped
early (measured on Experiment 1: plans ending 0.05 m further from the goal than the
optimum, and fatrop then never moved closer than 0.19 m). Scaled, the multipliers are
O(1e4).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from dynfab.mpc.config import MpcConfig
from dynfab.mpc.model import PredictionModel
from dynfab.mpc.values import GoalTerm, Plan, SolveResult
from dynfab.robots.robot import Robot

_DISTANCE_SMOOTHING = 1e-6  # ε [m]
_SLACK_COST = 1e4  # w_s σ, the slack variable's cost coefficient (module docstring)


class MpcProblem:
    """The NLP of the module docstring for one robot, its goals and obstacle count.

    Built once; :meth:`solve` only sets the parameters (initial state, goal references,
    obstacle centres over the horizon, obstacle radii) and the initial guess.

    Attributes:
        robot: the robot.
        goals: the goal terms.
        obstacles: number of obstacle spheres.
        config: horizon, weights and solver.
        model: the prediction model (double integrator, or differential drive for a
            robot with a ``base``).
        solver: the CasADi ``nlpsol`` function.
    """

    def __init__(self, robot: Robot, goals: Sequence[GoalTerm], obstacles: int, config: MpcConfig) -> None:
        if not goals:
            raise ValueError("MpcProblem needs at least one goal")
        self.robot = robot
        self.goals = tuple(goals)
        self.obstacles = obstacles
        self.config = config
        self.model = PredictionModel.for_robot(robot)
        self._n = robot.dof
        self._m = self.model.velocity_size
        self._dims = 2 if robot.planar else 3
        self._goal_dims = tuple(self._n if g.dimension is None else g.dimension for g in self.goals)
        self._slack_unit = min(1.0, _SLACK_COST / config.slack_weight) if config.slack_weight > 0 else 1.0
        self._index: dict[str, list[np.ndarray]] = {"q": [], "qdot": [], "qddot": [], "slack": []}
        self._size = 0
        nlp = self._build()
        self._lbg, self._ubg = nlp.lower, nlp.upper
        self._lbx, self._ubx = self._bounds()
        self._worst_clearance = nlp.worst_clearance
        self.solver = ca.nlpsol("mpc", config.solver, nlp.problem, _solver_options(config, nlp.equality))

    def solve(self, q: np.ndarray, qdot: np.ndarray, goal_references: Sequence[np.ndarray],
              obstacle_centres: np.ndarray, obstacle_radii: np.ndarray, guess: Plan | None) -> SolveResult:
        """Solve from the measured state.

        Args:
            q: current configuration, shape (n,).
            qdot: current velocity coordinates ``u``, shape (m,): joint velocities, or
                ``(v, ω, arm rates)`` on a differential-drive base.
            goal_references: per goal, its reference at t_1..t_H, shape (H, d_i).
            obstacle_centres: obstacle centres at t_1..t_H, shape (obstacles, H, 2 or 3)
                [m] (planar robots use the first two coordinates).
            obstacle_radii: shape (obstacles,) [m].
            guess: initial guess (e.g. the previous plan shifted); ``None``: rest at ``q``.

        Raises:
            ValueError: if ``q``, ``qdot`` or ``obstacle_centres`` has the wrong shape.
        """
        horizon = self.config.stages
        q, qdot = np.asarray(q, dtype=float), np.asarray(qdot, dtype=float)
        if q.shape != (self._n,) or qdot.shape != (self._m,):
            raise ValueError(f"q and qdot must have shapes ({self._n},) and ({self._m},), got {q.shape} and {qdot.shape}")
        centres = np.asarray(obstacle_centres, dtype=float)[..., :self._dims]
        if centres.shape != (self.obstacles, horizon, self._dims):
            raise ValueError(f"obstacle_centres must have shape ({self.obstacles}, {horizon}, {self._dims}), "
                             f"got {np.shape(obstacle_centres)}")
        parameters = np.concatenate([q, qdot, *[np.asarray(r, dtype=float).ravel() for r in goal_references],
                                     centres.ravel(), np.asarray(obstacle_radii, dtype=float)])
        result = self.solver(x0=self._initial_point(q, qdot, guess, parameters), p=parameters, lbx=self._lbx,
                             ubx=self._ubx, lbg=self._lbg, ubg=self._ubg)
        stats = self.solver.stats()
        plan = self._unpack(np.asarray(result["x"]).ravel())
        return SolveResult(plan=plan, success=bool(stats["success"]) and plan.finite,
                           iterations=int(stats.get("iter_count", -1)), status=str(stats["return_status"]))

    # -- construction -------------------------------------------------------------------

    def _variable(self, name: str, size: int) -> ca.SX:
        """A new block of decision variables, appended to the decision vector."""
        self._index[name].append(np.arange(self._size, self._size + size))
        self._size += size
        return ca.SX.sym(f"{name}_{len(self._index[name]) - 1}", size)

    def _build(self) -> _Nlp:
        """The NLP of the module docstring, its rows stage by stage."""
        n, m, horizon, h, cfg = self._n, self._m, self.config.stages, self.config.stage_length, self.config
        q: list[ca.SX] = []
        qdot: list[ca.SX] = []
        qddot: list[ca.SX] = []
        slack: list[ca.SX] = []
        variables: list[ca.SX] = []
        for k in range(horizon + 1):  # stage k: state (q_k, u_k), controls (u̇_k, s_k)
            q.append(self._variable("q", n))
            qdot.append(self._variable("qdot", m))
            variables += [q[k], qdot[k]]
            if k < horizon:
                qddot.append(self._variable("qddot", m))
                variables.append(qddot[k])
            if k > 0:
                slack.append(self._variable("slack", 1))
                variables.append(slack[k - 1])
        state_init = ca.SX.sym("x_init", n + m)
        references = [ca.SX.sym(f"goal_{i}", d, horizon) for i, d in enumerate(self._goal_dims)]
        centres = [ca.SX.sym(f"obstacle_{o}", self._dims, horizon) for o in range(self.obstacles)]
        radii = ca.SX.sym("radii", self.obstacles)
        spheres = self._sphere_function()
        gaps = [_clearance(spheres, q[k], [c[:, k - 1] for c in centres], radii) for k in range(1, horizon + 1)]
        unit = self._slack_unit
        rows = _Rows()
        q_sym, u_sym, udot_sym = ca.SX.sym("q", n), ca.SX.sym("u", m), ca.SX.sym("udot", m)
        step = ca.Function("step", [q_sym, u_sym, udot_sym], [self.model.step(q_sym, u_sym, udot_sym, h)])
        for k in range(horizon):
            rows.add(q[k + 1] - step(q[k], qdot[k], qddot[k]), 0.0, 0.0, equality=True)
            rows.add(qdot[k + 1] - (qdot[k] + h * qddot[k]), 0.0, 0.0, equality=True)
            if k == 0:
                rows.add(ca.vertcat(q[0], qdot[0]) - state_init, 0.0, 0.0, equality=True)
            else:
                rows.add(gaps[k - 1] + unit * slack[k - 1], cfg.collision_margin, ca.inf)
        rows.add(gaps[-1] + unit * slack[-1], cfg.collision_margin, ca.inf)
        goal_functions = self._goal_functions()
        cost = cfg.input_weight * sum(ca.sumsqr(u) for u in qddot)
        for k in range(1, horizon + 1):
            cost += cfg.velocity_weight * ca.sumsqr(qdot[k]) + cfg.slack_weight * unit * slack[k - 1]
            for goal, function, reference in zip(self.goals, goal_functions, references):
                cost += cfg.goal_weight * goal.weight * ca.sumsqr(function(q[k]) - reference[:, k - 1])
        parameters = ca.vertcat(state_init, *[ca.vec(r) for r in references], *[ca.vec(c) for c in centres], radii)
        decision = ca.vertcat(*variables)
        worst = ca.vertcat(*[ca.mmin(gap) if gap.numel() else ca.SX(0) for gap in gaps])
        return _Nlp(problem={"x": decision, "p": parameters, "f": cost, "g": ca.vertcat(*rows.expressions)},
                    equality=rows.equality, lower=np.concatenate(rows.lower), upper=np.concatenate(rows.upper),
                    worst_clearance=ca.Function("worst_clearance", [decision, parameters], [worst]))

    def _sphere_function(self) -> tuple[ca.Function, np.ndarray]:
        """``q ↦`` centres (one row each, x-y for planar robots) of the spheres some joint
        moves, and their radii [m]."""
        q = ca.SX.sym("q", self._n)
        centres = self.robot.sphere_centers(q)[:, :self._dims]
        moving = [j for j in range(centres.shape[0]) if ca.depends_on(centres[j, :], q)]
        return ca.Function("spheres", [q], [centres[moving, :]]), self.robot.sphere_radii[moving]

    def _goal_functions(self) -> list[ca.Function]:
        """Per goal, ``q ↦ e_i(q)``: goal point on the goal's axes, directions of link axes,
        or q itself."""
        q = ca.SX.sym("q", self._n)
        kinematics = self.robot.kinematics
        functions = []
        for i, goal in enumerate(self.goals):
            if goal.link is None:
                task = q
            elif goal.link_axes:
                rotation = kinematics.rotation(q, goal.link)
                task = ca.vertcat(*[ca.mtimes(rotation, ca.DM(list(axis))) for axis in goal.link_axes])
            else:
                task = kinematics.position(q, goal.link, parent=goal.parent_link, offset=goal.offset)[list(goal.axes)]
            functions.append(ca.Function(f"goal_{i}", [q], [task]))
        return functions

    def _bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Joint limits ``q_min ≤ q_k ≤ q_max`` and velocity limits ``|u_k| ≤ u_max`` on
        stages 1..H, acceleration limits ``|u̇_k| ≤ a_max`` on every stage, ``s ≥ 0``;
        everything else free."""
        lower, upper = np.full(self._size, -np.inf), np.full(self._size, np.inf)
        kin = self.robot.kinematics
        for index in self._index["q"][1:]:
            lower[index], upper[index] = kin.lower, kin.upper
        for index in self._index["qdot"][1:]:
            lower[index], upper[index] = -self.model.velocity_limits, self.model.velocity_limits
        for index in self._index["qddot"]:
            lower[index], upper[index] = -self.model.acceleration_limits, self.model.acceleration_limits
        for index in self._index["slack"]:
            lower[index] = 0.0
        return lower, upper

    # -- packing ------------------------------------------------------------------------

    def _initial_point(self, q: np.ndarray, qdot: np.ndarray, guess: Plan | None, parameters: np.ndarray) -> np.ndarray:
        """The decision vector the solver starts from: ``guess`` (rest at ``q`` if None)
        with its first state replaced by the measured one and each slack raised to make
        its stage's collision rows feasible, ``s_k ≥ δ − min_{j,o} gap_{jo}(q_k)``."""
        horizon, m = self.config.stages, self._m
        if guess is None:
            guess = Plan(q=np.tile(q, (horizon + 1, 1)), qdot=np.zeros((horizon + 1, m)),
                         qddot=np.zeros((horizon, m)), slack=np.zeros(horizon))
        start_q, start_qdot = guess.q.copy(), guess.qdot.copy()
        start_q[0], start_qdot[0] = q, qdot
        vector = self._pack(Plan(q=start_q, qdot=start_qdot, qddot=guess.qddot, slack=np.zeros(horizon)))
        worst = np.asarray(self._worst_clearance(vector, parameters)).ravel()
        slack = np.maximum(guess.slack, self.config.collision_margin - worst)
        return self._pack(Plan(q=start_q, qdot=start_qdot, qddot=guess.qddot, slack=slack))

    def _pack(self, plan: Plan) -> np.ndarray:
        vector = np.empty(self._size)
        for name in ("q", "qdot", "qddot"):
            vector[np.concatenate(self._index[name])] = getattr(plan, name).ravel()
        vector[np.concatenate(self._index["slack"])] = plan.slack / self._slack_unit
        return vector

    def _unpack(self, vector: np.ndarray) -> Plan:
        return Plan(*(vector[np.stack(self._index[name])] for name in ("q", "qdot", "qddot")),
                    slack=self._slack_unit * vector[np.concatenate(self._index["slack"])])


def _clearance(spheres: tuple[ca.Function, np.ndarray], q: ca.SX, centres: list[ca.SX], radii: ca.SX) -> ca.SX:
    """``sqrt(||p_j(q) − c_o||² + ε²) − r_j − r_o`` for every moving sphere j and obstacle o [m]."""
    positions, sphere_radii = spheres
    points = positions(q)
    gaps = []
    for o, centre in enumerate(centres):
        offset = points - ca.repmat(centre.T, points.shape[0], 1)
        gaps.append(ca.sqrt(ca.sum2(offset**2) + _DISTANCE_SMOOTHING**2) - sphere_radii - radii[o])
    return ca.vertcat(*gaps) if gaps else ca.SX(0, 1)


@dataclass(frozen=True, eq=False)
class _Nlp:
    """The built NLP.

    Attributes:
        problem: ``nlpsol``'s dict: decision vector x, parameters p, cost f, rows g.
        equality: per row of g, whether it is an equality.
        lower: lower bounds of the rows.
        upper: upper bounds of the rows.
        worst_clearance: ``(x, p) ↦ min_{j,o} gap_{jo}(q_k)`` for k = 1..H [m] (0 without
            obstacles).
    """

    problem: dict[str, ca.SX]
    equality: list[bool]
    lower: np.ndarray
    upper: np.ndarray
    worst_clearance: ca.Function


class _Rows:
    """Constraint rows ``lower ≤ g ≤ upper`` in the order they are added."""

    def __init__(self) -> None:
        self.expressions: list[ca.SX] = []
        self.lower: list[np.ndarray] = []
        self.upper: list[np.ndarray] = []
        self.equality: list[bool] = []

    def add(self, expression: ca.SX, lower: float, upper: float, equality: bool = False) -> None:
        size = expression.shape[0]
        self.expressions.append(expression)
        self.lower.append(np.full(size, lower))
        self.upper.append(np.full(size, upper))
        self.equality += [equality] * size


def _solver_options(config: MpcConfig, equality: list[bool]) -> dict[str, object]:
    """``nlpsol`` options: silent, bounded iterations, no exception on failure.

    Both interior-point methods start close to the barrier's end, which is what makes the
    warm start pay off: IPOPT with its adaptive barrier update, fatrop (which has no
    adaptive update) with a small initial barrier parameter (measured on Experiment 1:
    median iterations per solve 18 → 4 for IPOPT and 7 → 4 for fatrop).
    """
    common = {"print_time": False, "error_on_fail": False}
    if config.solver == "fatrop":
        return {**common, "structure_detection": "auto", "equality": equality,
                "fatrop": {"print_level": 0, "max_iter": config.max_iter, "tol": config.tolerance, "mu_init": 1e-3}}
    return {**common, "ipopt": {"print_level": 0, "sb": "yes", "max_iter": config.max_iter, "tol": config.tolerance,
                                "mu_strategy": "adaptive"}}
