"""The scale-factor test's name and step roles: what each step of its plan is for.

A procedure's roles are ``"<name>.<purpose>"``: the plan sets them, the analysis selects its
turns by them, and imucalib's registry checks a step file's roles against the procedure's
``roles`` member (this module's :data:`ROLES`). Importing this module imports nothing else.

:data:`ROLE_MOUNT` ``"scale-factor.mount"``
    The operator check of the mounting: the unit on the cube's +z face.
:data:`ROLE_RATE` ``"scale-factor.rate"``
    A turn about z over whole revolutions (tags ``axis=z`` and ``rate=<°/s>``; ``commanded``
    gives ``rate_dps`` and ``revolutions``).

Contents
--------
:data:`NAME`, :data:`ROLE_MOUNT`, :data:`ROLE_RATE`, :data:`ROLES`
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

__all__ = ["NAME", "ROLES", "ROLE_MOUNT", "ROLE_RATE"]

#: The procedure's name: the plan's ``procedure`` field and the prefix of its step roles.
NAME: Final = "scale-factor"
#: The mounting check.
ROLE_MOUNT: Final = f"{NAME}.mount"
#: A turn over whole revolutions (``commanded`` gives ``rate_dps`` and ``revolutions``).
ROLE_RATE: Final = f"{NAME}.rate"

#: Every role of the procedure and what the step is for (the procedure's ``roles``).
ROLES: Final[Mapping[str, str]] = {
    ROLE_MOUNT: "the operator mounts the unit on the cube's +z face (operator check)",
    ROLE_RATE: "a turn about z over whole revolutions (tags axis=z, rate=<°/s>)",
}
