"""The tumble plan: positions, roles and tags, the head axes' geometry, bad options."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import ConfigurationError
from imucalib.plan.fixture_poses import rot_pm_for_pose
from imucalib.procedures import registry
from imucalib.procedures.common.reference import spin_axis_b
from imucalib.procedures.tumble.plan import HEAD_MOUNTS, generate_tumble_plan
from imucalib.procedures.tumble.roles import TUMBLE_DRIFT, TUMBLE_MOUNT, TUMBLE_POSITION


def test_default_plan_positions_roles_and_tags() -> None:
    plan = registry.get("tumble").generate_plan()
    assert plan.procedure == "tumble"
    assert plan.twin is not None and plan.twin.table.kind == "dual-axis"
    assert plan.twin.table.grade == "high" and len(plan.twin.imus) == 1
    mounts = [s for s in plan.steps if s.role == TUMBLE_MOUNT]
    assert [s.tags for s in mounts] == [("axis=x",), ("axis=y",), ("axis=z",)]
    assert [(s.remount, s.remount_yaw_deg) for s in mounts] == [("+z", 90.0), ("+z", 0.0),
                                                                ("+z", 0.0)]
    for axis in "xyz":
        tags = [dict(t.split("=") for t in s.tags) for s in plan.steps
                if s.role == TUMBLE_POSITION and f"axis={axis}" in s.tags]
        assert [float(t["angle"]) for t in tags] == [30.0 * k for k in range(12)]
        assert all(t["positions"] == "12" for t in tags)
    drift = [s for s in plan.steps if s.role == TUMBLE_DRIFT]
    assert len(drift) == 3 and all(s.angles_deg[0] == 0.0 for s in drift)


def test_both_directions_and_other_n() -> None:
    plan = generate_tumble_plan(n_positions=8, axes=("z",), both_directions=True)
    pos = [s for s in plan.steps if s.role == TUMBLE_POSITION]
    cw = [s.angles_deg[0] for s in pos if "pass=cw" in s.tags]
    ccw = [s.angles_deg[0] for s in pos if "pass=ccw" in s.tags]
    assert cw == [45.0 * k for k in range(8)]
    assert ccw == [0.0, 315.0, 270.0, 225.0, 180.0, 135.0, 90.0, 45.0]
    assert sum(s.role == TUMBLE_DRIFT for s in plan.steps) == 2


@pytest.mark.parametrize("axis", ["x", "y", "z"])
def test_head_axis_lies_along_the_body_axis(axis: str) -> None:
    """The pitch axis in the body frame is ±(the chosen body axis), module docstring."""
    pose, yaw, roll = HEAD_MOUNTS[axis]
    in_platform = spin_axis_b(("pitch", "roll"), 0, np.radians([0.0, roll]))
    in_body = rot_pm_for_pose(pose, yaw).T @ in_platform
    want = np.zeros(3)
    want["xyz".index(axis)] = 1.0
    assert abs(abs(float(in_body @ want)) - 1.0) < 1e-12


@pytest.mark.parametrize(("options", "message"), [
    ({"n_positions": 7}, "integer ≥ 4 dividing 360"),
    ({"n_positions": 2}, "integer ≥ 4 dividing 360"),
    ({"axes": ("x", "w")}, "distinct names of"),
    ({"axes": ("y", "y")}, "distinct names of"),
    ({"record_s": 0.0}, "`record_s` must be positive"),
])
def test_bad_options(options: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        generate_tumble_plan(**options)  # type: ignore[arg-type]
