"""Scenario runner: recordings of the scenarios, their valid windows, truth and errors."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from imucalib import units
from imucalib.errors import ConfigurationError, LimitExceededError, RecordingError
from imucalib.io import open_recording
from imucalib.io.streams import axis_columns
from imucalib.models.imu import ImuModel
from imucalib.models.triad import apply_triad
from imucalib.plan.equipment import ImuConfig, TableConfig
from imucalib.plan.schema import PositionStep, RateStep, StaticStep
from imucalib.sim.scenario import BUILTIN_SCENARIOS, Scenario, load_scenario
from imucalib.station.simulate import simulate_scenario

ARCSEC = units.ARCSEC


def small_p1(seed: int = 11) -> Scenario:
    """P1 positions and ±rates with short dwells (the built-in one has a 600 s static)."""
    six = [(0, 0), (0, 180), (90, 0), (90, 180), (0, 90), (0, 270)]
    steps: list = [PositionStep(kind="position", angles_deg=a, settle_s=2.0, record_s=2.0)
                   for a in six]
    for axis in (0, 1):
        for rate in (-60.0, 60.0):
            steps.append(RateStep(kind="rate", axis=axis, rate_dps=rate, settle_s=2.0,
                                  revolutions=2))
    steps.append(PositionStep(kind="position", angles_deg=(0, 0), settle_s=2.0, record_s=1.0))
    return Scenario(name="small-p1", seed=seed, table=TableConfig(kind="dual-axis", grade="high"),
                    imus=(ImuConfig(name="IMU-A", grade="consumer", sample_rate_hz=200.0,
                                    drift_ppm=30.0, jitter_s=1e-4),),
                    steps=tuple(steps), store_truth_streams=True, chunk_s=3.0)


@pytest.fixture(scope="module")
def p1_file(tmp_path_factory) -> tuple[Path, object]:
    path = tmp_path_factory.mktemp("runner") / "p1.h5"
    calls: list[tuple[float, float]] = []
    summary = simulate_scenario(small_p1(), path, progress=lambda d, t: calls.append((d, t)))
    return path, summary, calls


def test_every_step_is_recorded_done_with_its_window(p1_file):
    path, summary, _ = p1_file
    with open_recording(path) as rec:
        steps = rec.steps
        assert [s.kind for s in steps] == [s.kind for s in summary.steps]
        assert all(s.status == "done" for s in steps)
        for s in steps:
            assert s.t_start_s <= s.valid_start_s < s.valid_end_s <= s.t_end_s + 1e-12
        # the station runner acquires one more tick (2 s on the twin) after the last step
        assert summary.virtual_duration_s == pytest.approx(steps[-1].t_end_s + 2.0)
        assert {e.source for e in rec.log} == {"runner"}
        assert all(e.level == "info" for e in rec.log)
        assert "'small-p1' started" in rec.log[0].message
        assert rec.log[-1].message == "plan 'small-p1' completed"


def test_valid_position_windows_lie_in_settled_data(p1_file):
    """Measured table angles stay within 5″ of the commanded (mod 360°) angles in every window."""
    path, _, _ = p1_file
    with open_recording(path) as rec:
        for s in rec.steps:
            if s.kind != "position":
                continue
            data = rec.read_step(s.index, "table", "main")
            for i, axis in enumerate(("pitch", "roll")):
                angle = data.columns[axis_columns(axis)[0]]
                target = math.radians(s.commanded["angles_deg"][i])
                err = np.angle(np.exp(1j * (angle - target)))
                assert np.abs(err).max() < 5.0 * ARCSEC, (s.label, axis)
                rate = data.columns[axis_columns(axis)[1]]
                assert np.abs(rate).max() < 5.0 * ARCSEC


def test_rate_windows_span_whole_revolutions(p1_file):
    path, _, _ = p1_file
    with open_recording(path) as rec:
        for s in rec.steps:
            if s.kind != "rate":
                continue
            axis = ("pitch", "roll")[s.commanded["axis"]]
            angle_col, rate_col = axis_columns(axis)
            data = rec.read_step(s.index, "table", "main")
            rate = data.columns[rate_col]
            assert np.abs(rate - math.radians(s.commanded["rate_dps"])).max() < 0.5 * units.DEG
            turned = abs(data.columns[angle_col][-1] - data.columns[angle_col][0])
            one_sample = abs(math.radians(s.commanded["rate_dps"])) / 100.0  # 100 Hz feedback
            encoder = 5.0 * ARCSEC  # twice the high-grade encoder's peak error
            assert abs(turned - 2 * 2 * math.pi) <= one_sample + encoder


def test_static_means_follow_the_stored_truth(p1_file):
    """Position (0, 0): the mean accelerometer output is the truth model applied to +g on z."""
    path, _, _ = p1_file
    with open_recording(path) as rec:
        truth = rec.truth
        model = ImuModel.from_dict(truth["imu_models"]["IMU-A"])
        g = truth["site"]["gravity_mps2"]
        data = rec.read_step(0, "imu", "IMU-A")
        accel = np.column_stack([data.columns[f"accel_{a}_mps2"] for a in "xyz"])
        expected = apply_triad(model.accel, np.array([0.0, 0.0, g]),
                               rate_b_rps=np.zeros(3), angular_accel_b_rps2=np.zeros(3))
        se = model.accel_noise.white_density / math.sqrt(2.0)  # 2 s of data
        # consumer bias instability (60 µg) adds an unknown offset of a few B: allow for it
        allowed = 5 * se + 4 * model.accel_noise.bias_instability
        assert np.all(np.abs(accel.mean(axis=0) - expected) < allowed)
        truth_stream = rec.read_truth_stream("imu", "IMU-A", t_start_s=data.time_s[0],
                                             t_end_s=data.time_s[-1])
        np.testing.assert_allclose(truth_stream.columns["true_force_z_mps2"], g, rtol=1e-9)


def test_progress_reaches_the_total_monotonically(p1_file):
    _, summary, calls = p1_file
    done = [d for d, _ in calls]
    assert done == sorted(done)
    assert calls[-1] == (summary.virtual_duration_s, summary.virtual_duration_s)


def test_imu_samples_are_counted_and_clock_drift_shows(p1_file):
    path, summary, _ = p1_file
    with open_recording(path) as rec:
        info = rec.stream_info("imu", "IMU-A")
        assert info.n_samples == summary.samples["imu/IMU-A"]
        counter = rec.read_stream("imu", "IMU-A", ["counter"]).columns["counter"]
        np.testing.assert_array_equal(np.diff(counter), 1)
        expected = summary.virtual_duration_s * 200.0 * (1 + 30e-6)
        assert abs(info.n_samples - expected) <= 1.0


def test_same_seed_same_data_other_seed_other_data(tmp_path):
    sc = small_p1(seed=5).model_copy(update={"steps": small_p1().steps[:2]})
    a, b, c = tmp_path / "a.h5", tmp_path / "b.h5", tmp_path / "c.h5"
    simulate_scenario(sc, a)
    simulate_scenario(sc, b)
    simulate_scenario(sc.model_copy(update={"seed": 6}), c)
    with open_recording(a) as ra, open_recording(b) as rb, open_recording(c) as rc:
        x = ra.read_stream("imu", "IMU-A").columns["gyro_x_rps"]
        np.testing.assert_array_equal(x, rb.read_stream("imu", "IMU-A").columns["gyro_x_rps"])
        assert not np.array_equal(x, rc.read_stream("imu", "IMU-A").columns["gyro_x_rps"])


@pytest.mark.parametrize("name", sorted(BUILTIN_SCENARIOS))
def test_builtin_scenarios_validate(name):
    sc = load_scenario(name)
    assert sc.name == name and sc.steps


def test_centrifuge_and_chamber_scenarios_write_their_streams(tmp_path):
    fuge = load_scenario("centrifuge")
    fuge = fuge.model_copy(update={"steps": fuge.steps[:2] + fuge.steps[4:5]})
    summary = simulate_scenario(fuge, tmp_path / "c.h5")
    with open_recording(tmp_path / "c.h5") as rec:
        assert {f"{s.device}/{s.unit}" for s in rec.streams} == {"imu/IMU-0001",
                                                                  "centrifuge/main"}
        spin = rec.steps[2]
        rate = rec.read_step(2, "centrifuge", "main").columns["rate_spin_rps"]
        assert np.abs(rate - math.radians(spin.commanded["rate_dps"])).max() < 0.5 * units.DEG
        # the IMU's x axis points inward: it reads +ω²·r on average
        accel_x = rec.read_step(2, "imu", "IMU-0001").columns["accel_x_mps2"]
        omega = math.radians(spin.commanded["rate_dps"])
        assert accel_x.mean() == pytest.approx(omega**2 * 0.6, rel=2e-3)
    assert summary.samples["centrifuge/main"] > 0
    # the soak to −10 °C and one pose; the streams, not the data, are checked: the units at
    # 20 Hz (not 200) and the soak stable for 60 s (not 600) keep the cooling and cut the
    # soak's 2,400 s of station time by 1,000 s (14.8 → 6.3 s CPU)
    arr = load_scenario("chamber-array")
    soak = arr.steps[0].model_copy(update={"stable_for_s": 60.0})
    arr = arr.model_copy(update={
        "steps": (soak, arr.steps[1]),
        "imus": tuple(i.model_copy(update={"sample_rate_hz": 20.0}) for i in arr.imus)})
    simulate_scenario(arr, tmp_path / "a.h5")
    with open_recording(tmp_path / "a.h5") as rec:
        chamber = rec.read_stream("chamber", "main")
        assert chamber.columns["setpoint_degc"][-1] == pytest.approx(-10.0)
        temps = rec.read_stream("imu", "IMU-0003", ["temperature_degc"]).columns
        assert temps["temperature_degc"][-1] < 15.0  # cooling towards −10 °C


def test_limits_are_checked_before_anything_is_written(tmp_path):
    sc = small_p1().model_copy(update={
        "table": TableConfig(kind="dual-axis", grade="high", max_rate_dps=50.0)})
    path = tmp_path / "x.h5"
    with pytest.raises(LimitExceededError, match=r"axis 'pitch': rate .* \(-60 °/s\) exceeds"):
        simulate_scenario(sc, path)
    assert not path.exists()


def test_existing_file_is_kept(tmp_path):
    path = tmp_path / "keep.h5"
    path.write_bytes(b"precious")
    sc = small_p1().model_copy(update={"steps": small_p1().steps[:1]})
    with pytest.raises(RecordingError, match="exists"):
        simulate_scenario(sc, path)
    assert path.read_bytes() == b"precious"


@pytest.mark.parametrize(("toml", "match"), [
    ('name = "x"\n[[imus]]\nname = "a"\n[[steps]]\nkind = "twirl"\n', r"steps\.0"),
    ('name = "x"\n[[imus]]\nname = "a"\n[[steps]]\nkind = "static"\nduration_s = -1\n',
     r"steps\.0\.static\.duration_s: Input should be greater than 0 \(got -1\)"),
    ('name = "x"\n[[imus]]\nname = "a"\ngrade = "military"\n[[steps]]\nkind = "static"\n'
     'duration_s = 1\n', r"imus\.0\.grade"),
    ('name = "x"\n[[imus]]\nname = "a"\n[[steps]]\nkind = "soak"\ntemperature_degc = 40\n'
     'duration_s = 10\n', r"soak step needs `chamber.enabled = true`"),
    ('name = "x"\n[[imus]]\nname = "a"\nnoisy = 3\n[[steps]]\nkind = "static"\n'
     'duration_s = 1\n', r"imus\.0\.noisy: Extra inputs are not permitted"),
    ('name = "x"\n[table]\nkind = "dual-axis"\n[[imus]]\nname = "a"\n[[steps]]\n'
     'kind = "position"\nangles_deg = [10]\n', r"`angles_deg` needs 2 value\(s\)"),
    ("name = [broken\n", "not valid TOML"),
])
def test_malformed_scenarios_name_the_field(tmp_path, toml, match):
    path = tmp_path / "bad.toml"
    path.write_text(toml, encoding="utf-8")
    with pytest.raises(ConfigurationError, match=match):
        load_scenario(path)


def test_unknown_scenario_name():
    with pytest.raises(ConfigurationError, match=r"neither a built-in \(centrifuge, "):
        load_scenario("no-such-scenario")


def test_toml_scenario_round_trip(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text('name = "mine"\nseed = 3\n[site]\nlatitude_deg = 52.0\n[[imus]]\n'
                    'name = "IMU-9"\ngrade = "navigation"\nsample_rate_hz = 100\n[[steps]]\n'
                    'kind = "static"\nduration_s = 5\n', encoding="utf-8")
    sc = load_scenario(path)
    assert sc == Scenario(name="mine", seed=3, site={"latitude_deg": 52.0},
                          imus=(ImuConfig(name="IMU-9", grade="navigation",
                                          sample_rate_hz=100.0),),
                          steps=(StaticStep(kind="static", duration_s=5.0),))
    summary = simulate_scenario(sc, tmp_path / "mine.h5")
    assert summary.samples == {"imu/IMU-9": 700}  # 5 s, then the run's last tick of 2 s


def test_the_builtin_centrifuge_runs_to_the_end_within_its_gyro_range(tmp_path):
    summary = simulate_scenario(load_scenario("centrifuge"), tmp_path / "c.h5")
    assert summary.status == "done", summary.reason
    assert [s.status for s in summary.steps] == ["done"] * 9
