"""analyze_allan_recording on twin recordings: per-axis noise terms, streaming, JSON, bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imucalib import units
from imucalib.analysis import compute_oadev
from imucalib.errors import InvalidInputError
from imucalib.io import ColumnSpec, RecordingWriter, StreamSpec, open_recording
from imucalib.models.noise import NoiseModel
from imucalib.models.noise_generator import simulate_noise
from imucalib.procedures import NoiseCharacterization, analyze_allan_recording

RATE_HZ = 200.0
GYRO = NoiseModel(white_density=0.2 * units.DEG_PER_RTH, bias_instability=5 * units.DEG_PER_H,
                  random_walk=[2e-5, 3e-5, 4e-5], bias_instability_corner_hz=20.0)
ACCEL = NoiseModel(white_density=60 * units.UG_PER_RTHZ, bias_instability=20 * units.UG,
                   bias_instability_corner_hz=20.0)
COLUMNS = ["gyro_x_rps", "gyro_y_rps", "gyro_z_rps", "accel_x_mps2", "accel_y_mps2",
           "accel_z_mps2"]


def spec(gyro_unit: str = "rad/s", raw: bool = False) -> StreamSpec:
    cols = {c: ColumnSpec(gyro_unit if c.startswith("gyro") else "m/s^2",
                          quantity="raw" if raw and c == "gyro_x_rps" else "si")
            for c in COLUMNS}
    cols["temperature_degc"] = ColumnSpec("degC", dtype="f4")
    return StreamSpec("imu", "IMU-0001", cols)


def write(path: Path, *, n_warm: int = 2000, n_static: int = 1 << 15, steps: bool = True,
          gap_at: int | None = None, nan_at: int | None = None, gyro_unit: str = "rad/s",
          raw: bool = False, extra_stream: bool = False) -> dict[str, np.ndarray]:
    n = n_warm + 2 * n_static
    gyro = simulate_noise(GYRO, n, 1 / RATE_HZ, rng=1) + np.array([1e-5, -2e-5, 7.29e-5])
    accel = simulate_noise(ACCEL, n, 1 / RATE_HZ, rng=2) + np.array([0.0, 0.0, 9.81])
    t = np.arange(n) / RATE_HZ
    if gap_at is not None:
        t[gap_at:] += 0.1
    data = {"time_s": t, "temperature_degc": np.where(t < (n_warm + n_static) / RATE_HZ,
                                                      25.0, 40.0).astype(np.float32)}
    scale = units.DEG if gyro_unit == "deg/s" else 1.0
    for i, c in enumerate(COLUMNS[:3]):
        data[c] = gyro[:, i] / scale
    for i, c in enumerate(COLUMNS[3:]):
        data[c] = accel[:, i]
    if nan_at is not None:
        data["accel_y_mps2"][nan_at] = np.nan
    streams = [spec(gyro_unit, raw)]
    if extra_stream:
        streams.append(StreamSpec("imu", "IMU-0002", {"gyro_x_rps": ColumnSpec("rad/s")}))
    with RecordingWriter(path, streams=streams) as w:
        for a in range(0, n, 10_000):
            w.append("imu", "IMU-0001", {k: v[a:a + 10_000] for k, v in data.items()})
        if steps:
            t_w, t_1 = n_warm / RATE_HZ, (n_warm + n_static) / RATE_HZ
            s = w.begin_step("warmup", "warm-up", 0.0)
            w.update_step(s, t_end_s=t_w, status="done")
            s = w.begin_step("static", "static 25 °C", t_w)
            w.update_step(s, t_end_s=t_1, valid_start_s=t_w, valid_end_s=t_1, status="done")
            s = w.begin_step("allan", "static 40 °C", t_1)
            w.update_step(s, t_end_s=n / RATE_HZ, status="done")
    data["gyro"], data["accel"] = gyro, accel
    return data


@pytest.fixture(scope="module")
def twin(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, np.ndarray]]:
    path = tmp_path_factory.mktemp("allan") / "allan.h5"
    return path, write(path)


@pytest.fixture(scope="module")
def result(twin: tuple[Path, dict[str, np.ndarray]]) -> NoiseCharacterization:
    return analyze_allan_recording(twin[0], terms=("white", "bias_instability", "random_walk"))


def test_static_steps_are_analysed_separately(twin, result: NoiseCharacterization) -> None:
    assert [s.label for s in result.segments] == ["static 25 °C", "static 40 °C"]
    assert [s.step_index for s in result.segments] == [1, 2]
    for seg in result.segments:
        assert seg.n_samples == 1 << 15
        assert seg.sample_rate_hz == pytest.approx(RATE_HZ, rel=1e-9)
        assert [c.channel for c in seg.channels] == COLUMNS
    assert result.segments[0].temperature_degc == pytest.approx(25.0)
    assert result.segments[1].temperature_degc == pytest.approx(40.0)
    window = twin[1]["gyro"][2000:2000 + (1 << 15), 2]
    assert result.segments[0].channel("gyro_z").mean_si == pytest.approx(window.mean(), rel=1e-9)


def test_results_equal_the_in_memory_deviation(twin, result: NoiseCharacterization) -> None:
    _, data = twin
    seg = result.segments[0]
    window = data["gyro"][2000:2000 + (1 << 15), 1]
    ref = compute_oadev(window, RATE_HZ)
    np.testing.assert_array_equal(seg.channel("gyro_y_rps").oadev.deviation, ref.deviation)
    np.testing.assert_array_equal(seg.channel("gyro_y_rps").oadev.ci_high, ref.ci_high)


def test_fitted_white_noise_matches_the_twin(result: NoiseCharacterization) -> None:
    for seg in result.segments:
        for ch in seg.channels:
            model = GYRO if ch.sensor == "gyro" else ACCEL
            axis = "xyz".index(ch.channel.split("_")[1])
            term = ch.fit.term("white")
            assert term.detected
            assert abs(term.value_si - model.white_density[axis]) < 4 * term.std_si, ch.channel
    arw = result.segments[0].channel("gyro_x").fit.term("white").display[0]
    assert arw.unit == "°/√h" and arw.value == pytest.approx(0.2, rel=0.03)


def test_scratch_files_give_identical_results(twin, result: NoiseCharacterization,
                                              tmp_path: Path) -> None:
    streamed = analyze_allan_recording(twin[0], steps=[1], memory_limit_samples=1000,
                                       chunk_samples=3333, scratch_dir=tmp_path,
                                       terms=("white", "bias_instability", "random_walk"))
    for a, b in zip(streamed.segments[0].channels, result.segments[0].channels, strict=True):
        np.testing.assert_array_equal(a.oadev.deviation, b.oadev.deviation)
        np.testing.assert_array_equal(a.fit.coefficients, b.fit.coefficients)
    assert list(tmp_path.iterdir()) == []


def test_json_round_trip(result: NoiseCharacterization, tmp_path: Path) -> None:
    path = result.save(tmp_path / "noise.json")
    back = NoiseCharacterization.load(path)
    assert back.to_json() == result.to_json()
    assert json.loads(result.to_json())["format_version"] == 1
    ch = back.segments[1].channel("accel_z")
    np.testing.assert_array_equal(ch.oadev.deviation,
                                  result.segments[1].channel("accel_z").oadev.deviation)
    newer = json.loads(result.to_json()) | {"format_version": 99}
    with pytest.raises(InvalidInputError, match="format_version 99 is newer than this software"):
        NoiseCharacterization.from_json(json.dumps(newer))
    with pytest.raises(InvalidInputError, match="not an imucalib-noise-characterization"):
        NoiseCharacterization.from_json("{}")


def test_exports_from_a_segment(result: NoiseCharacterization) -> None:
    params = result.segments[0].noise_parameters()
    assert params.update_rate_hz == pytest.approx(RATE_HZ)
    assert params.gyroscope_noise_density == pytest.approx(GYRO.white_density[0], rel=0.05)
    assert params.accelerometer_noise_density == pytest.approx(ACCEL.white_density[0],
                                                               rel=0.05)
    assert set(result.segments[0].fits("gyro")) == {"gyro_x", "gyro_y", "gyro_z"}


def test_whole_record_without_steps_and_other_units(tmp_path: Path) -> None:
    path = tmp_path / "nosteps.h5"
    data = write(path, n_warm=0, n_static=1 << 13, steps=False, gyro_unit="deg/s")
    res = analyze_allan_recording(path, channels=["gyro_x_rps"], kinds=("oadev", "mdev"),
                                  terms=("white",))
    seg = res.segments[0]
    assert seg.label == "whole record" and seg.step_index is None
    assert seg.n_samples == 1 << 14
    ref = compute_oadev(data["gyro"][:, 0] / units.DEG * units.DEG, RATE_HZ)
    np.testing.assert_allclose(seg.channel("gyro_x").oadev.deviation, ref.deviation, rtol=1e-12)
    assert set(seg.channel("gyro_x").deviations) == {"oadev", "mdev"}
    with open_recording(path) as rec:  # an open Recording works as well
        assert analyze_allan_recording(rec, channels=["accel_z_mps2"],
                                       terms=("white",)).segments[0].n_samples == 1 << 14


def test_bad_recordings(tmp_path: Path) -> None:
    gap = tmp_path / "gap.h5"
    write(gap, n_warm=0, n_static=4096, steps=False, gap_at=5000)
    with pytest.raises(InvalidInputError, match=r"non-uniform sampling: a gap of 0.105 s "
                                                r"\(nominal interval 0.005 s\) after t = 24.995"):
        analyze_allan_recording(gap)
    nan = tmp_path / "nan.h5"
    write(nan, n_warm=0, n_static=4096, steps=False, nan_at=3000)
    with pytest.raises(InvalidInputError, match=r"whole record, column accel_y_mps2: sample "
                                                r"3000 \(t = 15 s from the start\) is NaN"):
        analyze_allan_recording(nan)
    raw = tmp_path / "raw.h5"
    write(raw, n_warm=0, n_static=1024, steps=False, raw=True)
    with pytest.raises(InvalidInputError, match=r"column 'gyro_x_rps' holds raw device output"):
        analyze_allan_recording(raw)
    two = tmp_path / "two.h5"
    write(two, n_warm=0, n_static=1024, steps=False, extra_stream=True)
    with pytest.raises(InvalidInputError, match=r"has 2 imu stream\(s\) \['IMU-0001', "
                                                r"'IMU-0002'\]; pass `unit` to choose one"):
        analyze_allan_recording(two)
    with pytest.raises(InvalidInputError, match=r"no stream imu/IMU-9 in two.h5"):
        analyze_allan_recording(two, unit="IMU-9")
    with pytest.raises(InvalidInputError, match=r"has no column 'gyro_q_rps'"):
        analyze_allan_recording(two, unit="IMU-0001", channels=["gyro_q_rps"])
    with pytest.raises(InvalidInputError, match="is neither a gyro nor an accelerometer column"):
        analyze_allan_recording(two, unit="IMU-0001", channels=["temperature_degc"])


def test_steps_selection_errors(twin) -> None:
    path, _ = twin
    with pytest.raises(InvalidInputError, match=r"no step 7 in allan.h5; it has 3 step\(s\)"):
        analyze_allan_recording(path, steps=[7])
    only_warm = path.parent / "warm.h5"
    with RecordingWriter(only_warm, streams=[spec()]) as w:
        cols = {c: np.zeros(10) for c in COLUMNS} | {"temperature_degc": np.zeros(10)}
        w.append("imu", "IMU-0001", {"time_s": np.arange(10) / RATE_HZ, **cols})
        s = w.begin_step("warmup", "warm-up", 0.0)
        w.update_step(s, t_end_s=0.05, status="done")
        s = w.begin_step("thermal_soak", "late", 5.0)
        w.update_step(s, t_end_s=6.0, status="done")
    with pytest.raises(InvalidInputError, match=r"has no step of kind \['static', 'allan'\] "
                                                r"\(kinds: \['thermal_soak', 'warmup'\]\)"):
        analyze_allan_recording(only_warm)
    with pytest.raises(InvalidInputError, match=r"late: 0 sample\(s\) in the window "
                                                r"\[5.0, 6.0\) s of imu/IMU-0001"):
        analyze_allan_recording(only_warm, steps=[1])
    with pytest.raises(InvalidInputError, match=r"τ = 1e\+09 s is too long for `oadev`"):
        analyze_allan_recording(path, steps=[0], channels=["gyro_x_rps"], taus=[1e9])
