"""Calibrating what no P1 plan made: a recording written by ``imucalib simulate``.

The built-in ``dual-axis-p1`` scenario is twin equipment plus steps that carry P1's roles, run by
the one station runner; ``imucalib calibrate`` must run P1 on its file exactly as on a planned run.
The planned run here uses the P1 plan generator with the same rates, revolutions and settling on the
same twin equipment (so the same IMU truth), and the two estimates must agree within their
combined standard uncertainty (4σ), parameter by parameter.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.models.result import CalibrationResult
from imucalib.procedures import generate_p1_plan
from imucalib.procedures.p1.analysis import analyze_p1
from imucalib.sim.scenario import load_scenario

from ..conftest import run_twin

pytestmark = pytest.mark.slow


def test_a_simulated_recording_calibrates_like_the_planned_run(tmp_path):
    runner = CliRunner()
    sim_path = tmp_path / "sim.h5"
    done = runner.invoke(app, ["simulate", "dual-axis-p1", "--out", str(sim_path)])
    assert done.exit_code == 0, done.output
    done = runner.invoke(app, ["calibrate", str(sim_path), "--out", str(tmp_path)])
    assert done.exit_code == 0, done.output  # PASS: every assessed check passes
    unplanned = CalibrationResult.from_json(
        (tmp_path / "sim.IMU-0001.p1.result.json").read_text(encoding="utf-8"))

    scenario = load_scenario("dual-axis-p1")
    plan = generate_p1_plan(grade="tactical", rates_dps=(-100.0, -50.0, 0.0, 50.0, 100.0),
                            held_out_rates_dps=(), revolutions=3, static_s=600.0,
                            settle_s=30.0, record_s=10.0, rate_settle_s=20.0, repetitions=1,
                            warm_up_s=10.0, seed=scenario.seed)
    plan = plan.model_copy(update={"twin": scenario.equipment})
    planned = analyze_p1(run_twin(plan, tmp_path / "planned.h5")).result

    assert unplanned.param_names == planned.param_names
    sigma = np.hypot(np.sqrt(np.diag(unplanned.covariance)),
                     np.sqrt(np.diag(planned.covariance)))
    z = (unplanned.values - planned.values) / sigma
    worst = int(np.argmax(np.abs(z)))
    assert np.all(np.abs(z) <= 4.0), (
        f"{unplanned.param_names[worst]}: {z[worst]:+.2f} combined σ apart")
    # the two windows sets are not the same data: the estimates must differ somewhere
    assert not math.isclose(float(np.max(np.abs(z))), 0.0, abs_tol=1e-6)
