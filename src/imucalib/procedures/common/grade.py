"""The IMU grades a static-position plan accepts, and each grade's default warm-up.

The g-sensitivity, random-drift and Earth-rate bias plans take the unit's grade (consumer,
tactical or navigation) and, when no warm-up is given, warm the unit up for the grade's default
(docs/g-sensitivity.md, "The plan": 15/30/60 min by grade; docs/random-drift.md and
docs/earth-rate-bias.md, "The plan"). :func:`check_grade` refuses any other grade.

Contents
--------
:data:`WARM_UP_S`, :func:`check_grade`
"""

from __future__ import annotations

from imucalib.errors import ConfigurationError

__all__ = ["WARM_UP_S", "check_grade"]

#: Default warm-up of each grade; its keys are the grades a plan accepts. [s]
WARM_UP_S = {"consumer": 900.0, "tactical": 1800.0, "navigation": 3600.0}


def check_grade(grade: str) -> None:
    """Raise ConfigurationError for an unknown grade."""
    if grade not in WARM_UP_S:
        raise ConfigurationError(f"`grade` must be one of {sorted(WARM_UP_S)}; got {grade!r}")
