"""Step roles: the grammar of what a recorded step is for (the ``role`` field of ``/steps``).

A role is ``"<procedure>.<purpose>"``: the registry name of the procedure whose analysis uses
the step, a dot, and what the step is for in it (``"p1.accel-position"``, ``"tumble.drift"``).
Plan generators set them, the runner stores them with each executed step, and an analysis
selects its windows by them, so that a Recording explains itself without the plan that made it
(``docs/recording-format.md``, "Step roles"). A step that only prepares (an operator check
without a role, a warm-up, moving to a start position) has no role: the empty string. There is
no role without a procedure.

Which roles exist is each procedure's own fact: its folder's ``roles.py``
(``imucalib.procedures.<name>.roles``) and its ``roles`` member, which the registry checks a
role against (``imucalib.procedures.registry.check_roles``); this module, in the file-format
layer, knows none of them, only the grammar (:func:`split_role`, :func:`is_role`).

The one exception is a frozen fact of the file format: :func:`role_from_tags`, the mapping by
which a version 1 Recording (which had no ``role`` field) and a step of a hand-written plan
that carries tags but no role get their role. It names the P1 and Allan roles of the time
(``p1.accel-position``, ``p1.gyro-bias``, ``p1.gyro-rate``, ``p1.held-out-position``,
``p1.held-out-rate``, ``allan.static``) and is kept exactly as it was when version 2 began.

Contents
--------
:func:`split_role`, :func:`is_role`, :func:`role_from_tags`, :data:`MAX_ROLE_LENGTH`
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Final

__all__ = ["MAX_ROLE_LENGTH", "is_role", "role_from_tags", "split_role"]

#: Longest role, in characters (a plan step's ``role`` field).
MAX_ROLE_LENGTH: Final = 128
#: A procedure name or a purpose: no dot, no white space, no control character.
_PART = re.compile(r"[^.\s\x00-\x1f\x7f]+")


def split_role(role: str) -> tuple[str, str]:
    """Return the procedure and the purpose of a role: ``"p1.gyro-rate"`` → ``("p1", "gyro-rate")``.

    The procedure is the part before the first dot; the purpose, the rest, may hold further
    dots. Neither may be empty or hold white space.

    Parameters
    ----------
    role : str

    Returns
    -------
    procedure, purpose : str

    Raises
    ------
    ValueError
        `role` is not ``"<procedure>.<purpose>"`` (the message says why).

    Examples
    --------
    >>> split_role("tumble.position")
    ('tumble', 'position')
    >>> split_role("position")
    Traceback (most recent call last):
    ...
    ValueError: role 'position' is not '<procedure>.<purpose>' (e.g. 'p1.accel-position')
    """
    procedure, dot, purpose = role.partition(".")
    if (not dot or len(role) > MAX_ROLE_LENGTH or not _PART.fullmatch(procedure)
            or not all(_PART.fullmatch(p) for p in purpose.split("."))):
        raise ValueError(f"role {role!r} is not '<procedure>.<purpose>' (e.g. "
                         "'p1.accel-position')")
    return procedure, purpose


def is_role(role: str) -> bool:
    """Return whether `role` follows the grammar ``"<procedure>.<purpose>"`` (:func:`split_role`).

    Examples
    --------
    >>> is_role("p3.rate"), is_role("warm-up"), is_role("")
    (True, False, False)
    """
    try:
        split_role(role)
    except ValueError:
        return False
    return True


# The version 1 mapping's roles (frozen: module docstring).
_V1_P1_ACCEL_POSITION: Final = "p1.accel-position"
_V1_P1_GYRO_BIAS: Final = "p1.gyro-bias"
_V1_P1_GYRO_RATE: Final = "p1.gyro-rate"
_V1_P1_HELD_OUT_POSITION: Final = "p1.held-out-position"
_V1_P1_HELD_OUT_RATE: Final = "p1.held-out-rate"
_V1_ALLAN_STATIC: Final = "allan.static"


def role_from_tags(kind: str, tags: Sequence[str], procedure: str = "") -> str:
    """Return the role a step of `kind` with `tags` has under the generators' rules, or ``""``.

    The frozen version 1 mapping (module docstring): it gives P1 and Allan roles only.

    Parameters
    ----------
    kind : str
        The step kind (``"position"``, ``"static"``, ``"rate"``, …).
    tags : sequence of str
        The step's tags, e.g. ``("calibration", "six-position", "rep1")``.
    procedure : str
        The plan's ``procedure`` (``"p1"``, ``"allan"``), or ``""`` when unknown: then the
        distinctive tags decide.

    Examples
    --------
    >>> role_from_tags("position", ("calibration", "six-position", "rep1"), "p1")
    'p1.accel-position'
    >>> role_from_tags("rate", ("verification", "rate", "rep2"))
    'p1.held-out-rate'
    >>> role_from_tags("static", ("allan", "T+20"), "allan")
    'allan.static'
    """
    tagset = set(tags)
    if procedure in ("allan", "") and kind == "static" and "allan" in tagset:
        return _V1_ALLAN_STATIC
    if procedure not in ("p1", ""):
        return ""
    if kind == "position" and "six-position" in tagset:
        return _V1_P1_ACCEL_POSITION
    if kind == "static" and "gyro-bias" in tagset:
        return _V1_P1_GYRO_BIAS
    if "verification" in tagset:
        return {"position": _V1_P1_HELD_OUT_POSITION, "static": _V1_P1_HELD_OUT_POSITION,
                "rate": _V1_P1_HELD_OUT_RATE}.get(kind, "")
    if kind == "rate" and "calibration" in tagset:
        return _V1_P1_GYRO_RATE
    return ""
