"""GuidanceSettings refuse values that would break guidance (a division by zero, a clock
that never runs) with a message naming the field."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from dynfab.motion.guidance_settings import GuidanceSettings


def test_the_defaults_are_valid() -> None:
    GuidanceSettings()


@pytest.mark.parametrize(("changes", "named"), [
    ({"way_reach": 0.0}, "way_reach"),               # the allowances' fade divides by it
    ({"check_period": -0.1}, "check_period"),
    ({"sweep_horizon": math.nan}, "sweep_horizon"),
    ({"stall_window": math.inf}, "stall_window"),
    ({"speed": 0.0}, "speed"),
    ({"acceleration": 1.5}, "acceleration"),          # beyond the robot's limits
    ({"attempts": 0}, "attempts"),
    ({"replans": 2.5}, "replans"),
    ({"mesh_margin": -0.001}, "mesh_margin"),
    ({"tight_margin": -math.inf}, "tight_margin"),
    ({"detour_ratio": 0.9}, "detour_ratio"),          # every way would be a detour
    ({"lag_slow": 0.3, "lag_stop": 0.3}, "lag_slow"),  # the clock's ramp has no width
    ({"approach_offset_slow": 0.01, "approach_offset_stop": 0.005}, "approach_offset_slow"),
])
def test_a_value_that_breaks_guidance_is_refused_by_name(changes: dict[str, float], named: str) -> None:
    with pytest.raises(ValueError, match=f"GuidanceSettings.{named} "):
        replace(GuidanceSettings(), **changes)


def test_off_values_stay_allowed() -> None:
    settings = replace(GuidanceSettings(), slow_clearance=0.0, approach_pull=0.0, replans=0, tight_margin=-0.02,
                       sweep_horizon=0.0)
    assert settings.replans == 0
