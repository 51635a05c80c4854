"""The static gyro design (FL.2) built for all poses at once is the pose-by-pose build, bitwise.

`_gyro_design` replaced a loop that built each pose's rows and covariance block with
``np.kron``, ``np.diag`` and ``np.outer``; the field calibration's results must not move, so the
arrays (and the signs of their zeros) must be those of that construction.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from imucalib.procedures.common.static_intervals import StaticPose
from imucalib.procedures.field.analysis import _gyro_design
from imucalib.units import EARTH_RATE_RPS


def _poses(n: int, rng: np.random.Generator) -> tuple[list[StaticPose], np.ndarray, np.ndarray]:
    up = rng.normal(size=(n, 3))
    up /= np.linalg.norm(up, axis=1, keepdims=True)
    up[0] = [0.0, 0.0, 1.0]  # a face: zeros whose signs the products decide
    up[1] = [0.0, -1.0, 0.0]
    force = 9.81 * up
    poses = [StaticPose(index=k, start_time_s=10.0 * k, end_time_s=10.0 * k + 5.0,
                        n_samples=500, accel_mean=force[k], accel_se=np.full(3, 1e-4),
                        gyro_mean=rng.normal(scale=1e-4, size=3),
                        gyro_se=rng.uniform(1e-6, 1e-5, size=3)) for k in range(n)]
    return poses, up, force


def _pose_by_pose(poses, up, force, lat, g_sensitivity, times):
    """The construction of (FL.2) one pose at a time (the loop `_gyro_design` replaced)."""
    omega = EARTH_RATE_RPS
    q = 3 + 9 * g_sensitivity + 3 * (times is not None)
    n = len(poses)
    design, z, cov = np.zeros((3 * n, q)), np.zeros(3 * n), np.zeros((3 * n, 3 * n))
    for row, (p, u, f) in enumerate(zip(poses, up, force, strict=True)):
        if lat is None:
            vertical = np.zeros(3)
            type_b = omega**2 / 3.0 * np.eye(3)
        else:
            s, c = math.sin(math.radians(lat)), math.cos(math.radians(lat))
            vertical = omega * s * u
            type_b = (omega * c) ** 2 / 2.0 * (np.eye(3) - np.outer(u, u))
        rows = slice(3 * row, 3 * row + 3)
        block = [np.eye(3)]
        if g_sensitivity:
            block.append(np.kron(np.eye(3), f[None, :]))
        if times is not None:
            block.append((times[row] - times.mean()) * np.eye(3))
        design[rows] = np.hstack(block)
        z[rows] = p.gyro_mean - vertical
        cov[rows, rows] = np.diag(p.gyro_se**2) + type_b
    return design, z, cov


def _identical(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and a.tobytes() == b.tobytes()  # values and the signs of zeros


@pytest.mark.parametrize("lat", [48.1, -33.9, None])
@pytest.mark.parametrize("g_sensitivity", [True, False])
@pytest.mark.parametrize("with_times", [True, False])
def test_the_design_is_the_pose_by_pose_build(lat, g_sensitivity, with_times):
    rng = np.random.default_rng(7)
    poses, up, force = _poses(24, rng)
    times = np.array([0.5 * (p.start_time_s + p.end_time_s) for p in poses]) if with_times \
        else None
    names, design, z, cov = _gyro_design(poses, up, force, lat, g_sensitivity, times)
    want = _pose_by_pose(poses, up, force, lat, g_sensitivity, times)
    assert len(names) == design.shape[1] == 3 + 9 * g_sensitivity + 3 * with_times
    for got, expected in zip((design, z, cov), want, strict=True):
        assert _identical(np.ascontiguousarray(got), expected)
    if g_sensitivity:  # a face's zero force components give -0.0 and 0.0 as np.kron does
        assert np.signbit(design[3:6, 3:12]).any()
