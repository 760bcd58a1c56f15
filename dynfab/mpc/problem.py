"""The MPC baseline's nonlinear program, built once and solved with IPOPT or fatrop.

Model: a second-order integrator per joint, state ``x = (q, q̇)``, input ``u = q̈``,
discretised exactly for an input held constant over each stage of length h [s]:

    q_{k+1} = q_k + h q̇_k + ½ h² q̈_k,        q̇_{k+1} = q̇_k + h q̈_k.

Over stages k = 0..H at times t_k = t + k h, with one slack ``s_k ≥ 0`` per stage:

    min   Σ_{k=1..H} [ w_g Σ_i ω_i ||e_i(q_k) − r_i(t_k)||² + w_v ||q̇_k||² + w_s s_k ]
        + Σ_{k=0..H-1} w_u ||q̈_k||²
    s.t.  (q_0, q̇_0) = (q(t), q̇(t))                                      initial state
          the dynamics above,                                            k = 0..H-1
          ||p_j(q_k) − c_o(t_k)|| − r_j − r_o ≥ −s_k   every robot sphere j, obstacle o
          q_min ≤ q_k ≤ q_max,  |q̇_k| ≤ q̇_max                           k = 1..H

``e_i`` is the goal link's position on the goal's axes in its parent link's frame [m]
(or the joint vector for joint goals [rad]), ``r_i(t_k)`` the goal's reference at the
stage time, ``p_j`` a collision sphere's centre and ``c_o(t_k)`` an obstacle's centre
at the stage time; planar robots measure distances in x-y only. Stage 0 carries no
collision or limit constraint and no goal cost: its state is fixed by the measurement,
so they could only make the problem infeasible. Spheres that no joint moves are left
out for the same reason. Distances are smoothed, ``sqrt(||d||² + ε²)`` with
ε = 1e-6 m, so that their gradient exists at ``d = 0``. As in the benchmark, collisions
are constrained at the stage times only: in between, a sphere moving a distance L per
stage past an obstacle at the constraint's boundary can cut up to about L² / (8 (r_j + r_o))
into it (millimetres at 1 m/s).

Decision variables and constraints are ordered stage by stage (x_0, u_0, x_1, u_1, ...,
gap-closing rows ``x_{k+1} − F(x_k, u_k) = 0`` first in each stage), the layout fatrop's
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
from dynfab.robots.robot import Robot

_DISTANCE_SMOOTHING = 1e-6  # ε [m]
_SLACK_COST = 1e4  # w_s σ, the slack variable's cost coefficient (module docstring)


@dataclass(frozen=True)
class GoalTerm:
    """One goal of the cost.

    Attributes:
        link: goal link of a position or path goal; ``None`` for a joint-space goal.
        axes: indices (0 = x, 1 = y, 2 = z) of the controlled axes of ``link``.
        parent_link: frame in which the link position is measured (``None``: root).
        weight: ω, relative weight of this goal.
    """

    link: str | None
    axes: tuple[int, ...] = (0, 1, 2)
    parent_link: str | None = None
    weight: float = 1.0


@dataclass(frozen=True, eq=False)
class Plan:
    """A solution over the horizon, stage k at time ``t_0 + k h``.

    Attributes:
        q: joint positions q_0..q_H, shape (H + 1, n) [rad or m].
        qdot: joint velocities, shape (H + 1, n) [rad/s or m/s].
        qddot: accelerations held over each stage, shape (H, n) [rad/s² or m/s²].
        slack: collision slacks s_1..s_H, shape (H,) [m].
    """

    q: np.ndarray
    qdot: np.ndarray
    qddot: np.ndarray
    slack: np.ndarray

    def shifted(self, stages: int, stage_length: float) -> Plan:
        """The plan from stage ``stages`` on, extended at the end with ``q̈ = 0``.

        The extension keeps the dynamics: ``q ← q + h q̇`` per added stage.
        """
        horizon = self.qddot.shape[0]
        stages = min(stages, horizon)
        q, qdot = self.q[stages:], self.qdot[stages:]
        added = np.arange(1, stages + 1)[:, None] * stage_length
        return Plan(q=np.vstack([q, q[-1] + added * qdot[-1]]),
                    qdot=np.vstack([qdot, np.repeat(qdot[-1:], stages, axis=0)]),
                    qddot=np.vstack([self.qddot[stages:], np.zeros((stages, self.qddot.shape[1]))]),
                    slack=np.concatenate([self.slack[stages:], np.zeros(stages)]))

    @property
    def finite(self) -> bool:
        """Whether every entry is a finite number."""
        return all(np.isfinite(a).all() for a in (self.q, self.qdot, self.qddot, self.slack))


@dataclass(frozen=True, eq=False)
class SolveResult:
    """The outcome of one solve.

    Attributes:
        plan: the solver's last iterate (meaningful only if ``success``).
        success: the solver converged and the plan is finite.
        iterations: solver iterations.
        status: the solver's return status.
    """

    plan: Plan
    success: bool
    iterations: int
    status: str


class MpcProblem:
    """The NLP of the module docstring for one robot, its goals and obstacle count.

    Built once; :meth:`solve` only sets the parameters (initial state, goal references,
    obstacle centres over the horizon, obstacle radii) and the initial guess.

    Attributes:
        robot: the robot.
        goals: the goal terms.
        obstacles: number of obstacle spheres.
        config: horizon, weights and solver.
        solver: the CasADi ``nlpsol`` function.
    """

    def __init__(self, robot: Robot, goals: Sequence[GoalTerm], obstacles: int, config: MpcConfig) -> None:
        if not goals:
            raise ValueError("MpcProblem needs at least one goal")
        self.robot = robot
        self.goals = tuple(goals)
        self.obstacles = obstacles
        self.config = config
        self._n = robot.dof
        self._dims = 2 if robot.planar else 3
        self._goal_dims = tuple(len(g.axes) if g.link is not None else self._n for g in self.goals)
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
            q: current joint positions, shape (n,).
            qdot: current joint velocities, shape (n,).
            goal_references: per goal, its reference at t_1..t_H, shape (H, d_i).
            obstacle_centres: obstacle centres at t_1..t_H, shape (m, H, 2 or 3) [m]
                (planar robots use the first two coordinates).
            obstacle_radii: shape (m,) [m].
            guess: initial guess (e.g. the previous plan shifted); ``None``: rest at ``q``.
        """
        horizon = self.config.stages
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
        n, horizon, h, cfg = self._n, self.config.stages, self.config.stage_length, self.config
        q: list[ca.SX] = []
        qdot: list[ca.SX] = []
        qddot: list[ca.SX] = []
        slack: list[ca.SX] = []
        variables: list[ca.SX] = []
        for k in range(horizon + 1):  # stage k: x_k = (q_k, q̇_k), u_k = (q̈_k, s_k)
            q.append(self._variable("q", n))
            qdot.append(self._variable("qdot", n))
            variables += [q[k], qdot[k]]
            if k < horizon:
                qddot.append(self._variable("qddot", n))
                variables.append(qddot[k])
            if k > 0:
                slack.append(self._variable("slack", 1))
                variables.append(slack[k - 1])
        state_init = ca.SX.sym("x_init", 2 * n)
        references = [ca.SX.sym(f"goal_{i}", d, horizon) for i, d in enumerate(self._goal_dims)]
        centres = [ca.SX.sym(f"obstacle_{o}", self._dims, horizon) for o in range(self.obstacles)]
        radii = ca.SX.sym("radii", self.obstacles)
        spheres = self._sphere_function()
        gaps = [_clearance(spheres, q[k], [c[:, k - 1] for c in centres], radii) for k in range(1, horizon + 1)]
        unit = self._slack_unit
        rows = _Rows()
        for k in range(horizon):
            rows.add(q[k + 1] - (q[k] + h * qdot[k] + 0.5 * h * h * qddot[k]), 0.0, 0.0, equality=True)
            rows.add(qdot[k + 1] - (qdot[k] + h * qddot[k]), 0.0, 0.0, equality=True)
            if k == 0:
                rows.add(ca.vertcat(q[0], qdot[0]) - state_init, 0.0, 0.0, equality=True)
            else:
                rows.add(gaps[k - 1] + unit * slack[k - 1], 0.0, ca.inf)
        rows.add(gaps[-1] + unit * slack[-1], 0.0, ca.inf)
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
        """Per goal, ``q ↦ e_i(q)``: link position on the goal's axes, or q itself."""
        q = ca.SX.sym("q", self._n)
        functions = []
        for i, goal in enumerate(self.goals):
            if goal.link is None:
                task = q
            else:
                task = self.robot.kinematics.position(q, goal.link, parent=goal.parent_link)[list(goal.axes)]
            functions.append(ca.Function(f"goal_{i}", [q], [task]))
        return functions

    def _bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Joint and velocity limits on stages 1..H, ``s ≥ 0``; everything else free."""
        lower, upper = np.full(self._size, -np.inf), np.full(self._size, np.inf)
        kin = self.robot.kinematics
        for index in self._index["q"][1:]:
            lower[index], upper[index] = kin.lower, kin.upper
        for index in self._index["qdot"][1:]:
            lower[index], upper[index] = -kin.velocity_limits, kin.velocity_limits
        for index in self._index["slack"]:
            lower[index] = 0.0
        return lower, upper

    # -- packing ------------------------------------------------------------------------

    def _initial_point(self, q: np.ndarray, qdot: np.ndarray, guess: Plan | None, parameters: np.ndarray) -> np.ndarray:
        """The decision vector the solver starts from: ``guess`` (rest at ``q`` if None)
        with its first state replaced by the measured one and each slack raised to make
        its stage's collision rows feasible, ``s_k ≥ −min_{j,o} gap_{jo}(q_k)``."""
        horizon, n = self.config.stages, self._n
        if guess is None:
            guess = Plan(q=np.tile(q, (horizon + 1, 1)), qdot=np.zeros((horizon + 1, n)),
                         qddot=np.zeros((horizon, n)), slack=np.zeros(horizon))
        start_q, start_qdot = guess.q.copy(), guess.qdot.copy()
        start_q[0], start_qdot[0] = q, qdot
        vector = self._pack(Plan(q=start_q, qdot=start_qdot, qddot=guess.qddot, slack=np.zeros(horizon)))
        worst = np.asarray(self._worst_clearance(vector, parameters)).ravel()
        return self._pack(Plan(q=start_q, qdot=start_qdot, qddot=guess.qddot, slack=np.maximum(guess.slack, -worst)))

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
