"""A small P2 run on the twin: 8 consumer units with thermal truth, lever arms 0 … 15 cm.

Two units (U0 and U1) share one truth (the same seed): U0 sits at the cube's centre, on the
spin axis in every pose, U1 15 cm from it. The others sit 2 … 13 cm out on the faces'
brackets. The chamber and the units respond within a minute (short time constants) so that
the whole sweep — five calibration points and one held-out point, heating then cooling — runs
in virtual hours but seconds of wall time.
"""

from __future__ import annotations

import fcntl
from collections.abc import Callable
from pathlib import Path

import numpy as np

from imucalib.plan.equipment import (
    ChamberConfig,
    FixtureConfig,
    ImuConfig,
    MountConfig,
    SiteConfig,
    TableConfig,
    TwinEquipment,
)
from imucalib.plan.schema import Plan
from imucalib.procedures.p2.plan import generate_p2_plan
from imucalib.station.runner import RunOptions, run_plan
from imucalib.station.sim import SimStation

#: (name, face, lever arm [m]) of the eight units; U0 and U1 share a truth.
UNITS = (
    ("U0", "+z", (0.0, 0.0, 0.0)),
    ("U1", "+z", (0.15 / np.sqrt(3), 0.15 / np.sqrt(3), 0.15 / np.sqrt(3))),
    ("U2", "-z", (0.0, 0.0, -0.02)),
    ("U3", "+y", (0.0, 0.04, 0.0)),
    ("U4", "-y", (0.03, -0.06, 0.0)),
    ("U5", "+x", (0.08, 0.0, 0.02)),
    ("U6", "-x", (-0.1, 0.02, 0.0)),
    ("U7", "+z", (0.06, -0.06, 0.1)),
)
SHARED_SEED = 1234


def twin_equipment(n: int = len(UNITS), *, hysteresis_fraction: float = 0.1,
                   drop: dict[str, float] | None = None) -> TwinEquipment:
    """The twin of the closed-loop test (module docstring)."""
    units = UNITS[:n]
    return TwinEquipment(
        seed=21,
        site=SiteConfig(latitude_deg=45.0, ambient_temperature_degc=25.0),
        table=TableConfig(kind="single-axis", grade="lab"),
        chamber=ChamberConfig(enabled=True, initial_temperature_degc=25.0,
                              max_ramp_degc_per_min=20.0, air_time_constant_s=20.0,
                              stability_noise_degc=0.0),
        fixture=FixtureConfig(kind="hexahedral", half_edge_m=0.05, mounts=tuple(
            MountConfig(face=face, lever_arm_m=arm) for _, face, arm in units)),  # type: ignore[arg-type]
        imus=tuple(ImuConfig(
            name=name, grade="consumer", sample_rate_hz=50.0, thermal_time_constant_s=40.0,
            seed=SHARED_SEED if name in ("U0", "U1") else None,
            temperature_dependence="typical", hysteresis_fraction=hysteresis_fraction,
            noise="white",
            drop_probability=(drop or {}).get(name, 0.0))
            for name, _, _ in units),
    )


def twin_plan(equipment: TwinEquipment, **overrides: object) -> Plan:
    """The P2 plan of the closed-loop test: short soaks, 120 °/s turns of one revolution."""
    options: dict[str, object] = dict(
        temperatures_degc=(-30.0, -5.0, 20.0, 45.0, 70.0), held_out_degc=(5.0,),
        hysteresis=True, rate_dps=120.0, revolutions=1, static_s=4.0, settle_s=2.0,
        stable_for_s=60.0, resoak_s=5.0, ramp_degc_per_min=20.0, twin=equipment)
    options.update(overrides)
    return generate_p2_plan(**options)  # type: ignore[arg-type]


def run_twin_p2(plan: Plan, path: Path, *, truth_streams: bool = True,
                must_finish: bool = True) -> Path:
    """Run `plan` on its twin into `path` (by default the run must complete), with the truth."""
    assert plan.twin is not None
    station = SimStation(plan.twin, truth_streams=truth_streams)
    summary = run_plan(plan, station, path, options=RunOptions(tick_s=5.0, truth=station.truth),
                       truth_source=station if truth_streams else None)
    assert summary.status == "done" or not must_finish, summary.reason
    return path


def shared_run(base: Path, name: str, make: Callable[[Path], Path]) -> Path:
    """Make a recording once for every pytest-xdist worker (a file lock in the shared base)."""
    path = base / f"{name}.h5"
    done = base / f"{name}.done"
    with open(base / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            if not done.exists():
                path.unlink(missing_ok=True)
                make(path)
                done.touch()
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)
    return path


def true_parameters(path: Path, unit: str, points: list[tuple[int, float]]
                    ) -> dict[int, np.ndarray]:
    """The truth of every P2 parameter of `unit` at each (point, temperature).

    The hysteresis state is replayed (:func:`~imucalib.models.temperature.hysteresis_state`)
    over the unit's true temperature from the truth stream, as the twin's synthesizer did, and
    averaged over the point's measuring windows (small temperature reversals while a point
    holds erode it by a few per cent: minor loops of the Duhem model).
    """
    from imucalib.io.opening import open_recording
    from imucalib.models.imu import ImuModel
    from imucalib.models.temperature import hysteresis_state
    from imucalib.procedures.p2.reduction import PARAM_NAMES

    with open_recording(path) as rec:
        raw = rec.truth["imu_models"][unit]
        spans: dict[int, list[tuple[float, float]]] = {}
        for st in rec.steps:
            if st.role in ("p2.static", "p2.rate") and st.has_valid_window:
                spans.setdefault(int(st.tag_value("point") or 0), []).append(
                    (st.valid_start_s, st.valid_end_s))
        data = rec.read_truth_stream("imu", unit, ["true_temperature_degc"])
    model = ImuModel.from_dict(raw)
    dep = model.gyro.temperature
    assert dep is not None
    state, _ = hysteresis_state(data.columns["true_temperature_degc"], 0.0,
                                dep.hysteresis_width_degc)
    k2 = np.asarray(raw["accel"]["k2"], dtype=float)
    out = {}
    for k, temp in points:
        inside = np.zeros(data.time_s.size, dtype=bool)
        for t0, t1 in spans[k]:
            inside |= (data.time_s >= t0) & (data.time_s < t1)
        s = float(np.mean(state[inside]))
        values = model.parameters_at(temp, hysteresis_state=s)
        out[k] = np.array([values[n] if n in values else k2["xyz".index(n[-1])]
                           for n in PARAM_NAMES])
    return out
