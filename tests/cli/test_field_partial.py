"""A field calibration that cannot fit its gyro triad returns what it could (docs/field.md,
"A partial result"): the accelerometer and the static gyro terms, a note, exit status 3, and
`apply` corrects with what is there; a rotation that disagrees with the others is left out and
named; a fit that cannot converge names the rotations that disagree."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.cli.calibrate import PARTIAL_EXIT_CODE
from imucalib.estimation.gyro_rotations import rotation_disagreement
from imucalib.procedures.common.static_intervals import FieldLog
from imucalib.procedures.field.analysis import FieldOptions, analyze_field
from imucalib.sim import handheld_session, write_session_csv

runner = CliRunner()


def _fit(session, gyro=None, **options):
    log = FieldLog("IMU", "twin", session.time_s,
                   session.gyro_rps if gyro is None else gyro, session.accel_mps2)
    return analyze_field(log, FieldOptions(latitude_deg=45.0, **options))


def test_unusable_rotations_give_a_partial_result_exit_3_and_apply_works(tmp_path: Path):
    # a ±20 °/s gyro: every hand turn clips, so no rotation can teach the gyro triad
    s = handheld_session("consumer", seed=5, noise="white", gyro_range_dps=20.0)
    written = write_session_csv(s, tmp_path / "hand.csv")
    out = tmp_path / "out"
    res = runner.invoke(app, ["calibrate", "field", str(written.path), "--latitude", "45",
                              "-o", str(out), "--no-record"])
    assert res.exit_code == PARTIAL_EXIT_CODE == 3, res.output
    assert "partial result: left out the gyro triad" in res.output
    assert "Traceback" not in res.output
    doc = json.loads((out / "hand.IMU.field.report.json").read_text(encoding="utf-8"))
    assert doc["omitted"] and doc["omitted"][0].startswith("the gyro triad")
    assert any(n.startswith("PARTIAL RESULT") for n in doc["notes"])
    assert "accel_M_xx" in doc["parameters"] and "gyro_bias_x" in doc["parameters"]
    assert "gyro_M_xx" not in doc["parameters"]
    # apply corrects the accelerometer with what is there
    corrected = tmp_path / "corrected.csv"
    res = runner.invoke(app, ["apply", str(out / "hand.IMU.field.result.json"),
                              str(written.path), "-o", str(corrected)])
    assert res.exit_code == 0, res.output
    import pandas as pd

    df = pd.read_csv(corrected)
    accel = df[[c for c in df.columns if c.startswith("accel_")]].to_numpy()
    still = np.zeros(len(s), dtype=bool)
    for p in s.statics:
        still |= (s.time_s >= p.start_time_s + 0.5) & (s.time_s <= p.stop_time_s - 0.5)
    g = s.site.local_gravity_mps2
    raw = np.abs(np.linalg.norm(s.accel_mps2[still], axis=1).mean() - g)
    fixed = np.abs(np.linalg.norm(accel[still[:len(accel)]], axis=1).mean() - g)
    assert fixed < 0.2 * raw


def test_the_gyro_form_asked_for_fails_instead():
    s = handheld_session("consumer", seed=5, noise="white", gyro_range_dps=20.0)
    with pytest.raises(Exception, match="rotations"):
        _fit(s, gyro_form="gravity")


def test_a_rotation_that_disagrees_is_left_out_and_named():
    s = handheld_session("consumer", seed=5, noise="white")
    gyro = s.gyro_rps.copy()
    rot = s.rotations[7]
    mid = 0.5 * (rot.start_time_s + rot.stop_time_s)
    gyro[(s.time_s >= mid) & (s.time_s < mid + 0.05), 0] += np.radians(60.0)  # a knock
    r = _fit(s, gyro)
    left = [row for row in r.rotations if "left_out" in row]
    assert len(left) == 1 and left[0]["start_time_s"] <= mid <= left[0]["end_time_s"]
    assert "disagrees with the other rotations" in left[0]["left_out"]
    assert any("1 of 24 rotations left out" in n for n in r.notes)
    rotations = next(q for q in r.quality if q.group == "gyro (rotations)")
    assert not rotations.misfit
    clean = _fit(s)
    assert not any("left_out" in row for row in clean.rotations)


def test_a_misfit_of_every_rotation_is_not_hidden_by_leaving_some_out():
    s = handheld_session("consumer", seed=11, noise="white",
                         errors={"gyro.scale_asymmetry": [3e-3, -3e-3, 3e-3]})
    r = _fit(s)
    assert not any("left_out" in row for row in r.rotations)
    assert next(q for q in r.quality if q.group == "gyro (rotations)").misfit


def test_a_fit_that_cannot_converge_names_the_rotations_that_disagree():
    # a gyro twice as sensitive as its import options say: turns of 180° read 360°
    m = (np.eye(3) * 1.0 + 0.05).tolist()
    s = handheld_session("consumer", seed=3, noise="white",
                         errors={"gyro.scale_misalignment": m})
    r = _fit(s)   # auto: a partial result, saying why
    assert r.omitted and not r.result.has_triad("gyro") and r.result.has_triad("accel")
    assert "did not converge" in r.omitted[0]
    assert re.search(r"disagree most at the nominal scale: .* s \(\d", r.omitted[0])
    assert "check --gyro-scale" in r.omitted[0]



def test_rotation_disagreement_is_residual_over_sigma():
    from imucalib.estimation.gyro_rotations import RotationObservation

    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 2.0, 201)
    obs = []
    for k in range(3):
        axis = np.eye(3)[k]
        rate = np.outer(np.sin(np.pi * t / 2.0) * np.pi / 4.0, axis)   # a 90° turn
        obs.append(RotationObservation(
            kind="gravity", time_s=t, gyro_rps=rate + 1e-4 * rng.standard_normal(rate.shape),
            bias_rps=np.zeros(3), bias_std_rps=np.full(3, 1e-5),
            accel_before_mps2=np.array([0.0, 0.0, 9.8]) if k < 2 else np.array([9.8, 0, 0]),
            accel_before_std=np.full(3, 1e-3),
            accel_after_mps2=np.array([0.0, 0.0, 9.8]), accel_after_std=np.full(3, 1e-3)))
    far = rotation_disagreement(obs, np.zeros(9), gyro_noise_density_rps_rthz=1e-5)
    assert far.shape == (3,) and np.all(far >= 0) and np.all(np.isfinite(far))
