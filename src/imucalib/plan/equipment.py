"""The equipment of a twin station: site, rate table, chamber, centrifuge, fixture and IMUs.

A plan may carry one as its ``[twin]`` table (to run it with ``--station sim``); a twin scenario
(:mod:`imucalib.sim.scenario`) is this description plus a plan's steps. The description belongs
to the plan layer: the twin (:mod:`imucalib.sim`) is built from it, never the reverse.

Contents
--------
:class:`TwinEquipment` and its parts :class:`SiteConfig`, :class:`TableConfig`,
:class:`ChamberConfig`, :class:`CentrifugeConfig`, :class:`FixtureConfig`, :class:`ImuConfig`;
:data:`LEGACY_CENTRIFUGE_NAMES`.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from imucalib.models.triad import PARAMETER_SHAPES
from imucalib.plan.bounds import (
    MAX_CENTRIFUGE_RATE_DPS,
    MAX_IMUS,
    MAX_RAMP_DEGC_PER_MIN,
    MAX_SAMPLE_RATE_HZ,
    MAX_TABLE_RATE_DPS,
    MAX_TEMPERATURE_DEGC,
    MAX_TIME_CONSTANT_S,
    MIN_RAMP_DEGC_PER_MIN,
    MIN_SAMPLE_RATE_HZ,
    MIN_TEMPERATURE_DEGC,
    MIN_TIME_CONSTANT_S,
)
from imucalib.plan.fixture_poses import FIXTURE_AXES, FixtureAxis

__all__ = [
    "LEGACY_CENTRIFUGE_NAMES",
    "CentrifugeConfig",
    "ChamberConfig",
    "FixtureConfig",
    "ImuConfig",
    "MountConfig",
    "SiteConfig",
    "TableConfig",
    "TwinEquipment",
    "hexahedral_grid_offsets_m",
]

_ARM = Annotated[float, Field(ge=-5.0, le=5.0)]
_OFFSET = Annotated[float, Field(ge=-1.0, le=1.0)]
_ARM_RADIUS = Annotated[float, Field(ge=-20.0, le=20.0)]

#: Former names of the centrifuge's unbalance coefficients (their unit read as m/s²), mapped to
#: the unit-true names when a file written before the rename is read.
LEGACY_CENTRIFUGE_NAMES: dict[str, str] = {
    "unbalance_c0_m_s2": "unbalance_c0_m_per_rps_sq",
    "unbalance_c_per_kg_m_s2_per_kg": "unbalance_c_m_per_rps_sq_per_kg",
}


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class SiteConfig(_Model):
    """Where the station stands."""

    latitude_deg: float = Field(45.0, ge=-90.0, le=90.0)
    height_m: float = Field(0.0, ge=-500.0, le=9000.0)
    heading_deg: float = Field(0.0, ge=-360.0, le=360.0)
    gravity_mps2: float | None = Field(None, gt=9.7, lt=9.9)
    ambient_temperature_degc: float = Field(20.0, ge=-40.0, le=60.0)


class TableConfig(_Model):
    """The rate table: none, single axis (vertical) or dual axis (pitch outer, roll inner)."""

    kind: Literal["none", "single-axis", "dual-axis"] = "none"
    grade: Literal["ideal", "lab", "high"] = "high"
    max_rate_dps: float | None = Field(None, gt=0.0, le=MAX_TABLE_RATE_DPS)
    feedback_rate_hz: float = Field(100.0, ge=MIN_SAMPLE_RATE_HZ, le=10000.0,
                                    description="controller feedback rate [Hz]")


class ChamberConfig(_Model):
    """A thermal chamber around the fixture (absent when ``enabled`` is false)."""

    enabled: bool = False
    initial_temperature_degc: float = Field(25.0, ge=-70.0, le=180.0)
    min_temperature_degc: float = Field(-55.0, ge=MIN_TEMPERATURE_DEGC, le=MAX_TEMPERATURE_DEGC)
    max_temperature_degc: float = Field(125.0, ge=MIN_TEMPERATURE_DEGC, le=MAX_TEMPERATURE_DEGC)
    max_ramp_degc_per_min: float = Field(5.0, ge=MIN_RAMP_DEGC_PER_MIN, le=MAX_RAMP_DEGC_PER_MIN)
    air_time_constant_s: float = Field(120.0, ge=MIN_TIME_CONSTANT_S, le=MAX_TIME_CONSTANT_S)
    stability_noise_degc: float = Field(0.05, ge=0.0, le=5.0)

    @model_validator(mode="after")
    def _range(self) -> ChamberConfig:
        if self.min_temperature_degc >= self.max_temperature_degc:
            raise ValueError(f"min_temperature_degc ({self.min_temperature_degc:g}) must be "
                             f"below max_temperature_degc ({self.max_temperature_degc:g})")
        return self


class CentrifugeConfig(_Model):
    """A precision centrifuge carrying the test item on its arm.

    The dynamic unbalance shifts the radius by (c0 + c·load)·ω² with ω in rad/s, so both
    coefficients are metres per (rad/s)² (c per kilogram of load as well). Files written with
    the former names (:data:`LEGACY_CENTRIFUGE_NAMES`) are read with the new ones.

    ``spin_axis_tilt_deg`` tilts the spin axis from the vertical and ``arm_stretch_s2`` is the
    arm's elastic stretch κ (Δr = κ·r·ω²), both passed to
    :class:`~imucalib.sim.centrifuge.CentrifugeSpec`. The controller's own imbalance alarm
    latches a fault and stops the spin when the rotor's excursion |c|·ω² (c with the current
    load) exceeds ``imbalance_alarm_um``.
    """

    enabled: bool = False
    static_radius_m: float = Field(1.0, gt=0.0, le=20.0)
    unbalance_c0_m_per_rps_sq: float = Field(
        0.0, ge=-1e-3, le=1e-3, description="radius shift c0·ω² of the rotor [m/(rad/s)²]")
    unbalance_c_m_per_rps_sq_per_kg: float = Field(
        0.0, ge=-1e-3, le=1e-3, description="change of c0 per kg of load [m/(rad/s)²/kg]")
    load_kg: float = Field(0.0, ge=0.0, le=1000.0)
    max_rate_dps: float = Field(720.0, gt=0.0, le=MAX_CENTRIFUGE_RATE_DPS)
    spin_axis_tilt_deg: float = Field(
        0.0, ge=0.0, le=5.0, description="tilt of the spin axis from the vertical [°]")
    arm_stretch_s2: float = Field(
        0.0, ge=0.0, le=1e-4, description="elastic radial stretch κ, Δr = κ·r·ω² [s²]")
    imbalance_alarm_um: float = Field(
        200.0, gt=0.0, le=10000.0,
        description="the controller's imbalance alarm: rotor excursion |c|·ω² [µm]")

    @model_validator(mode="before")
    @classmethod
    def _legacy_names(cls, data: Any) -> Any:
        if isinstance(data, dict) and any(old in data for old in LEGACY_CENTRIFUGE_NAMES):
            data = dict(data)
            for old, new in LEGACY_CENTRIFUGE_NAMES.items():
                if old in data:
                    if new in data:
                        raise ValueError(f"give `{new}` only (`{old}` is its former name)")
                    data[new] = data.pop(old)
        return data


class MountConfig(_Model):
    """Where one IMU sits on the cube (hexahedral fixture).

    The IMU lies on face `face` (its z axis along the face's outward normal, x and y as in
    :data:`imucalib.sim.fixture.HEXAHEDRAL_FACES`), its origin at the face centre moved by
    `offset_m` along its own x and y axes: lever arm h·n̂ + offset_x·x_b + offset_y·y_b in the
    fixture frame, h the half edge. Each offset component must lie within ±h (checked with the
    fixture).
    """

    face: FixtureAxis
    offset_m: tuple[_OFFSET, _OFFSET] = Field((0.0, 0.0), description="along x_b, y_b [m]")
    lever_arm_m: tuple[_ARM, _ARM, _ARM] | None = Field(
        None, description="the IMU origin in the fixture frame, replacing the face position "
                          "(a unit on a bracket, inside or off the cube); the face still sets "
                          "its orientation [m]")

    @model_validator(mode="after")
    def _one_position(self) -> MountConfig:
        if self.lever_arm_m is not None and self.offset_m != (0.0, 0.0):
            raise ValueError("give `offset_m` (on the face) or `lever_arm_m` (anywhere), not both")
        return self


class FixtureConfig(_Model):
    """The fixture carrying the IMUs.

    A hexahedral fixture (the cube of P2) carries up to :data:`~imucalib.plan.bounds.MAX_IMUS`
    IMUs. With explicit `mounts` (one per IMU, in the order of the IMUs) each sits where its
    :class:`MountConfig` says; without them the IMUs fill the faces round robin (IMU i on face
    i mod 6, in the order +z, −z, +y, −y, +x, −x) and the k IMUs of one face sit on a centred
    square grid of `spacing_m` pitch (⌈√k⌉ columns), which must fit inside the face.

    An arm fixture (``kind = "arm"``, on a centrifuge) places IMU i at (r_i, 0, 0) in the fixture
    frame, r_i = ``arm_radii_m[i]`` (one signed position per IMU, in the order of the IMUs):
    x of the fixture frame is the arm direction x_p, positive on the test side (where the test
    position ``centrifuge.static_radius_m`` is). Each IMU's x axis points inward, towards the
    spin axis, so that its x accelerometer reads +ω²·|r_i|: rot_mb is 180° about z for r_i > 0
    and the identity for r_i < 0 (r_i = 0 is refused).
    """

    kind: Literal["single", "hexahedral", "array", "arm"] = "single"
    half_edge_m: float = Field(0.05, gt=0.0, le=1.0)
    lever_arm_m: tuple[_ARM, _ARM, _ARM] = Field((0.0, 0.0, 0.0), description="[m]")
    spacing_m: float = Field(0.05, gt=0.0, le=1.0)
    mounts: tuple[MountConfig, ...] = Field(
        (), max_length=MAX_IMUS, description="hexahedral only: one mount per IMU, in order")
    arm_radii_m: tuple[_ARM_RADIUS, ...] = Field(
        (), max_length=MAX_IMUS,
        description="arm only: each IMU's signed position along the arm, + on the test side [m]")

    @model_validator(mode="after")
    def _mounts(self) -> FixtureConfig:
        if self.arm_radii_m and self.kind != "arm":
            raise ValueError(f"`arm_radii_m` places IMUs along a centrifuge arm (fixture kind "
                             f"'arm'); fixture kind is {self.kind!r}")
        for i, r in enumerate(self.arm_radii_m):
            if r == 0.0:
                raise ValueError(f"arm_radii_m.{i} is 0: an IMU on the spin axis has no inward "
                                 "direction; give a signed position (+ on the test side)")
        if self.mounts and self.kind != "hexahedral":
            raise ValueError(f"`mounts` places IMUs on the faces of a hexahedral fixture; "
                             f"fixture kind is {self.kind!r}")
        h = self.half_edge_m
        seen: dict[tuple[Any, ...], int] = {}
        for i, mount in enumerate(self.mounts):
            place = mount.lever_arm_m if mount.lever_arm_m is not None else mount.offset_m
            j = seen.setdefault((mount.face, *place), i)
            if j != i:
                raise ValueError(f"mounts.{j} and mounts.{i} put two IMUs at the same place "
                                 f"(face {mount.face}, offset_m {mount.offset_m})")
            if max(abs(mount.offset_m[0]), abs(mount.offset_m[1])) > h:
                raise ValueError(
                    f"mounts.{i}: offset_m ({mount.offset_m[0]:g}, {mount.offset_m[1]:g}) m "
                    f"leaves face {mount.face} (each component within ±half_edge_m {h:g} m)")
        return self


class ImuConfig(_Model):
    """One IMU unit: its grade (its truth, thermal behaviour included, is drawn from it), clock.

    ``gyro_range_dps`` and ``accel_range_g`` replace the grade's full scale (None keeps it): a
    navigation-grade gyro (±400 °/s) on a centrifuge spinning faster, or a reference whose
    accelerometer saturates on purpose. With a converter word length the LSB scales with it.

    ``errors`` replaces parameters of the drawn truth by given values, keyed
    ``"<triad>.<parameter>"`` (``"gyro.scale_asymmetry"``, ``"accel.k3"``; the parameters of
    :class:`~imucalib.models.triad.TriadModel`, SI), each a list of its shape (3 values for a
    per-axis term, 3 lists of 3 for a matrix): a known nonlinearity, asymmetry or cross-term
    injected for a test (docs/twin.md).
    """

    name: str = Field(min_length=1, max_length=64)
    grade: Literal["consumer", "tactical", "navigation"] = "tactical"
    sample_rate_hz: float | None = Field(None, ge=MIN_SAMPLE_RATE_HZ, le=MAX_SAMPLE_RATE_HZ,
                                         description="output data rate [Hz]")
    seed: int | None = Field(None, ge=0, lt=2**63)
    drift_ppm: float = Field(0.0, ge=-1000.0, le=1000.0)
    jitter_s: float = Field(0.0, ge=0.0, le=0.1)
    latency_s: float = Field(0.0, ge=0.0, le=1.0)
    drop_probability: float = Field(0.0, ge=0.0, lt=1.0)
    gyro_range_dps: float | None = Field(
        None, gt=0.0, le=100000.0, description="gyro full scale ±, replacing the grade's [°/s]")
    accel_range_g: float | None = Field(
        None, gt=0.0, le=10000.0, description="accelerometer full scale ±, replacing the "
                                              "grade's [g]")
    thermal_time_constant_s: float = Field(600.0, ge=MIN_TIME_CONSTANT_S,
                                           le=MAX_TIME_CONSTANT_S)
    self_heating_degc: float = Field(0.0, ge=0.0, le=50.0)
    nonlinear: bool = True
    noise: Literal["grade", "white"] = Field(
        "grade", description="grade: the grade's noise (white, bias instability, random walks); "
                             "white: its white noise only — a bias that does not wander, for "
                             "checks against the deterministic truth")
    temperature_dependence: Literal["none", "typical"] = Field(
        "none", description="'typical': cubic temperature dependence of biases, scale factors "
        "and misalignments (imucalib.models.imu.sample_imu_model)")
    hysteresis_fraction: float = Field(
        0.0, ge=0.0, le=0.5, description="thermal hysteresis amplitude as a fraction of each "
        "parameter's swing over -40…85 °C (with 'typical') [–]")
    reference_temperature_degc: float = Field(
        25.0, ge=MIN_TEMPERATURE_DEGC, le=MAX_TEMPERATURE_DEGC,
        description="T0, where the drawn parameters hold (with 'typical') [°C]")
    errors: dict[str, tuple[float, ...] | tuple[tuple[float, ...], ...]] = Field(
        default_factory=dict, description="truth parameters replaced: '<triad>.<parameter>' → "
                                          "values (SI, the parameter's shape)")

    @model_validator(mode="after")
    def _thermal(self) -> ImuConfig:
        if self.hysteresis_fraction > 0.0 and self.temperature_dependence == "none":
            raise ValueError("hysteresis_fraction > 0 needs temperature_dependence = 'typical'")
        return self

    @model_validator(mode="after")
    def _errors(self) -> ImuConfig:
        for key, values in self.errors.items():
            triad, _, name = key.partition(".")
            if triad not in ("gyro", "accel") or name not in PARAMETER_SHAPES:
                raise ValueError(f"errors: {key!r} is not '<gyro|accel>.<parameter>' with a "
                                 f"parameter of {sorted(PARAMETER_SHAPES)}")
            arr = np.asarray(values, dtype=float)
            if arr.shape != PARAMETER_SHAPES[name] or not np.all(np.isfinite(arr)):
                raise ValueError(f"errors: {key} must be finite values of shape "
                                 f"{PARAMETER_SHAPES[name]}; got shape {arr.shape}")
        return self


def hexahedral_grid_offsets_m(n_imus: int, spacing_m: float) -> list[tuple[str, float, float]]:
    """Return the default layout of `n_imus` IMUs on the cube: (face, offset x_b, offset y_b).

    IMU i sits on face i mod 6 (+z, −z, +y, −y, +x, −x); the k IMUs of one face fill a centred
    grid of ⌈√k⌉ columns and ⌈k / columns⌉ rows with pitch `spacing_m`, row by row (x_b along a
    row, y_b from row to row). One IMU on a face sits at its centre. [m]
    """
    counts = [len(range(f, n_imus, 6)) for f in range(6)]
    grids: list[list[tuple[float, float]]] = []
    for k in counts:
        cols = max(1, math.ceil(math.sqrt(k)))
        rows = max(1, math.ceil(k / cols))
        cells = [((c - (cols - 1) / 2.0) * spacing_m, ((rows - 1) / 2.0 - r) * spacing_m)
                 for r in range(rows) for c in range(cols)]
        grids.append(cells[:k])
    return [(FIXTURE_AXES[i % 6], *grids[i % 6][i // 6]) for i in range(n_imus)]


def _check_hexahedral(fixture: FixtureConfig, n_imus: int) -> None:
    h = fixture.half_edge_m
    if fixture.mounts:
        if len(fixture.mounts) != n_imus:
            raise ValueError(f"fixture.mounts must hold one mount per IMU ({n_imus}); got "
                             f"{len(fixture.mounts)}")
        return
    if n_imus <= 6:
        return
    per_face = math.ceil(n_imus / 6)
    cols = math.ceil(math.sqrt(per_face))
    reach = (cols - 1) / 2.0 * fixture.spacing_m
    if reach > h + 1e-12:
        raise ValueError(
            f"{n_imus} IMUs on a hexahedral fixture: up to {per_face} per face on a "
            f"{cols}×{math.ceil(per_face / cols)} grid of spacing_m {fixture.spacing_m:g} m reach "
            f"{reach:g} m from the face centre, beyond half_edge_m {h:g} m; use a smaller "
            "spacing, a larger cube or explicit fixture.mounts")


class TwinEquipment(_Model):
    """The twin station without a step list: site, equipment, fixture and IMUs.

    It is what a simulated station is built from (:func:`imucalib.sim.build.build_rig`); a twin
    scenario adds a plan's steps, and a test plan can carry one as its ``[twin]`` table.
    """

    seed: int = Field(0, ge=-(2**63), lt=2**63)
    site: SiteConfig = Field(default_factory=SiteConfig)
    table: TableConfig = Field(default_factory=TableConfig)
    chamber: ChamberConfig = Field(default_factory=ChamberConfig)
    centrifuge: CentrifugeConfig = Field(default_factory=CentrifugeConfig)
    fixture: FixtureConfig = Field(default_factory=FixtureConfig)
    imus: tuple[ImuConfig, ...] = Field(min_length=1, max_length=MAX_IMUS)

    @model_validator(mode="after")
    def _consistent_equipment(self) -> TwinEquipment:
        names = [imu.name for imu in self.imus]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"IMU names must be unique; repeated: {dup}")
        if self.fixture.kind == "hexahedral":
            _check_hexahedral(self.fixture, len(self.imus))
        if self.fixture.kind == "arm" and len(self.fixture.arm_radii_m) != len(self.imus):
            raise ValueError(
                f"fixture kind 'arm' needs one arm_radii_m entry per IMU ({len(self.imus)}: "
                f"{names}); got {len(self.fixture.arm_radii_m)}")
        if self.fixture.kind == "single" and len(self.imus) > 1:
            raise ValueError(
                f"fixture kind 'single' carries one IMU; got {len(self.imus)} (use 'array')"
            )
        if self.centrifuge.enabled and self.table.kind != "none":
            raise ValueError("a twin station has either a rate table or a centrifuge, not both")
        return self

    @property
    def table_axes(self) -> int:
        """Return the number of rate-table axes (0 without a table)."""
        return {"none": 0, "single-axis": 1, "dual-axis": 2}[self.table.kind]
