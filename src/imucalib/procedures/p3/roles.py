"""P3's step roles: what each recorded step is for (``p3.<purpose>``, docs/p3.md).

Accelerometer K2 on a centrifuge with dynamic-unbalance compensation. Every P3 step of a
configuration carries the tag ``config=<k>`` (1: reference A on the test side, no test load;
2: A and B swapped; 3: A back on the test side, the test load mounted); the first mounting
check names the units with ``ref-a=<unit>``, ``ref-b=<unit>`` and ``test=<unit>``.

:data:`P3_MOUNT` ``"p3.mount"``
    An operator check that mounts the accelerometers or turns them for the 1 g tumble.
:data:`P3_TUMBLE` ``"p3.tumble"``
    A record at rest with the input axes vertical (tag ``pose=+x|-x``, the fixture axis up): K1
    and K0 of each accelerometer from ±1 g.
:data:`P3_REST` ``"p3.rest"``
    A record at rest at one of the four arm positions (tags ``arm=<deg>`` and
    ``phase=before|after`` the configuration's rates).
:data:`P3_RATE` ``"p3.rate"``
    A record spinning at one rate over whole revolutions.
:data:`P3_SWAP` ``"p3.swap"``
    The operator exchanges references A and B (an operator check, ``swap_units``).
:data:`P3_LOAD` ``"p3.load"``
    The operator puts A and B back and mounts the test accelerometer and its load
    (``swap_units`` and ``centrifuge_load_kg``).

Contents
--------
:data:`ROLES` (role → what it is for), the role constants above.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

__all__ = ["P3_LOAD", "P3_MOUNT", "P3_RATE", "P3_REST", "P3_SWAP", "P3_TUMBLE", "ROLES"]

P3_MOUNT: Final = "p3.mount"
P3_TUMBLE: Final = "p3.tumble"
P3_REST: Final = "p3.rest"
P3_RATE: Final = "p3.rate"
P3_SWAP: Final = "p3.swap"
P3_LOAD: Final = "p3.load"

#: Every P3 role and what the step is for.
ROLES: Final[Mapping[str, str]] = {
    P3_MOUNT: "mount the accelerometers, or turn them for the 1 g tumble (operator check)",
    P3_TUMBLE: "a record at rest, input axes vertical (tag pose=+x|-x): K1 and K0 from ±1 g",
    P3_REST: "a record at rest at one of the four arm positions (tags arm=, phase=)",
    P3_RATE: "a record spinning at one rate over whole revolutions",
    P3_SWAP: "the operator exchanges references A and B (operator check)",
    P3_LOAD: "the operator mounts the test accelerometer and its load (operator check)",
}
