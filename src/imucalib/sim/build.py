"""Build the twin rig that a scenario describes, and the truth behind it.

Contents
--------
:func:`build_rig`
    Scenario → :class:`~imucalib.sim.rig.TwinRig` (equipment, fixture, IMUs with drawn truths).
:class:`BuiltRig`
    The rig, the IMU truths by name, and the truth record stored in a twin Recording.
:func:`scenario_seed`
    The seed of one random component of a scenario (stable: adding an IMU does not change the
    others' truths).

Choices
-------
- Each IMU's truth is drawn with :func:`~imucalib.models.imu.sample_imu_model` from its grade,
  seeded by ``ImuConfig.seed`` or else by the scenario seed and the IMU's position; with
  ``ImuConfig.noise = "white"`` its noise keeps the grade's white terms only (a bias that does
  not wander: closed-loop checks against the deterministic truth, docs/p2.md).
- The sample clock's phase is drawn uniformly within one sample period, so IMUs are not aligned
  with the controller's feedback grid (as on a real station).
- On a centrifuge, a single IMU at the fixture origin (``fixture.lever_arm_m`` zero) is placed at
  the test position r_t on the arm with its x axis pointing **inward** (towards the spin axis), so
  that x reads +ω²·r; a given lever arm is used as it is.
- A hexahedral fixture (the cube of P2) places its IMUs as ``fixture.mounts`` says, or else
  round robin on the faces (IMU i on face i mod 6) on a centred grid of ``spacing_m``
  (:func:`~imucalib.plan.equipment.hexahedral_grid_offsets_m`); up to six IMUs sit at the face
  centres. A mount with ``lever_arm_m`` keeps its face's orientation and sits where it says.
- An array fixture spaces its IMUs ``spacing_m`` apart along x_m, centred on the rotation centre.
- An arm fixture (P3 on a centrifuge) places IMU i at (r_i, 0, 0) in m, r_i =
  ``fixture.arm_radii_m[i]`` signed along the arm (+ on the test side), its x axis pointing
  inward (towards the spin axis): rot_mb is 180° about z for r_i > 0, the identity for r_i < 0,
  so that every unit's x accelerometer reads +ω²·|r_i| (plus the unbalance shift, +c·ω² on the
  test side, −c·ω² on the far side).
- ``ImuConfig.gyro_range_dps`` / ``accel_range_g`` replace the full scale ±range of the drawn
  model's output stage (:class:`~imucalib.models.sensor.SensorSpec`; with a word length its LSB
  scales with the range); None keeps the grade's.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from imucalib import units
from imucalib.models.earth import Site
from imucalib.models.imu import ImuModel, sample_imu_model
from imucalib.models.noise import NoiseModel
from imucalib.plan.equipment import ImuConfig, TwinEquipment, hexahedral_grid_offsets_m
from imucalib.sim.centrifuge import CentrifugeSpec, SimCentrifuge
from imucalib.sim.chamber import ChamberSpec, ImuThermalSpec, SimChamber
from imucalib.sim.fixture import (
    Fixture,
    MountedImu,
    array_fixture,
    hexahedral_fixture,
    single_imu_fixture,
)
from imucalib.sim.rig import TwinRig
from imucalib.sim.synth import ClockSpec, SimImu
from imucalib.sim.table import RateTableSpec, SimRateTable

__all__ = ["BuiltRig", "build_rig", "scenario_seed"]

_PURPOSES = {"table": 1, "chamber": 2, "centrifuge": 3, "synth": 4, "imu-model": 10,
             "imu-phase": 11}


def scenario_seed(seed: int, purpose: str, index: int = 0) -> np.random.SeedSequence:
    """Return the seed sequence of one random component of a scenario.

    Parameters
    ----------
    seed : int
        The scenario's seed.
    purpose : {"table", "chamber", "centrifuge", "synth", "imu-model", "imu-phase"}
        Which component.
    index : int
        The IMU's position for per-IMU purposes.
    """
    return np.random.SeedSequence([abs(int(seed)), _PURPOSES[purpose], int(index)])


@dataclass(frozen=True, eq=False)
class BuiltRig:
    """A rig built from a scenario.

    Attributes
    ----------
    rig : TwinRig
        The stateful twin, at virtual time 0.
    imu_models : dict of str to ImuModel
        The true model of each IMU, by name.
    truth : dict
        What a twin Recording stores under ``/truth`` (JSON-able values).
    """

    rig: TwinRig
    imu_models: dict[str, ImuModel]
    truth: dict[str, Any]


def _table(sc: TwinEquipment) -> SimRateTable | None:
    cfg = sc.table
    if cfg.kind == "none":
        return None
    overrides: dict[str, Any] = {}
    if cfg.max_rate_dps is not None:
        overrides["max_rate_rps"] = cfg.max_rate_dps * units.DEG
    spec = (RateTableSpec.single_axis(cfg.grade, **overrides) if cfg.kind == "single-axis"
            else RateTableSpec.dual_axis_pitch_roll(cfg.grade, **overrides))
    return SimRateTable(spec, rng=np.random.default_rng(scenario_seed(sc.seed, "table")))


def _chamber(sc: TwinEquipment) -> SimChamber | None:
    cfg = sc.chamber
    if not cfg.enabled:
        return None
    spec = ChamberSpec(min_temp_degc=cfg.min_temperature_degc,
                       max_temp_degc=cfg.max_temperature_degc,
                       max_ramp_degc_ps=cfg.max_ramp_degc_per_min / 60.0,
                       air_time_constant_s=cfg.air_time_constant_s,
                       stability_noise_degc=cfg.stability_noise_degc)
    return SimChamber(spec, cfg.initial_temperature_degc,
                      rng=np.random.default_rng(scenario_seed(sc.seed, "chamber")))


def _centrifuge(sc: TwinEquipment) -> SimCentrifuge | None:
    cfg = sc.centrifuge
    if not cfg.enabled:
        return None
    spec = CentrifugeSpec(static_radius_m=cfg.static_radius_m,
                          unbalance_c0_m_per_rps_sq=cfg.unbalance_c0_m_per_rps_sq,
                          unbalance_c_m_per_rps_sq_per_kg=cfg.unbalance_c_m_per_rps_sq_per_kg,
                          max_rate_rps=cfg.max_rate_dps * units.DEG,
                          arm_stretch_s2=cfg.arm_stretch_s2,
                          spin_axis_tilt_rad=cfg.spin_axis_tilt_deg * units.DEG)
    return SimCentrifuge(spec, cfg.load_kg,
                         rng=np.random.default_rng(scenario_seed(sc.seed, "centrifuge")))


def _with_ranges(model: ImuModel, cfg: ImuConfig) -> ImuModel:
    """Return `model` with the full scales `cfg` overrides (the grade's otherwise)."""
    changes: dict[str, Any] = {}
    if cfg.gyro_range_dps is not None:
        changes["gyro_output"] = dataclasses.replace(
            model.gyro_output, range=cfg.gyro_range_dps * units.DEG_PER_S)
    if cfg.accel_range_g is not None:
        changes["accel_output"] = dataclasses.replace(
            model.accel_output, range=cfg.accel_range_g * units.G0_MPS2)
    return dataclasses.replace(model, **changes) if changes else model


def _with_errors(model: ImuModel, cfg: ImuConfig) -> ImuModel:
    """Return `model` with the truth parameters `cfg.errors` replaces (SI)."""
    if not cfg.errors:
        return model
    triads: dict[str, dict[str, Any]] = {"gyro": {}, "accel": {}}
    for key, values in cfg.errors.items():
        triad, _, name = key.partition(".")
        triads[triad][name] = np.asarray(values, dtype=float)
    return dataclasses.replace(model, **{
        t: dataclasses.replace(getattr(model, t), **changes)
        for t, changes in triads.items() if changes})


def _fixture(sc: TwinEquipment) -> Fixture:
    cfg = sc.fixture
    names = [imu.name for imu in sc.imus]
    if cfg.kind == "hexahedral":
        if cfg.mounts:
            faces: list[str] = [m.face for m in cfg.mounts]
            offsets = np.array([m.offset_m for m in cfg.mounts], dtype=float)
        else:
            layout = hexahedral_grid_offsets_m(len(names), cfg.spacing_m)
            faces = [face for face, _, _ in layout]
            offsets = np.array([(ox, oy) for _, ox, oy in layout], dtype=float)
        arms = [m.lever_arm_m for m in cfg.mounts] or [None] * len(names)
        if all(a is None for a in arms):
            return hexahedral_fixture(cfg.half_edge_m, names, faces=faces, offsets_m=offsets)
        # units on brackets: the face's orientation, the origin as given
        mounts = []
        for name, face, offset, given in zip(names, faces, offsets, arms, strict=True):
            mount = hexahedral_fixture(cfg.half_edge_m, [name], faces=[face],
                                       offsets_m=[offset]).mounts[0]
            mounts.append(mount if given is None else dataclasses.replace(
                mount, lever_arm_m_m=np.asarray(given, dtype=float)))
        return Fixture(tuple(mounts))
    if cfg.kind == "arm":
        inward = Rotation.from_euler("z", 180.0, degrees=True)
        return Fixture(tuple(
            MountedImu(name, inward if r > 0.0 else Rotation.identity(), np.array([r, 0.0, 0.0]))
            for name, r in zip(names, cfg.arm_radii_m, strict=True)))
    if cfg.kind == "array":
        n = len(names)
        offsets = np.zeros((n, 3))
        offsets[:, 0] = (np.arange(n) - (n - 1) / 2.0) * cfg.spacing_m
        return array_fixture(offsets, names)
    arm = np.asarray(cfg.lever_arm_m, dtype=float)
    if sc.centrifuge.enabled and not arm.any():
        return single_imu_fixture((sc.centrifuge.static_radius_m, 0.0, 0.0),
                                  Rotation.from_euler("z", 180.0, degrees=True), names[0])
    return single_imu_fixture(arm, None, names[0])


def build_rig(sc: TwinEquipment) -> BuiltRig:
    """Build the rig of scenario (or twin equipment) `sc` at virtual time 0, with its truth.

    Raises
    ------
    ConfigurationError
        If the scenario's parts do not fit together (e.g. an IMU's bandwidth above its Nyquist
        frequency).
    """
    fixture = _fixture(sc)
    models: dict[str, ImuModel] = {}
    sim_imus: list[SimImu] = []
    clocks: dict[str, dict[str, float]] = {}
    for i, cfg in enumerate(sc.imus):
        model_seed = (cfg.seed if cfg.seed is not None
                      else np.random.default_rng(scenario_seed(sc.seed, "imu-model", i)))
        model = sample_imu_model(cfg.grade, model_seed, sample_rate_hz=cfg.sample_rate_hz,
                                 nonlinear=cfg.nonlinear,
                                 temperature_dependence=cfg.temperature_dependence,
                                 hysteresis_fraction=cfg.hysteresis_fraction,
                                 reference_temperature_degc=cfg.reference_temperature_degc)
        model = _with_errors(_with_ranges(model, cfg), cfg)
        if cfg.noise == "white":
            model = dataclasses.replace(
                model, gyro_noise=NoiseModel(white_density=model.gyro_noise.white_density),
                accel_noise=NoiseModel(white_density=model.accel_noise.white_density))
        period_s = 1.0 / model.sample_rate_hz
        phase_s = float(np.random.default_rng(scenario_seed(sc.seed, "imu-phase", i)).uniform(
            0.0, period_s))
        clock = ClockSpec(drift_ppm=cfg.drift_ppm, jitter_s=cfg.jitter_s, latency_s=cfg.latency_s,
                          drop_probability=cfg.drop_probability, phase_s=phase_s)
        thermal = ImuThermalSpec(cfg.thermal_time_constant_s, cfg.self_heating_degc)
        models[cfg.name] = model
        sim_imus.append(SimImu(cfg.name, model, clock, thermal, fixture.mount(cfg.name)))
        clocks[cfg.name] = {"drift_ppm": clock.drift_ppm, "jitter_s": clock.jitter_s,
                            "latency_s": clock.latency_s, "phase_s": phase_s,
                            "drop_probability": clock.drop_probability}
    site = Site(sc.site.latitude_deg, sc.site.height_m, sc.site.heading_deg, sc.site.gravity_mps2)
    centrifuge = _centrifuge(sc)
    rig = TwinRig(site=site, fixture=fixture, imus=sim_imus, table=_table(sc),
                  centrifuge=centrifuge, chamber=_chamber(sc),
                  ambient_temperature_degc=sc.site.ambient_temperature_degc,
                  feedback_rate_hz=sc.table.feedback_rate_hz,
                  rng=np.random.default_rng(scenario_seed(sc.seed, "synth")))
    truth: dict[str, Any] = {
        "imu_models": {name: m.to_dict() for name, m in models.items()},
        "imu_clocks": clocks,
        "mounts": {m.name: {"rot_mb_quat_xyzw": m.rot_mb.as_quat().tolist(),
                            "lever_arm_m_m": m.lever_arm_m_m.tolist()} for m in fixture.mounts},
        "rot_pm_quat_xyzw": fixture.rot_pm.as_quat().tolist(),
        "site": {"latitude_deg": site.latitude_deg, "height_m": site.height_m,
                 "heading_deg": site.heading_deg, "gravity_mps2": site.local_gravity_mps2,
                 "earth_rate_t_rps": site.earth_rate_t_rps.tolist()},
    }
    if centrifuge is not None:
        truth["centrifuge_unbalance_m_per_rps_sq"] = centrifuge.unbalance_m_per_rps_sq
    return BuiltRig(rig=rig, imu_models=models, truth=truth)
