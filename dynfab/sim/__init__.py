"""Embedded simulators that close the loop around a controller."""

from dynfab.sim.models import DifferentialDrive, DoubleIntegrator, MotionModel, motion_model_for
from dynfab.sim.simulator import (
    Controller,
    ControllerError,
    ProgressCallback,
    Record,
    RunStopped,
    StopPredicate,
    n_steps_for,
    simulate,
)

__all__ = [
    "Controller",
    "ControllerError",
    "DifferentialDrive",
    "DoubleIntegrator",
    "MotionModel",
    "ProgressCallback",
    "Record",
    "RunStopped",
    "StopPredicate",
    "motion_model_for",
    "n_steps_for",
    "simulate",
]
