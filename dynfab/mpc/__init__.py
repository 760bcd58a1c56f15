"""The MPC baseline of the paper's benchmark: a receding-horizon optimal control problem
on a joint-space double integrator (holonomic robots) or a unicycle base carrying double-
integrator joints (robots on a differential-drive base), re-solved at 10 Hz with CasADi
(IPOPT or fatrop)."""

from dynfab.mpc.config import MpcConfig
from dynfab.mpc.controller import MpcController
from dynfab.mpc.model import PredictionModel
from dynfab.mpc.problem import MpcProblem
from dynfab.mpc.values import GoalTerm, Plan, SolveResult

__all__ = ["GoalTerm", "MpcConfig", "MpcController", "MpcProblem", "Plan", "PredictionModel", "SolveResult"]
