"""The field calibration's step roles (``field.<purpose>``, docs/field.md).

The analysis finds the intervals in the continuous IMU stream itself; the roles say what the
guided session asked for.

:data:`FIELD_REST` ``"field.rest"``
    The initial rest (the static detector's reference variance).
:data:`FIELD_MOVE` ``"field.move"``
    The operator turns the unit by hand onto another face (an operator check, ``remount``).
:data:`FIELD_POSE` ``"field.pose"``
    A static record of one pose (tags ``pose<k>`` or ``turn<face><±360>``, and the face).
:data:`FIELD_TURN` ``"field.turn"``
    The operator turns the unit flat on the desk by one full turn (an operator check).

Contents
--------
:data:`ROLES` (role → what it is for), the role constants above.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

__all__ = ["FIELD_MOVE", "FIELD_POSE", "FIELD_REST", "FIELD_TURN", "ROLES"]

FIELD_REST: Final = "field.rest"
FIELD_MOVE: Final = "field.move"
FIELD_POSE: Final = "field.pose"
FIELD_TURN: Final = "field.turn"

#: Every field role and what the step is for.
ROLES: Final[Mapping[str, str]] = {
    FIELD_REST: "the initial rest (the static detector's reference variance)",
    FIELD_MOVE: "the operator turns the unit by hand onto another face (operator check)",
    FIELD_POSE: "a static record of one pose",
    FIELD_TURN: "the operator turns the unit flat on the desk by one full turn (operator check)",
}
