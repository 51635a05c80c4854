"""Plan parts of the static-position tests on a dual-axis table (pitch, roll).

The g-sensitivity test (docs/g-sensitivity.md, "The plan") records long static positions of
:data:`G_SENSITIVITY_POSITIONS_DEG`; the random-drift test (docs/random-drift.md, "The plan")
repeats its six axis-up positions. Both write the positions with :func:`position_steps` and
carry the twin of :func:`dual_axis_twin` (a high-grade dual-axis table and one IMU).

Contents
--------
:data:`G_SENSITIVITY_POSITIONS_DEG`, :func:`position_steps`, :func:`dual_axis_twin`
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from imucalib.plan.equipment import ImuConfig, SiteConfig, TableConfig, TwinEquipment
from imucalib.plan.schema import PlanStep, PositionStep

__all__ = ["G_SENSITIVITY_POSITIONS_DEG", "dual_axis_twin", "position_steps"]

#: (pitch, roll) [°]: the six axis-up positions, then eight 45° positions (redundancy).
G_SENSITIVITY_POSITIONS_DEG: tuple[tuple[float, float], ...] = (
    (0.0, 0.0), (0.0, 180.0), (90.0, 0.0), (-90.0, 0.0), (0.0, 90.0), (0.0, 270.0),
    (45.0, 0.0), (-45.0, 0.0), (135.0, 0.0), (-135.0, 0.0),
    (0.0, 45.0), (0.0, 135.0), (0.0, 225.0), (0.0, 315.0),
)


def position_steps(positions_deg: Sequence[tuple[float, float]], role: str, *, settle_s: float,
                   record_s: float, extra_tags: tuple[str, ...] = ()) -> list[PlanStep]:
    """Return one static position step per (pitch, roll), tagged ``position=<k>``."""
    return [PositionStep(kind="position", angles_deg=(float(p), float(r)), settle_s=settle_s,
                         record_s=record_s, role=role,
                         label=f"position {k} (pitch {p:g}°, roll {r:g}°)",
                         tags=(f"position={k}", *extra_tags))
            for k, (p, r) in enumerate(positions_deg)]


def dual_axis_twin(grade: str, sample_rate_hz: float, latitude_deg: float, seed: int,
                   noise: str, errors: Mapping[str, Any] | None) -> TwinEquipment:
    """Return a twin: a high-grade dual-axis table and one IMU ``IMU-0001``."""
    return TwinEquipment(
        seed=seed, site=SiteConfig(latitude_deg=latitude_deg),
        table=TableConfig(kind="dual-axis", grade="high"),
        imus=(ImuConfig(name="IMU-0001", grade=grade, sample_rate_hz=sample_rate_hz,
                        noise=noise, errors=dict(errors or {})),))
