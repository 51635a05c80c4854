"""The Allan procedure's step roles: what each recorded step is for (``allan.<purpose>``).

:data:`ALLAN_STATIC` ``"allan.static"``
    A static record whose noise is characterised (tags ``allan`` and ``T<temperature>``).

The plan generator (:mod:`.plan`) sets it and the analysis selects its records by it
(docs/recording-format.md, "Step roles"); version 1 Recordings get it from their tags
(:func:`imucalib.io.step_roles.role_from_tags`, a frozen fact of the file format).

Contents
--------
:data:`ROLES` (role → what it is for), :data:`ALLAN_STATIC`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

__all__ = ["ALLAN_STATIC", "ROLES"]

ALLAN_STATIC: Final = "allan.static"

#: Every Allan role and what the step is for.
ROLES: Final[Mapping[str, str]] = {
    ALLAN_STATIC: "a static record whose noise is characterised (Allan deviation, noise fit)",
}
