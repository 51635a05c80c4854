"""P1 benchmarks: accuracy against imucal's Ferraris calibration, and analysis throughput.

1. **imucal vs imucalib on the same twin data.** Each run draws a tactical IMU (linear error
   model, full noise model), records the six static positions (10 s at 100 Hz) and three full
   turns on an ideal dual-axis table, and gives the same windows to imucal's
   ``FerrarisCalibration`` (Ferraris et al. 1995, PyPI ``imucal``) and to imucalib's triad fit.
   Printed: the RMS error of the accelerometer biases and scale/misalignment against the truth
   for both, their ratio (imucal's bias comes from the ± pair of one axis, σ/√2, imucalib's from
   all six positions, σ/√6: the Cramér–Rao bound predicts √3 ≈ 1.73), and the ratio of run times.
2. **Analysis throughput.** A three-repetition P1 recording at 1 kHz (60-minute static records)
   is made on the twin (or given with ``--recording``), then analysed in a child process:
   printed are samples per second and the child's peak resident memory against the file size
   and the largest step.

Run:  .venv/bin/python bench/bench_p1.py [--runs 100] [--skip-throughput] [--recording FILE]
"""

from __future__ import annotations

import argparse
import math
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from imucalib import units
from imucalib.models import ImuModel, NoiseModel, TriadModel, sample_imu_model
from imucalib.procedures.p1.fit import fit_triad
from imucalib.procedures.p1.observations import WindowObservation, table_rotation
from imucalib.sim import Site, TwinRig, single_imu_fixture
from imucalib.sim.synth import SimImu
from imucalib.sim.table import RateTableSpec, SimRateTable

FS_HZ = 100.0
RECORD_S = 10.0
SITE = Site(latitude_deg=45.0)
# imucal's region names → (pitch, roll) on the P1 table
POSITIONS = {"z_p": (0.0, 0.0), "z_a": (0.0, 180.0), "x_p": (90.0, 0.0), "x_a": (-90.0, 0.0),
             "y_p": (0.0, 90.0), "y_a": (0.0, 270.0)}
# turns for imucal's gyro part: (start pose, spinning axis, rate [°/s]) giving a negative reading
TURNS = {"x_rot": ((90.0, 0.0), 1, -90.0), "y_rot": ((0.0, 0.0), 0, 90.0),
         "z_rot": ((0.0, 90.0), 0, -90.0)}


def simulate(seed: int, white_only: bool
             ) -> tuple[dict[str, tuple[np.ndarray, np.ndarray]], TriadModel, NoiseModel]:
    truth = sample_imu_model("tactical", rng=seed, nonlinear=False)
    accel_noise = (NoiseModel(white_density=truth.accel_noise.white_density) if white_only
                   else truth.accel_noise)
    accel = TriadModel(kind="accel", bias=truth.accel.bias,
                       scale_misalignment=truth.accel.scale_misalignment)
    gyro = TriadModel(kind="gyro", bias=truth.gyro.bias,
                      scale_misalignment=truth.gyro.scale_misalignment)
    model = ImuModel(gyro=gyro, accel=accel, gyro_noise=truth.gyro_noise,
                     accel_noise=accel_noise, sample_rate_hz=FS_HZ)
    table = SimRateTable(RateTableSpec.dual_axis_pitch_roll("ideal"))
    rig = TwinRig(site=SITE, fixture=single_imu_fixture(name="u"), imus=[SimImu("u", model)],
                  table=table, rng=seed)
    regions: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    t = 0.0
    for name, (pitch, roll) in POSITIONS.items():
        table.command_position(0, math.radians(pitch), t)
        t = table.command_position(1, math.radians(roll), t) + 5.0
        rig.generate(t)
        s = rig.generate(t + RECORD_S).imu["u"]
        t += RECORD_S
        regions[name] = (s.accel_mps2, s.gyro_rps)
    for name, ((pitch, roll), axis, rate) in TURNS.items():
        table.command_position(0, math.radians(pitch), t)
        t = table.command_position(1, math.radians(roll), t) + 3.0
        rig.generate(t)
        t_ramp = table.command_rate(axis, math.radians(rate), t)
        rig.generate(t_ramp + 1.0)
        s = rig.generate(t_ramp + 1.0 + 360.0 / abs(rate)).imu["u"]
        t = table.command_stop(axis, t_ramp + 1.0 + 360.0 / abs(rate)) + 2.0
        rig.generate(t)
        regions[name] = (s.accel_mps2, s.gyro_rps)
    return regions, accel, accel_noise


def imucalib_fit(regions: dict[str, tuple[np.ndarray, np.ndarray]], noise: NoiseModel
                 ) -> tuple[np.ndarray, float]:
    g = SITE.local_gravity_mps2
    start = time.perf_counter()
    windows = []
    z3 = np.zeros(3)
    for name, (pitch, roll) in POSITIONS.items():
        acc = regions[name][0]
        force = table_rotation(("pitch", "roll"), np.radians([pitch, roll])).inv().apply(
            [0.0, 0.0, g])
        se = noise.white_density / math.sqrt(acc.shape[0] / FS_HZ)
        windows.append(WindowObservation(
            step_index=0, plan_step=0, kind="static", role="calibration", repetition=1,
            tags=("six-position",), label=name, gyro_mean_rps=z3,
            accel_mean_mps2=acc.mean(axis=0), gyro_se_rps=np.ones(3),
            accel_se_mps2=np.asarray(se, dtype=float) * np.ones(3), gyro_std_rps=z3,
            accel_std_mps2=z3, rate_b_rps=z3, force_b_mps2=force,
            angles_rad=np.radians([pitch, roll]), table_rate_rps=0.0, axis=None,
            n_samples=acc.shape[0], n_outliers=0, n_revolutions=0, alignment_error_s=0.0,
            duration_s=RECORD_S))
    fit = fit_triad("accel", windows, model="triad")
    return fit.estimate, time.perf_counter() - start


def imucal_fit(regions: dict[str, tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, float]:
    from imucal import FerrarisCalibration, FerrarisSignalRegions

    g = SITE.local_gravity_mps2
    kwargs = {}
    for name in POSITIONS:
        kwargs[f"acc_{name}"], kwargs[f"gyr_{name}"] = regions[name]
    for name in TURNS:
        kwargs[f"acc_{name}"], kwargs[f"gyr_{name}"] = regions[name]
    start = time.perf_counter()
    cal = FerrarisCalibration()
    cal.grav = g
    info = cal.compute(FerrarisSignalRegions(**kwargs), FS_HZ, from_acc_unit="m/s^2",
                       from_gyr_unit="rad/s")
    elapsed = time.perf_counter() - start
    # imucal: acc = K·R·a + b  → in y = b + (I + M)·a form, I + M = K·R
    km = info.K_a @ info.R_a - np.eye(3)
    return np.r_[info.b_a, km.ravel()], elapsed


def accuracy(runs: int, white_only: bool) -> None:
    err_ours, err_theirs, t_ours, t_theirs = [], [], [], []
    for seed in range(runs):
        regions, truth, noise = simulate(seed, white_only)
        true = np.r_[truth.bias, truth.scale_misalignment.ravel()]
        ours, dt_ours = imucalib_fit(regions, noise)
        theirs, dt_theirs = imucal_fit(regions)
        err_ours.append(ours - true)
        err_theirs.append(theirs - true)
        t_ours.append(dt_ours)
        t_theirs.append(dt_theirs)
    eo, et = np.array(err_ours), np.array(err_theirs)
    rms = lambda e: float(np.sqrt(np.mean(e**2)))  # noqa: E731
    bo, bt = rms(eo[:, :3]), rms(et[:, :3])
    mo, mt = rms(eo[:, 3:]), rms(et[:, 3:])
    kind = ("white noise only (the bound's assumption)" if white_only else
            "the grade's full noise: white + flicker (bias instability)")
    part = "1a" if white_only else "1b"
    print(f"{part}. accuracy against the truth, {runs} twin runs (tactical IMU, six positions "
          f"of {RECORD_S:g} s at {FS_HZ:g} Hz), accelerometer with {kind}")
    print(f"   accelerometer bias RMS error     imucal {bt / units.UG:8.2f} µg   imucalib "
          f"{bo / units.UG:8.2f} µg   ratio imucal/imucalib {bt / bo:5.2f} (bound: √3 = 1.73)")
    print(f"   scale/misalignment RMS error     imucal {mt / units.PPM:8.2f} ppm  imucalib "
          f"{mo / units.PPM:8.2f} ppm  ratio {mt / mo:5.2f}")
    print(f"   time per calibration             imucal {np.median(t_theirs) * 1e3:8.3f} ms   "
          f"imucalib {np.median(t_ours) * 1e3:8.3f} ms   ratio imucalib/imucal "
          f"{np.median(t_ours) / np.median(t_theirs):5.2f}")
    print("   (imucal's time includes its gyro part; imucalib's is the accelerometer fit with "
          "its rank check and covariance)")
    if not white_only:
        print("   with flicker noise the slowly varying bias state, shared by all six positions, "
              "dominates both errors: no choice of estimator averages it out")


def make_recording(path: Path) -> None:
    from imucalib.procedures import generate_p1_plan
    from imucalib.station.runner import RunOptions, run_plan
    from imucalib.station.sim import SimStation

    plan = generate_p1_plan(grade="tactical", sample_rate_hz=1000.0, repetitions=3,
                            static_s=3600.0, warm_up_s=600.0)
    assert plan.twin is not None
    station = SimStation(plan.twin)
    start = time.perf_counter()
    summary = run_plan(plan, station, path, overwrite=True, options=RunOptions(tick_s=2.0))
    print(f"   made {path.name}: {summary.steps_done} steps, {summary.end_s / 3600:.2f} h of "
          f"station time in {time.perf_counter() - start:.1f} s")


def analyse_child(path: Path) -> None:
    """Run in a child process: analyse and print samples, seconds and peak RSS."""
    from imucalib.io import open_recording
    from imucalib.procedures.p1.analysis import P1Options, analyze_p1

    with open_recording(path) as rec:
        n = rec.stream_info("imu", "IMU-0001").n_samples
        largest = max((rec.row_range("imu", "IMU-0001", s.valid_start_s, s.valid_end_s)[1]
                       - rec.row_range("imu", "IMU-0001", s.valid_start_s, s.valid_end_s)[0])
                      for s in rec.steps if s.has_valid_window)
    start = time.perf_counter()
    analysis = analyze_p1(path, options=P1Options(hash_recording=False))
    elapsed = time.perf_counter() - start
    peak_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(f"{n} {largest} {elapsed} {peak_kib} {int(analysis.decision.passed)}")


def throughput(recording: Path | None) -> None:
    print("2. analysis throughput of a three-repetition P1 recording at 1 kHz")
    tmp = None
    if recording is None:
        tmp = tempfile.TemporaryDirectory()
        recording = Path(tmp.name) / "p1-1khz.h5"
        make_recording(recording)
    out = subprocess.run([sys.executable, __file__, "--analyse-child", str(recording)],
                         capture_output=True, text=True, check=True)
    n, largest, elapsed, peak_kib, passed = out.stdout.split()[-5:]
    size = recording.stat().st_size
    print(f"   {int(n):,} IMU samples (file {size / 1e6:,.0f} MB) analysed in "
          f"{float(elapsed):.1f} s: {int(n) / float(elapsed) / 1e6:.2f} M samples/s; decision "
          f"{'PASS' if passed == '1' else 'FAIL'}")
    step_mb = int(largest) * 8 * 8 / 1e6  # time, counter, 6 channels as float64
    print(f"   peak resident memory of the analysis {int(peak_kib) / 1024:,.0f} MiB; the file is "
          f"{size / 2**20:,.0f} MiB, the largest step {int(largest):,} samples "
          f"({step_mb:,.0f} MB of columns)")
    if tmp is not None:
        tmp.cleanup()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--skip-throughput", action="store_true")
    parser.add_argument("--recording", type=Path, default=None)
    parser.add_argument("--analyse-child", type=Path, default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.analyse_child is not None:
        analyse_child(args.analyse_child)
        return
    import imucal

    print(f"imucalib P1 vs imucal {getattr(imucal, '__version__', '?')}, numpy {np.__version__}, "
          f"Python {platform.python_version()}, {platform.machine()}")
    accuracy(args.runs, white_only=True)
    accuracy(args.runs, white_only=False)
    if not args.skip_throughput:
        throughput(args.recording)


if __name__ == "__main__":
    main()
