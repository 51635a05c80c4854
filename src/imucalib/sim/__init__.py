"""The station's digital twin.

Equipment and kinematics: :mod:`~imucalib.models.earth` (site, Earth rate, normal gravity;
re-exported here),
:mod:`~imucalib.sim.table` (single- and dual-axis rate tables), :mod:`~imucalib.sim.chamber`
(thermal chamber, IMU thermal lag), :mod:`~imucalib.sim.centrifuge` (precision centrifuge with
dynamic unbalance), :mod:`~imucalib.sim.fixture` (IMU mounts), :mod:`~imucalib.sim.kinematics`
(true angular rate and specific force of each IMU). Frames and signs: :mod:`imucalib.conventions`.

The station together: :mod:`~imucalib.sim.synth` (an IMU at its own clock),
:mod:`~imucalib.sim.rig` (:class:`TwinRig`, every stream of the station in virtual time),
:mod:`~imucalib.sim.scenario` (what to simulate: twin equipment plus a plan's steps),
:mod:`~imucalib.sim.build` (equipment → rig and truth). Field calibration without a table:
:mod:`~imucalib.sim.handheld` (a hand-held session on a desk and its truth;
:mod:`~imucalib.sim.handheld_csv` writes it as a user's files) on
:mod:`~imucalib.sim.hand_motion` (the hand's attitude, rate and angular acceleration). A
scenario is run into a Recording by the station runner on the simulated station
(:mod:`imucalib.station.simulate`).
"""

from __future__ import annotations

from imucalib.models.earth import (
    Site,
    earth_rate_n_rps,
    gravity_n_mps2,
    normal_gravity_gradient_ps2,
    normal_gravity_mps2,
    rot_nt,
)
from imucalib.sim.build import BuiltRig, build_rig
from imucalib.sim.centrifuge import CentrifugeSpec, SimCentrifuge, dynamic_radius_m
from imucalib.sim.chamber import ChamberSpec, ImuThermalSpec, SimChamber, imu_temperature_degc
from imucalib.sim.fixture import (
    HEXAHEDRAL_FACE_NAMES,
    HEXAHEDRAL_FACES,
    Fixture,
    MountedImu,
    array_fixture,
    as_rotation,
    hexahedral_fixture,
    single_imu_fixture,
)
from imucalib.sim.hand_motion import HandMotion, HandMove, HandSegment
from imucalib.sim.handheld import (
    HARSH,
    HandheldSession,
    HandRotation,
    StaticPose,
    handheld_session,
    harsh_handheld_session,
)
from imucalib.sim.handheld_csv import WrittenCsv, write_session_csv
from imucalib.sim.kinematics import (
    ImuKinematics,
    PlatformMotion,
    compute_fixture_kinematics,
    compute_imu_kinematics,
    stationary_platform_motion,
)
from imucalib.sim.rig import RigChunk, TwinRig
from imucalib.sim.scenario import BUILTIN_SCENARIOS, Scenario, load_scenario
from imucalib.sim.synth import ClockSpec, ImuSamples, ImuSynthesizer, SimImu
from imucalib.sim.table import (
    AxisSpec,
    RateTableSpec,
    SimRateTable,
    TableFeedback,
    TableGrade,
    compute_platform_motion,
)

__all__ = [
    "BUILTIN_SCENARIOS",
    "HARSH",
    "HEXAHEDRAL_FACES",
    "HEXAHEDRAL_FACE_NAMES",
    "AxisSpec",
    "BuiltRig",
    "CentrifugeSpec",
    "ChamberSpec",
    "ClockSpec",
    "Fixture",
    "HandMotion",
    "HandMove",
    "HandRotation",
    "HandSegment",
    "HandheldSession",
    "ImuKinematics",
    "ImuSamples",
    "ImuSynthesizer",
    "ImuThermalSpec",
    "MountedImu",
    "PlatformMotion",
    "RateTableSpec",
    "RigChunk",
    "Scenario",
    "SimCentrifuge",
    "SimChamber",
    "SimImu",
    "SimRateTable",
    "Site",
    "StaticPose",
    "TableFeedback",
    "TableGrade",
    "TwinRig",
    "WrittenCsv",
    "array_fixture",
    "as_rotation",
    "build_rig",
    "compute_fixture_kinematics",
    "compute_imu_kinematics",
    "compute_platform_motion",
    "dynamic_radius_m",
    "earth_rate_n_rps",
    "gravity_n_mps2",
    "handheld_session",
    "harsh_handheld_session",
    "hexahedral_fixture",
    "imu_temperature_degc",
    "load_scenario",
    "normal_gravity_gradient_ps2",
    "normal_gravity_mps2",
    "rot_nt",
    "single_imu_fixture",
    "stationary_platform_motion",
    "write_session_csv",
]
