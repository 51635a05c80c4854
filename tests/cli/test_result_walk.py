"""Every procedure, from the command line: twin run → calibrate → result file → export → apply.

For each built-in procedure a short plan (``plan new NAME`` with its own length flags) runs on
the twin (``run --station sim``); ``calibrate`` writes the result file, which must validate
against the published JSON Schema (``imucalib schema result``, read with ``jsonschema`` as any
consumer of the schema would); ``export --format result-json`` writes it again from the file
(the same document); ``apply`` corrects the recording with it: a whole triad model as it is, a
classical test's part with the rest nominal (said in a note), and a noise characterisation,
which has no model, refused in one line.
"""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pandas as pd
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.models.result import triad_parameter_names
from imucalib.models.result_document import result_schema
from imucalib.procedures import registry

#: Each procedure's short plan: its own flags (a few minutes of station time at 50–100 Hz).
SHORT = {
    "p1": "--static-s 20 --record-s 5 --settle-s 2 --rate-settle-s 2 --warm-up-s 5 "
          "--revolutions 1 --sample-rate-hz 100",
    "allan": "--record-s 600 --warm-up-s 5 --sample-rate-hz 50",
    "p2": "--n-imus 1 --static-s 5 --settle-s 2 --sample-rate-hz 25 --revolutions 1 "
          "--temperatures 0,25,50 --held-out 10 --no-hysteresis --stable-for-s 60 "
          "--resoak-s 30 --ramp-degc-per-min 10",
    "p3": "--rate-record-s 5 --rest-record-s 5 --tumble-record-s 5 --settle-s 2 --n-rates 4 "
          "--sample-rate-hz 100",
    "rate-transfer": "--revolutions 2 --settle-s 2 --sample-rate-hz 100",
    "installation": "--revolutions 2 --settle-s 2 --sample-rate-hz 100",
    "g-sensitivity": "--record-s 10 --settle-s 2 --warm-up-s 5 --sample-rate-hz 100",
    "earth-rate-bias": "--record-s 10 --settle-s 2 --warm-up-s 5 --sample-rate-hz 100",
    "random-drift": "--record-s 10 --settle-s 2 --warm-up-s 5 --sample-rate-hz 50 "
                    "--repetitions 3 --span-s 600",
    "tumble": "--record-s 5 --settle-s 2 --sample-rate-hz 100",
    "field": "--static-s 3 --init-static-s 10 --sample-rate-hz 100",
}

runner = CliRunner()


def _ok(args: list[str]) -> str:
    done = runner.invoke(app, args)
    assert done.exit_code == 0, f"imucalib {' '.join(args)}:\n{done.output}"
    assert "Traceback" not in done.output
    return done.output


def test_every_built_in_procedure_has_a_short_plan_here():
    assert set(SHORT) == set(registry.BUILTIN)


@pytest.mark.parametrize("name", sorted(SHORT))
def test_twin_run_to_result_file_to_export_to_apply(name: str, tmp_path: Path):
    plan, rec, out = tmp_path / "plan.toml", tmp_path / "run.h5", tmp_path / "out"
    _ok(["plan", "new", name, "--out", str(plan), *SHORT[name].split()])
    _ok(["run", str(plan), "--station", "sim", "--out", str(rec), "--yes"])
    done = runner.invoke(app, ["calibrate", str(rec), "--out", str(out), "--no-record"])
    assert "Traceback" not in done.output
    files = sorted(out.glob("*.result.json"))
    verdicts = {json.loads(p.read_text(encoding="utf-8"))["decision"]["verdict"] for p in files}
    # exit 1 is a FAIL decision (the short P3 run misses its K2 target), 0 any other
    assert done.exit_code == (1 if "FAIL" in verdicts else 0), done.output
    assert files, f"{name} wrote no result file: {sorted(p.name for p in out.iterdir())}"
    validator = jsonschema.Draft202012Validator(result_schema())
    for path in files:
        doc = json.loads(path.read_text(encoding="utf-8"))
        validator.validate(doc)
        assert doc["procedure"] == name and doc["parameters"]
        for p in doc["parameters"]:
            if p["std"] is not None:
                assert p["std"] >= p["std_noise"] * (1 - 1e-12)
        assert all(q["sigma_scale"] >= 1.0 for q in doc["fit_quality"])
    first = files[0]
    doc = json.loads(first.read_text(encoding="utf-8"))
    again = tmp_path / "again"
    _ok(["export", str(first), "--format", "result-json", "--out", str(again)])
    exported = json.loads(next(again.glob("*.result.json")).read_text(encoding="utf-8"))
    validator.validate(exported)
    assert exported == doc
    corrected = tmp_path / "corrected.csv"
    done = runner.invoke(app, ["apply", str(first), str(rec), "--out", str(corrected),
                               "--imu", doc["unit"]])
    assert "Traceback" not in done.output
    has_triad = doc["covariance"] is not None
    if not has_triad:  # a noise characterisation: nothing to apply, one line says so
        assert done.exit_code != 0
        assert "estimates no triad parameter" in done.output
        assert not corrected.exists()
        return
    assert done.exit_code == 0, done.output
    names = set(doc["covariance"]["names"])
    incomplete = [t for t in ("accel", "gyro") if any(n.startswith(t) for n in names)
                  and not set(triad_parameter_names(t, "triad")) <= names]
    said = "applied as nominal (zero)" in " ".join(done.output.split())
    assert said == bool(incomplete) and (doc["calibration"] is None or not incomplete)
    table = pd.read_csv(corrected, nrows=5)
    assert len(table) == 5 and table.columns[0].startswith("time_s")
