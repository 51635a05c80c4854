"""``--noise-characterization`` of ``imucalib plan new p1`` and ``imucalib plan optimize p1``.

docs/test-design.md, "A noise characterisation in place of the grade's": the flag writes the
file's noise into the plan's ``[imu.noise]`` (the prediction then names it), the optimiser
predicts both plans with it, and a file that is not a noise characterisation is one error
line, exit 2.
"""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.models.imu import sample_imu_model
from imucalib.models.noise_generator import simulate_noise
from imucalib.plan import load_plan
from imucalib.procedures.allan.analysis import analyze_allan_arrays
from imucalib.procedures.common.grade import characterization_config

runner = CliRunner()
RATE_HZ = 100.0


@pytest.fixture(scope="module")
def unit_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A noise JSON of 5.5 min at 100 Hz of a consumer unit's noise."""
    noise = sample_imu_model("consumer", 0, nonlinear=False)
    n = 1 << 15
    gyro = simulate_noise(noise.gyro_noise, n, 1 / RATE_HZ, rng=5)
    accel = simulate_noise(noise.accel_noise, n, 1 / RATE_HZ, rng=6) + np.array([0, 0, 9.81])
    cols = {f"{s}_{a}_{u}": (gyro if s == "gyro" else accel)[:, i]
            for s, u in (("gyro", "rps"), ("accel", "mps2")) for i, a in enumerate("xyz")}
    result = analyze_allan_arrays(np.arange(n) / RATE_HZ, cols, source="unit.csv")
    return result.save(tmp_path_factory.mktemp("unit") / "unit.noise.json")


def test_plan_new_writes_the_characterisation_into_the_plan(unit_file, tmp_path):
    out = tmp_path / "p1.toml"
    result = runner.invoke(app, ["plan", "new", "p1", "--repetitions", "1", "--static-s", "120",
                                 "--noise-characterization", str(unit_file), "--out", str(out)])
    assert result.exit_code == 0, result.output
    plan = load_plan(out)
    assert plan.imu.noise == characterization_config(unit_file)
    assert "[imu.noise]" in out.read_text(encoding="utf-8")
    shown = runner.invoke(app, ["plan", "show", str(out), "--predict"])
    digest = hashlib.sha256(unit_file.read_bytes()).hexdigest()
    assert shown.exit_code == 0, shown.output
    assert (f"noise model (characterisation unit.noise.json (sha256 {digest[:12]}…))"
            in " ".join(shown.stdout.split()))


@pytest.mark.parametrize("command", [["plan", "new", "p1"], ["plan", "optimize", "p1"]])
def test_a_bad_file_is_one_line_exit_2(command, tmp_path):
    bad = tmp_path / "result.json"
    bad.write_text('{"format": "imucalib-calibration-result"}', encoding="utf-8")
    for path, message in ((bad, "noise characterisation result.json: expected format "
                                "'imucalib-noise-characterization'"),
                          (tmp_path / "absent.json", "noise characterisation absent.json: "
                                                     "cannot read it")):
        result = runner.invoke(app, [*command, "--noise-characterization", str(path),
                                     "--out", str(tmp_path / "x.toml")])
        assert result.exit_code == 2, result.output
        assert result.stderr.startswith("error: ") and message in result.stderr
        assert result.stderr.count("\n") == 1 and "Traceback" not in result.output
        assert not (tmp_path / "x.toml").exists()


def test_plan_optimize_predicts_both_plans_with_it(unit_file, tmp_path):
    out = tmp_path / "opt.toml"
    result = runner.invoke(app, ["plan", "optimize", "p1", "--coarse", "--min-static", "120",
                                 "--noise-characterization", str(unit_file), "--out", str(out)])
    assert result.exit_code == 0, result.output
    text = " ".join(result.stdout.split())
    assert "note: noise model of both plans: characterisation unit.noise.json (sha256 " in text
    plan = load_plan(out)
    assert plan.imu.noise == characterization_config(unit_file)
    # the command's margin is the procedure's three repetitions (docs/p1.md rule 6)
    reps = {t for s in plan.steps for t in s.tags if re.fullmatch(r"rep\d+", t)}
    assert len(reps) >= 3


def test_the_request_carries_the_file_and_three_repetitions(monkeypatch, unit_file, tmp_path):
    """What ``plan optimize`` asks the procedure's optimiser, with the flags' defaults."""
    from imucalib.errors import ConfigurationError
    from imucalib.procedures.common import prediction

    asked = []

    def capture(procedure, request):
        asked.append(request)
        raise ConfigurationError("stop here")

    monkeypatch.setattr(prediction, "optimize_plan", capture)
    for extra in ([], ["--noise-characterization", str(unit_file)]):
        result = runner.invoke(app, ["plan", "optimize", "p1", *extra,
                                     "--out", str(tmp_path / "x.toml")])
        assert result.exit_code == 2 and result.stderr == "error: stop here\n"
    assert [r.min_repetitions for r in asked] == [3, 3]
    assert [r.noise_characterization for r in asked] == ["", str(unit_file)]
