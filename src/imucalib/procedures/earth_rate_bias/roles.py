"""The earth-rate bias test's step roles (``earth-rate-bias.<purpose>``, docs/earth-rate-bias.md).

:data:`EARTH_RATE_BIAS_REMOUNT` ``"earth-rate-bias.remount"``
    The operator places the fixture with another axis up (tag ``pose=<axis>``).
:data:`EARTH_RATE_BIAS_POSITION` ``"earth-rate-bias.position"``
    A static record at one azimuth of a single-axis table (tags ``pose=<axis>``,
    ``azimuth=<deg>``).

Contents
--------
:data:`ROLES` (role → what it is for), the role constants above.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

__all__ = ["EARTH_RATE_BIAS_POSITION", "EARTH_RATE_BIAS_REMOUNT", "ROLES"]

EARTH_RATE_BIAS_REMOUNT: Final = "earth-rate-bias.remount"
EARTH_RATE_BIAS_POSITION: Final = "earth-rate-bias.position"

#: Every earth-rate bias role and what the step is for.
ROLES: Final[Mapping[str, str]] = {
    EARTH_RATE_BIAS_REMOUNT: "the operator places the fixture with another axis up (tag pose=)",
    EARTH_RATE_BIAS_POSITION: "a static record at one azimuth (tags pose=, azimuth=)",
}
