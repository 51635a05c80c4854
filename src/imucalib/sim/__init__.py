"""The station's digital twin.

Equipment and kinematics: :mod:`~imucalib.sim.earth` (site, Earth rate, normal gravity),
:mod:`~imucalib.sim.table` (single- and dual-axis rate tables), :mod:`~imucalib.sim.chamber`
(thermal chamber, IMU thermal lag), :mod:`~imucalib.sim.centrifuge` (precision centrifuge with
dynamic unbalance), :mod:`~imucalib.sim.fixture` (IMU mounts), :mod:`~imucalib.sim.kinematics`
(true angular rate and specific force of each IMU). Frames and signs: :mod:`imucalib.conventions`.
"""

from __future__ import annotations

__all__: list[str] = []

# --- equipment and kinematics ---
from imucalib.sim.centrifuge import CentrifugeSpec, SimCentrifuge, dynamic_radius_m
from imucalib.sim.chamber import ChamberSpec, ImuThermalSpec, SimChamber, imu_temperature_degc
from imucalib.sim.earth import (
    Site,
    earth_rate_n_rps,
    gravity_n_mps2,
    normal_gravity_gradient_ps2,
    normal_gravity_mps2,
    rot_nt,
)
from imucalib.sim.fixture import (
    HEXAHEDRAL_FACES,
    Fixture,
    MountedImu,
    array_fixture,
    as_rotation,
    hexahedral_fixture,
    single_imu_fixture,
)
from imucalib.sim.kinematics import (
    ImuKinematics,
    PlatformMotion,
    compute_fixture_kinematics,
    compute_imu_kinematics,
    stationary_platform_motion,
)
from imucalib.sim.table import (
    AxisSpec,
    RateTableSpec,
    SimRateTable,
    TableFeedback,
    TableGrade,
    compute_platform_motion,
)

__all__ += [
    "HEXAHEDRAL_FACES",
    "AxisSpec",
    "CentrifugeSpec",
    "ChamberSpec",
    "Fixture",
    "ImuKinematics",
    "ImuThermalSpec",
    "MountedImu",
    "PlatformMotion",
    "RateTableSpec",
    "SimCentrifuge",
    "SimChamber",
    "SimRateTable",
    "Site",
    "TableFeedback",
    "TableGrade",
    "array_fixture",
    "as_rotation",
    "compute_fixture_kinematics",
    "compute_imu_kinematics",
    "compute_platform_motion",
    "dynamic_radius_m",
    "earth_rate_n_rps",
    "gravity_n_mps2",
    "hexahedral_fixture",
    "imu_temperature_degc",
    "normal_gravity_gradient_ps2",
    "normal_gravity_mps2",
    "rot_nt",
    "single_imu_fixture",
    "stationary_platform_motion",
]
# --- end equipment and kinematics ---
