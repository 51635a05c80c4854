"""The tumble's step roles: what each recorded step is for (``tumble.<purpose>``, docs/tumble.md).

The accelerometer multi-position tumble of IEEE Std 1293 on a dividing head (the dual-axis
table's pitch axis). Every tumble record carries the tags ``axis=<x|y|z>`` (the body axis along
the head axis), ``angle=<deg>`` (the head angle), ``positions=<N>``, ``mount=<pose>`` and
``yaw=<deg>`` (the fixture's remount), and ``pass=cw|ccw`` when both directions are run.

:data:`TUMBLE_MOUNT` ``"tumble.mount"``
    The operator places the IMU so that the body axis under test lies along the head axis.
:data:`TUMBLE_POSITION` ``"tumble.position"``
    A static record at head angle θ_k.
:data:`TUMBLE_DRIFT` ``"tumble.drift"``
    The 0° record repeated at the end of a sequence (the drift check).

Contents
--------
:data:`ROLES` (role → what it is for), the role constants above.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

__all__ = ["ROLES", "TUMBLE_DRIFT", "TUMBLE_MOUNT", "TUMBLE_POSITION"]

TUMBLE_MOUNT: Final = "tumble.mount"
TUMBLE_POSITION: Final = "tumble.position"
TUMBLE_DRIFT: Final = "tumble.drift"

#: Every tumble role and what the step is for.
ROLES: Final[Mapping[str, str]] = {
    TUMBLE_MOUNT: "the operator puts the body axis under test along the head axis",
    TUMBLE_POSITION: "a static record at head angle θ_k (tags axis=, angle=, positions=, mount=)",
    TUMBLE_DRIFT: "the 0° record repeated at the end of a sequence (the drift check)",
}
