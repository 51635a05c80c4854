"""Shared fixtures of the driver tests: small twin rigs and their simulator servers.

Every server listens on 127.0.0.1 with an OS-assigned port and is closed after its test. The
simulated time runs `SPEED` times faster than the wall, so settling waits cost little.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from imucalib.drivers.simulators import SimTimeBase
from imucalib.sim.rig import TwinRig

from ._rigs import SPEED, make_rig


@pytest.fixture
def time_base() -> SimTimeBase:
    return SimTimeBase(SPEED)


@pytest.fixture
def table_rig() -> TwinRig:
    return make_rig()


@pytest.fixture
def servers() -> Iterator[list[Any]]:
    """A list the test appends its servers to; all are closed afterwards."""
    started: list[Any] = []
    yield started
    for server in started:
        server.close()
