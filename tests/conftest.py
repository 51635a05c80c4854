"""Shared fixtures: twin runs of small P1 plans (session-scoped), used by several test folders."""

from __future__ import annotations

import os

# One BLAS thread per test process, set before numpy loads (the xdist workers inherit it):
# the suite runs two workers on two cores, and OpenBLAS's own threads then fight for them on
# the small solves the analyses are made of. Measured (tests/procedures, -n 2, idle 2-core
# machine): 221 s with one thread, 271 s without (docs/performance.md).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from imucalib.plan import Plan
from imucalib.procedures import generate_p1_plan
from imucalib.station.runner import RunOptions, run_plan
from imucalib.station.sim import SimStation

# --- the records database: every test session writes into its own, never the user's ---------


@pytest.fixture(autouse=True, scope="session")
def _records_database(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Point ``IMUCALIB_DB`` at a fresh SQLite file for the session (subprocesses inherit it).

    ``imucalib calibrate`` and ``imucalib run`` record by default (docs/records.md); without
    this the suite would write into the user's data directory.
    """
    import os

    os.environ["IMUCALIB_DB"] = str(tmp_path_factory.mktemp("records") / "records.db")
    os.environ.pop("IMUCALIB_USER", None)     # who is acting: only what a test says
    # a test that unsets IMUCALIB_DB falls back to the user's data dir: the session's own
    os.environ["XDG_DATA_HOME"] = str(tmp_path_factory.mktemp("data"))
    # the laboratory configuration: none (an empty file), not a ./imucalib.toml or the user's
    empty = tmp_path_factory.mktemp("config") / "imucalib.toml"
    empty.write_text("", encoding="utf-8")
    os.environ["IMUCALIB_CONFIG"] = str(empty)


# --- the order of the run (``make test`` runs ``pytest -n 2``; pyproject sets ``--dist worksteal``)

TESTS = Path(__file__).resolve().parent

#: The test files that take longest, in two groups of about equal time (seconds of each file
#: on a loaded 2-core machine, from ``pytest -n 2 --durations``): P2 twin 190, durability 80,
#: noise fit 50, faults 50, rate transfer twin 35, web supervisor 43–89 | README commands 130
#: (one test), P3 twin 110, P1 closed loop 67, CSV calibration 50, P1 gyro Monte Carlo 45, a
#: run released in a browser 20–47, the web results 27–42. ``worksteal`` gives the first worker
#: the first half of the collection and the second worker the rest; each group leads one half,
#: so the two workers start on the long files at once and the many short tests fill the end of
#: the run (an idle worker takes half of the other's pending tests, from their end). Collected
#: in the usual order the README commands came last and the long files fell to one worker;
#: tests/web, last in the usual order, made a tail of its twin runs (and their waits leave a
#: core idle unless the other worker is busy). The live view in a browser (20–47) stays at the
#: end: it races a paced run against the page, which is safest with few tests beside it. Only
#: the order changes, never a test.
LONGEST = (
    ("procedures/test_p2_twin.py", "station/test_durability.py", "analysis/test_noise_fit.py",
     "station/test_faults.py", "procedures/test_rate_transfer_twin.py", "web/test_supervisor.py"),
    ("test_readme_commands.py", "procedures/test_p3_twin.py", "procedures/test_p1_closed_loop.py",
     "procedures/test_calibrate_csv.py", "procedures/test_p1_gyro_monte_carlo.py",
     "web/test_browser_run.py", "web/test_results.py"),
)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Put each group of :data:`LONGEST` at the front of one half of the collection.

    A stable reordering: the order inside each file, and of all other files, is kept.
    """
    rank = {name: (g, i) for g, names in enumerate(LONGEST) for i, name in enumerate(names)}

    def key(item: pytest.Item) -> tuple[int, int] | None:
        try:
            return rank.get(item.path.resolve().relative_to(TESTS).as_posix())
        except ValueError:
            return None

    keyed = [(key(item), item) for item in items]
    groups = [sorted((k, j, it) for j, (k, it) in enumerate(keyed) if k is not None and k[0] == g)
              for g in range(len(LONGEST))]
    first, second = ([it for _, _, it in group] for group in groups)
    rest = [it for k, it in keyed if k is None]
    cut = max(len(items) // 2 - len(first), 0)
    items[:] = first + rest[:cut] + second + rest[cut:]



def p1_plan(grade: str = "tactical", seed: int = 1, *, repetitions: int = 1,
            ideal: bool = True, static_s: float = 300.0, **kwargs) -> Plan:
    """A short P1 plan at 200 Hz; `ideal`: an ideal table and a linear IMU (truth comparable)."""
    args = dict(grade=grade, seed=seed, repetitions=repetitions, static_s=static_s,
                warm_up_s=10.0, sample_rate_hz=200.0, revolutions=2, settle_s=5.0,
                rate_settle_s=3.0, record_s=10.0)
    args.update(kwargs)
    plan = generate_p1_plan(**args)
    if ideal:
        tw = plan.twin
        assert tw is not None
        tw = tw.model_copy(update={
            "table": tw.table.model_copy(update={"grade": "ideal"}),
            "imus": tuple(i.model_copy(update={"nonlinear": False}) for i in tw.imus)})
        plan = plan.model_copy(update={"twin": tw})
    return plan


def run_twin(plan: Plan, path: Path) -> Path:
    assert plan.twin is not None
    station = SimStation(plan.twin)
    summary = run_plan(plan, station, path, options=RunOptions(tick_s=2.0, truth=station.truth))
    assert summary.status == "done", summary.reason
    return path


def write_planless_recording(path: Path) -> Path:
    """Write a Recording of the twin's IMU at rest that holds no plan (two seconds, one step).

    ``imucalib simulate`` runs its scenario as a plan, so its recordings hold one; this is what
    a recording made without a plan (an import, another tool) looks like to the analysis.
    """
    from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS
    from imucalib.io.recording import RecordingWriter
    from imucalib.io.streams import DEVICE_IMU, imu_stream_spec
    from imucalib.sim.scenario import load_scenario

    station = SimStation(load_scenario("dual-axis-p1").equipment)
    station.clock.sleep(2.0)
    src = station.imus[0]
    block = src.read()
    cols = {"time_s": block.time_s, "device_time_s": block.device_time_s,
            "counter": block.counter, "temperature_degc": block.temperature_degc,
            "saturated": block.saturated}
    for j, c in enumerate(GYRO_COLUMNS):
        cols[c] = block.gyro_rps[:, j]
    for j, c in enumerate(ACCEL_COLUMNS):
        cols[c] = block.accel_mps2[:, j]
    with RecordingWriter(path, streams=[imu_stream_spec(src.name)]) as writer:
        writer.append(DEVICE_IMU, src.name, cols)
        row = writer.begin_step("static", "at rest", 0.0)
        writer.update_step(row, t_end_s=2.0, status="done", valid_start_s=0.0, valid_end_s=2.0)
    return path


@pytest.fixture(scope="session")
def tactical_run(tmp_path_factory) -> Path:
    return run_twin(p1_plan("tactical", 3, repetitions=2), tmp_path_factory.mktemp("p1") / "t.h5")


@pytest.fixture(scope="session")
def consumer_run(tmp_path_factory) -> Path:
    return run_twin(p1_plan("consumer", 5), tmp_path_factory.mktemp("p1") / "c.h5")


def small_plan_file(folder: Path, name: str = "cli-run") -> Path:
    """A P1 plan of a few minutes (one repetition, 100 Hz, a consumer unit), written as TOML."""
    from imucalib.plan import write_plan

    plan = generate_p1_plan(name=name, grade="consumer", rates_dps=(-90.0, 0.0, 90.0),
                            held_out_rates_dps=(), revolutions=1, static_s=5.0, settle_s=2.0,
                            record_s=2.0, rate_settle_s=2.0, repetitions=1, warm_up_s=2.0,
                            sample_rate_hz=100.0, seed=3)
    return write_plan(plan, folder / "plan.toml")


@pytest.fixture(scope="session")
def p1_tools() -> SimpleNamespace:
    """The helpers above, for test modules (which cannot import conftest by name)."""
    return SimpleNamespace(p1_plan=p1_plan, run_twin=run_twin,
                           write_planless_recording=write_planless_recording,
                           small_plan_file=small_plan_file)


# --- a hand-held log (tests/processing/test_static_detector.py, tests/cli/test_field_import_cli.py)

HAND_RATE_HZ = 200.0
HAND_BIAS_DPS = np.array([3.7, -3.7, 3.7])
_G = np.array([0.0, 0.0, 9.80665])


def _rot(axis: np.ndarray, angle: float) -> np.ndarray:
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)


def hand_log(seed: int = 1):
    """A synthetic hand-held log at 200 Hz with a 3.7 °/s gyro bias per axis.

    Static 3 s, 90° about x (raised-cosine rate with a 7 Hz tremor, 2 s), static 3 s, 360°
    about z (3 s), static 3 s, −90° about y (1.5 s), static 3 s. Returns t [s], gyro [rad/s],
    accel [m/s²], the still intervals [(start, end)] and the rotations [(start, end, angle
    vector [rad])].
    """
    rng = np.random.default_rng(seed)
    plan = [("still", 3.0), ((0, np.pi / 2), 2.0), ("still", 3.0), ((2, 2 * np.pi), 3.0),
            ("still", 3.0), ((1, -np.pi / 2), 1.5), ("still", 3.0)]
    dt = 1.0 / HAND_RATE_HZ
    r_bn = np.eye(3)  # body → navigation
    ts, gs, accs = [], [], []
    still, rots = [], []
    t0 = 0.0
    for what, dur in plan:
        n = round(dur * HAND_RATE_HZ)
        t = t0 + np.arange(n) * dt
        if what == "still":
            still.append((t0, t0 + dur))
            w = np.zeros((n, 3))
            f = np.tile(r_bn.T @ _G, (n, 1))
        else:
            ax, ang = what
            u = np.eye(3)[ax]
            s = (t - t0) / dur
            rate = ang / dur * (1 - np.cos(2 * np.pi * s))  # raised cosine, integral = ang
            rate += 0.02 * np.sin(2 * np.pi * 7 * (t - t0)) * (np.abs(ang) / dur)  # tremor
            w = rate[:, None] * u
            phi = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * dt)])
            f = np.array([(r_bn @ _rot(u, p)).T @ _G for p in phi])
            total = float(np.sum(0.5 * (rate[1:] + rate[:-1]) * dt)) + rate[-1] * dt
            r_bn = r_bn @ _rot(u, total)
            rots.append((t0, t0 + dur, total * u))
        ts.append(t)
        gs.append(w)
        accs.append(f)
        t0 += dur
    t = np.concatenate(ts)
    gyro = (np.concatenate(gs) + np.deg2rad(HAND_BIAS_DPS)
            + rng.normal(0, np.deg2rad(0.1), (t.size, 3)))
    accel = (np.concatenate(accs) + np.array([0.05, -0.03, 0.08])
             + rng.normal(0, 0.02, (t.size, 3)))
    return t, gyro, accel, still, rots


@pytest.fixture(scope="session")
def hand_held_log():
    """:func:`hand_log` with seed 1."""
    return hand_log()
