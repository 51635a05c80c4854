"""Plans and stations shared by the station tests."""

from __future__ import annotations

import pytest

from imucalib.plan import Plan
from imucalib.procedures import generate_p1_plan


def small_p1(**kwargs) -> Plan:
    """P1's structure (docs/p1.md), short dwells and a 200 Hz IMU (seconds of virtual time)."""
    args = dict(name="small-p1", grade="consumer", rates_dps=(-60.0, 0.0, 60.0),
                held_out_rates_dps=(), revolutions=1, static_s=20.0, settle_s=3.0,
                record_s=2.0, rate_settle_s=2.0, repetitions=1, warm_up_s=5.0,
                sample_rate_hz=200.0, seed=4)
    args.update(kwargs)
    return generate_p1_plan(**args)


@pytest.fixture
def plan() -> Plan:
    return small_p1()
