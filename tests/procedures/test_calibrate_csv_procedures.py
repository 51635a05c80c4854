"""A CSV and its step file of a classical procedure calibrate like the planned run they came from.

A step file may give any procedure's roles (checked against the registry), and carries each
step's tags, table angles and turns; ``imucalib import`` rebuilds the steps and a table stream
from the commanded states. So a tumble run on the twin (a dual-axis table as the dividing head)
and a rate-transfer run (a single-axis rate table), exported with ``imucalib export --step-file``,
calibrate through ``imucalib calibrate CSV --steps FILE`` to what the recording's own analysis
gives, parameter by parameter, with the same σ.

What the reconstruction cannot give back is the table's measured feedback: the tumble at the
measured head angles (its default least-squares form) differs from the recording's by the
twin's encoder error (about 1″, up to ~1.4σ of K0 here), and by exactly the amount the
recording's own two forms differ (least squares at the measured angles, DFT at the commanded
ones); against the recording analysed at the commanded angles it agrees to 1e-3σ. The other
classical tests on a table (installation errors, g-sensitivity, Earth-rate bias, random drift)
go through CSV the same way.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.io.opening import open_recording
from imucalib.io.step_file import load_step_file
from imucalib.plan.schema import Plan
from imucalib.procedures import registry
from imucalib.procedures.earth_rate_bias.plan import generate_earth_rate_bias_plan
from imucalib.procedures.g_sensitivity.plan import generate_g_sensitivity_plan
from imucalib.procedures.installation.plan import generate_installation_plan
from imucalib.procedures.random_drift.plan import generate_random_drift_plan
from imucalib.procedures.rate_transfer.plan import generate_rate_transfer_plan
from imucalib.procedures.rate_transfer.roles import RATE_TRANSFER_RATE
from imucalib.procedures.tumble.plan import generate_tumble_plan
from imucalib.procedures.tumble.roles import TUMBLE_DRIFT, TUMBLE_POSITION

from ._rate_twin import run, with_unit

UNIT = "IMU-0001"


def _export(rec: Path, tmp: Path) -> tuple[Path, Path]:
    csv, steps = tmp / "run.csv", tmp / "steps.toml"
    done = CliRunner().invoke(app, ["export", str(rec), "--stream", f"imu/{UNIT}",
                                    "--out", str(csv), "--step-file", str(steps)])
    assert done.exit_code == 0, done.output
    return csv, steps


def _calibrate(csv: Path, steps: Path, out: Path, procedure: str, *settings: str
               ) -> pd.DataFrame:
    args = ["calibrate", str(csv), "--steps", str(steps), "--out", str(out), "--no-record"]
    for text in settings:
        args += ["--set", text]
    done = CliRunner().invoke(app, args)
    assert done.exit_code == 0, done.output
    assert "table stream reconstructed from the step file" in " ".join(done.output.split())
    with open_recording(out / f"{csv.stem}.imported.h5") as rec:
        assert registry.identify(rec) == procedure
    return pd.read_csv(out / f"{csv.stem}.imported.{UNIT}.{procedure}.parameters.csv")


def _z(result: pd.DataFrame, rows: list[tuple[str, float, float, str]]
       ) -> tuple[np.ndarray, np.ndarray]:
    """z of each parameter against the reference rows (σ of the reference), and σ ratios."""
    assert list(result["parameter"]) == [r[0] for r in rows]
    value = np.array([r[1] for r in rows])
    sigma = np.array([r[2] for r in rows])
    has = np.isfinite(sigma) & (sigma > 0)
    assert has.sum() > 0.8 * len(rows)
    z = (result["value"].to_numpy() - value)[has] / sigma[has]
    return z, result["std_uncertainty"].to_numpy()[has] / sigma[has]


@pytest.fixture(scope="module")
def tumble(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path, Path]:
    tmp = tmp_path_factory.mktemp("tumble-csv")
    plan = generate_tumble_plan(n_positions=12, record_s=20.0, settle_s=3.0,
                                sample_rate_hz=50.0, seed=3)
    rec = run(plan, tmp / "planned.h5")
    csv, steps = _export(rec, tmp)
    return tmp, rec, csv, steps


def test_a_tumble_step_file_carries_roles_tags_and_head_angles(tumble):
    _, rec, _, steps = tumble
    sf = load_step_file(steps)
    assert {s.role for s in sf.used_steps} == {TUMBLE_POSITION, TUMBLE_DRIFT}
    first = sf.used_steps[0]
    assert {"axis=x", "angle=0", "positions=12", "mount=+z", "yaw=90"} <= set(first.tags)
    assert sf.table_axes == ("pitch", "roll") and sf.has_table
    with open_recording(rec) as r:
        planned = [s for s in r.steps if s.role in (TUMBLE_POSITION, TUMBLE_DRIFT)]
    assert [s.angles_deg for s in sf.used_steps] == [tuple(s.commanded["angles_deg"])
                                                      for s in planned]


def test_a_tumble_csv_calibrates_like_its_recording(tumble):
    tmp, rec, csv, steps = tumble
    tumble_proc = registry.get("tumble")
    result = _calibrate(csv, steps, tmp / "out", "tumble")
    commanded = tumble_proc.analyze(rec, options={"method": "dft"}).parameter_rows()
    z, ratio = _z(result, commanded)
    assert np.max(np.abs(z)) < 1e-3, z  # the same samples at the same (commanded) angles
    assert np.all((ratio > 0.99) & (ratio < 1.01)), ratio
    # against the recording at its measured angles: within 1σ but for the encoder error,
    # and differing exactly as the recording's own two forms do
    measured = tumble_proc.analyze(rec).parameter_rows()
    z_own, ratio_own = _z(result, measured)
    z_forms, _ = _z(pd.DataFrame(commanded, columns=result.columns), measured)
    far = np.abs(z_own) > 1.0
    assert np.all(np.abs(z_own[far] - z_forms[far]) < 1e-3), (z_own, z_forms)
    assert np.all((ratio_own > 0.67) & (ratio_own < 1.5)), ratio_own


def test_a_tumble_csv_in_the_dft_form_agrees_with_the_recordings(tumble):
    tmp, rec, csv, steps = tumble
    result = _calibrate(csv, steps, tmp / "out-dft", "tumble", "method=dft")
    z, ratio = _z(result, registry.get("tumble").analyze(
        rec, options={"method": "dft"}).parameter_rows())
    assert np.max(np.abs(z)) < 1e-3 and np.all(np.abs(ratio - 1.0) < 1e-3)


def test_a_rate_transfer_csv_calibrates_like_its_recording(tmp_path):
    plan = with_unit(generate_rate_transfer_plan(rates_dps=(20.0, 45.0, 90.0),
                                                 sample_rate_hz=50.0, seed=2),
                     noise="grade", seed=2)  # a CSV states the grade, not the twin's noise
    rec = run(plan, tmp_path / "planned.h5")
    csv, steps = _export(rec, tmp_path)
    sf = load_step_file(steps)
    assert {s.role for s in sf.used_steps} == {RATE_TRANSFER_RATE}
    assert all(s.kind == "rate" and s.angles_deg is None for s in sf.used_steps)
    result = _calibrate(csv, steps, tmp_path / "out", "rate-transfer")
    rows = registry.get("rate-transfer").analyze(rec).parameter_rows()
    z, ratio = _z(result, rows)
    assert np.all(np.abs(z) <= 1.0), z
    assert np.all((ratio > 0.67) & (ratio < 1.5)), ratio


def _short_plan(name: str) -> Plan:
    static = {"record_s": 30.0, "settle_s": 5.0, "warm_up_s": 10.0, "sample_rate_hz": 20.0,
              "noise": "white", "seed": 1}
    if name == "g-sensitivity":
        return generate_g_sensitivity_plan(grade="tactical", **static)  # type: ignore[arg-type]
    if name == "earth-rate-bias":
        return generate_earth_rate_bias_plan(**static | {"record_s": 60.0})  # type: ignore[arg-type]
    if name == "random-drift":
        return generate_random_drift_plan(repetitions=6, span_s=3000.0,
                                          **static)  # type: ignore[arg-type]
    return with_unit(generate_installation_plan(rate_dps=(30.0, 60.0), sample_rate_hz=50.0,
                                                seed=1), seed=1)


@pytest.mark.parametrize("name", ["installation", "g-sensitivity", "earth-rate-bias",
                                  "random-drift"])
def test_the_other_table_tests_calibrate_from_csv_like_their_recordings(tmp_path, name):
    rec = run(_short_plan(name), tmp_path / "planned.h5")
    csv, steps = _export(rec, tmp_path)
    assert {s.role for s in load_step_file(steps).used_steps} <= set(registry.get(name).roles)
    result = _calibrate(csv, steps, tmp_path / "out", name)
    z, ratio = _z(result, registry.get(name).analyze(rec).parameter_rows())
    assert np.all(np.abs(z) <= 1.0), z
    assert np.all((ratio > 0.67) & (ratio < 1.5)), ratio
