"""Step files: parsing with named errors, writing that parses back, skeletons, and the import."""

from __future__ import annotations

import math

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.errors import InvalidInputError
from imucalib.io.csv_recording import recording_from_csv
from imucalib.io.opening import open_recording
from imucalib.io.step_file import (
    StepFile,
    parse_step_file,
    step_file_skeleton,
    step_file_to_toml,
)

HEAD = 'latitude_deg = 45.0\ntable_axes = ["pitch", "roll"]\n'
POSITION = ('[[steps]]\nstart_s = 1.0\nend_s = 3.0\nrole = "p1.accel-position"\n'
            'label = "z-up"\nangles_deg = [0.0, 0.0]\n')
RATE = ('[[steps]]\nstart_s = 4.0\nend_s = 7.6\nrole = "p1.gyro-rate"\naxis = "pitch"\n'
        'rate_dps = 100.0\nangles_deg = [0.0, 0.0]\n')


def test_a_step_file_parses_and_writes_back_equal():
    sf = parse_step_file(HEAD + POSITION + RATE)
    assert [s.kind for s in sf.steps] == ["static", "rate"]
    assert sf.axis_index(sf.steps[1].axis) == 0
    text = step_file_to_toml(sf)
    assert "angles_deg = [0.0, 0.0]" in text  # arrays on one line
    assert parse_step_file(text) == sf


@pytest.mark.parametrize(("text", "expected"), [
    ("x = [", "is not valid TOML"),
    ('format = "imucalib-plan"\n' + HEAD + POSITION, "expected 'imucalib-steps'"),
    (HEAD, "steps: Field required"),
    (HEAD + POSITION.replace("p1.accel-position", "accel-position"),
     "steps[0]: role 'accel-position' is neither '<procedure>.<purpose>'"),
    (HEAD + POSITION.replace("p1.accel-position", "p1 .accel"), "is neither"),
    (HEAD + POSITION + RATE.replace("angles_deg = [0.0, 0.0]\n", ""),
     "steps[1]: a p1.gyro-rate step needs `angles_deg` (the table angles, outer axis first), "
     "as steps[0] gives them"),
    (HEAD + RATE.replace('axis = "pitch"\n', ""), "needs `axis` (the turning table axis)"),
    (HEAD + RATE.replace('rate_dps = 100.0\n', ""), "a turn (a p1.gyro-rate step with `axis`) "
                                                    "needs `rate_dps`"),
    (HEAD + RATE.replace('axis = "pitch"', 'axis = "yaw"'),
     "steps[0] : `axis` 'yaw' is not one of table_axes ['pitch', 'roll']"),
    (HEAD + POSITION.replace("[0.0, 0.0]", "[0.0]"),
     "steps[0] (z-up): `angles_deg` has 1 angle(s); the table has 2 axes"),
    (HEAD + POSITION.replace("end_s = 3.0", "end_s = 1.0"),
     "`end_s` (1 s) must be after `start_s` (1 s)"),
    (HEAD + POSITION + POSITION.replace("start_s = 1.0", "start_s = 2.0").replace(
        "end_s = 3.0", "end_s = 4.0"), "steps[0] (1–3 s) and steps[1] (from 2 s) overlap"),
    (HEAD.replace("latitude_deg = 45.0\n", "") + POSITION, "`latitude_deg` is required"),
    (HEAD + POSITION.replace("role = \"p1.accel-position\"", 'role = "skip"'),
     "every step's role is 'skip'"),
    (HEAD + POSITION + "colour = 1\n", "steps[0].colour: Extra inputs are not permitted"),
    (HEAD.replace('"roll"', '"tilt"') + POSITION, "'tilt' is not a table axis"),
    (HEAD + POSITION.replace("start_s = 1.0", "start_s = nan"), "finite number"),
    (HEAD + POSITION.replace("[0.0, 0.0]", "[1e308, 0.0]"),  # was accepted (issue 27)
     "steps[0]: `angles_deg` holds 1e+308°; a table angle is within ±360° (a turn either way)"),
    (HEAD + POSITION.replace("[0.0, 0.0]", "[0.0, -360.5]"), "holds -360.5°"),
])
def test_defects_are_named_with_their_step_and_field(text, expected):
    with pytest.raises(InvalidInputError) as err:
        parse_step_file(text, "steps.toml")
    message = str(err.value).replace("steps[0] : ", "steps[0]: ")
    assert message.startswith("steps.toml")
    assert expected.replace("steps[0] : ", "steps[0]: ") in message, message


TUMBLE = ('[[steps]]\nstart_s = 1.0\nend_s = 3.0\nrole = "tumble.position"\nlabel = "x 30°"\n'
          'tags = ["axis=x", "angle=30", "positions=12", "mount=+z", "yaw=90"]\n'
          'angles_deg = [30.0, 0.0]\n')
ALLAN = 'unit = "IMU-9"\n[[steps]]\nstart_s = 1.0\nend_s = 8.0\nrole = "allan.static"\n'


def test_any_procedures_roles_parse_the_grammar_alone_is_checked_here():
    sf = parse_step_file(HEAD + TUMBLE)
    assert [(s.role, s.kind) for s in sf.steps] == [("tumble.position", "static")]
    assert sf.steps[0].tags[1] == "angle=30" and sf.has_table
    unknown = parse_step_file(HEAD + TUMBLE.replace("tumble.position", "tumble.positoin"))
    assert unknown.steps[0].role == "tumble.positoin"  # the registry refuses it where used
    allan = parse_step_file(ALLAN)  # no table state: no latitude needed, no table stream
    assert not allan.has_table and allan.latitude_deg is None


def test_a_skeleton_must_be_labelled_before_it_is_accepted():
    text = step_file_skeleton([("static", 0.5, 3.0), ("rotating", 4.0, 8.0)], unit="IMU-7")
    with pytest.raises(InvalidInputError, match="every step's role is 'skip'"):
        parse_step_file(text)
    labelled = text.replace('# latitude_deg = 0.0', 'latitude_deg = 45.0').replace(
        'role = "skip"\nlabel = "static 0"',
        'role = "p1.accel-position"\nlabel = "static 0"\nangles_deg = [0.0, 0.0]', 1)
    sf = parse_step_file(labelled)
    assert sf.unit == "IMU-7"
    assert [s.role for s in sf.used_steps] == ["p1.accel-position"]
    assert (sf.used_steps[0].start_s, sf.used_steps[0].end_s) == (0.5, 3.0)


def _write_csv(path, t, gyro_rps, accel_mps2):
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps,accel_x_mps2,accel_y_mps2,"
                 "accel_z_mps2\n")
        for row in np.column_stack([t, gyro_rps, accel_mps2]):
            fh.write(",".join(repr(float(v)) for v in row) + "\n")


def test_the_import_reconstructs_the_table_from_the_commanded_states(tmp_path):
    fs = 100.0
    t = np.arange(0.0, 9.0, 1.0 / fs)
    t = np.delete(t, [150, 151])  # a gap of two samples
    gyro = np.zeros((t.size, 3))
    accel = np.tile([0.0, 0.0, 9.8], (t.size, 1))
    _write_csv(tmp_path / "log.csv", t, gyro, accel)
    sf = parse_step_file(HEAD + POSITION + RATE)
    out = recording_from_csv(tmp_path / "log.csv", sf, tmp_path / "log.h5")
    with open_recording(out) as rec:
        assert [s.role for s in rec.steps] == ["p1.accel-position", "p1.gyro-rate"]
        assert all(s.status == "done" for s in rec.steps)
        assert rec.steps[1].commanded["axis"] == 0
        assert rec.steps[1].commanded["rate_dps"] == 100.0
        imu = rec.read_stream("imu", "log")
        # the counter comes from the time column: the gap of two samples stays visible
        assert np.all(np.diff(imu.columns["counter"])[np.diff(imu.time_s) < 0.015] == 1)
        assert int(np.max(np.diff(imu.columns["counter"]))) == 3
        table = rec.read_step(1, "table", "commanded")
        rate = table.columns["rate_pitch_rps"]
        assert np.allclose(rate, math.radians(100.0))
        angle = table.columns["angle_pitch_rad"]
        assert np.allclose(angle, math.radians(100.0) * (table.time_s - 4.0))
        assert np.all(table.columns["angle_roll_rad"] == 0.0)
        assert rec.metadata["table_feedback"] == "reconstructed from the step file"
        assert "commanded" in rec.stream_info("table", "commanded").columns[
            "angle_pitch_rad"].description


def test_steps_without_table_states_import_without_a_table_stream(tmp_path):
    t = np.arange(0.0, 400.0, 0.02)
    rng = np.random.default_rng(5)
    _write_csv(tmp_path / "log.csv", t, rng.normal(0.0, 1e-3, (t.size, 3)),
               np.array([0.0, 0.0, 9.8]) + rng.normal(0.0, 1e-3, (t.size, 3)))
    steps = ALLAN.replace("end_s = 8.0", "end_s = 390.0")
    out = recording_from_csv(tmp_path / "log.csv", parse_step_file(steps), tmp_path / "a.h5")
    with open_recording(out) as rec:
        assert [s.device for s in rec.streams] == ["imu"]
        assert [(s.role, s.kind) for s in rec.steps] == [("allan.static", "static")]
        assert "table_feedback" not in rec.metadata
    (tmp_path / "s.toml").write_text(steps, encoding="utf-8")
    done = CliRunner().invoke(app, ["calibrate", str(tmp_path / "log.csv"), "--steps",
                                    str(tmp_path / "s.toml"), "--out", str(tmp_path / "o"),
                                    "--no-record"])
    assert done.exit_code == 0, done.output
    assert "reconstructed" not in done.output
    assert (tmp_path / "o" / "log.imported.IMU-9.allan.json").is_file()


@pytest.mark.parametrize(("role", "message"), [
    ("tumble.positoin", "step role 'tumble.positoin' is not a role of procedure tumble; its "
                        "roles: tumble.mount, tumble.position, tumble.drift"),
    ("p9.position", "step role 'p9.position' names no known procedure ('p9'); known: p1, "),
])
def test_import_refuses_a_role_its_procedure_lacks_before_writing(tmp_path, role, message):
    t = np.arange(0.0, 9.0, 0.01)
    _write_csv(tmp_path / "log.csv", t, np.zeros((t.size, 3)), np.zeros((t.size, 3)))
    (tmp_path / "s.toml").write_text(HEAD + TUMBLE.replace("tumble.position", role),
                                     encoding="utf-8")
    for args in (["import", str(tmp_path / "log.csv"), "--steps", str(tmp_path / "s.toml"),
                  "--out", str(tmp_path / "r.h5")],
                 ["calibrate", str(tmp_path / "log.csv"), "--steps", str(tmp_path / "s.toml"),
                  "--out", str(tmp_path / "o")]):
        done = CliRunner().invoke(app, args)
        assert done.exit_code == 2, done.output
        lines = done.output.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error:"), done.output
        assert message in " ".join(done.output.split()), done.output
    assert not (tmp_path / "r.h5").exists() and not list(tmp_path.glob("o/*"))


def test_a_step_with_too_few_samples_is_refused_before_writing(tmp_path):
    t = np.arange(0.0, 9.0, 0.5)
    _write_csv(tmp_path / "log.csv", t, np.zeros((t.size, 3)), np.zeros((t.size, 3)))
    sf = parse_step_file(HEAD + POSITION)
    with pytest.raises(InvalidInputError, match=r"step 0 \(z-up, 1–3 s\) holds 4 samples"):
        recording_from_csv(tmp_path / "log.csv", sf, tmp_path / "log.h5")
    assert not (tmp_path / "log.h5").exists()


def test_a_csv_without_the_accelerometer_is_refused_with_the_columns_named(tmp_path):
    (tmp_path / "g.csv").write_text("time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps\n0,0,0,0\n"
                                    "1,0,0,0\n", encoding="utf-8")
    with pytest.raises(InvalidInputError, match=r"missing \['accel_x_mps2'"):
        recording_from_csv(tmp_path / "g.csv", parse_step_file(HEAD + POSITION),
                           tmp_path / "g.h5")


def test_calibrate_on_a_csv_without_steps_says_what_to_give(tmp_path):
    (tmp_path / "d.csv").write_text("time_s,gyro_x_rps\n0,0\n", encoding="utf-8")
    done = CliRunner().invoke(app, ["calibrate", str(tmp_path / "d.csv")])
    assert done.exit_code == 2
    text = " ".join(done.output.split())
    assert "needs --steps" in text and "--step-file" in text


def test_segments_writes_a_skeleton_that_names_every_interval(tmp_path):
    fs = 100.0
    t = np.arange(0.0, 30.0, 1.0 / fs)
    rng = np.random.default_rng(1)
    gyro = rng.normal(0.0, 1e-3, (t.size, 3))
    gyro[(t >= 10.0) & (t < 20.0), 2] += math.radians(30.0)
    accel = np.tile([0.0, 0.0, 9.8], (t.size, 1)) + rng.normal(0.0, 1e-3, (t.size, 3))
    _write_csv(tmp_path / "log.csv", t, gyro, accel)
    done = CliRunner().invoke(app, ["segments", str(tmp_path / "log.csv"), "--step-file",
                                    str(tmp_path / "skel.toml")])
    assert done.exit_code == 0, done.output
    text = (tmp_path / "skel.toml").read_text(encoding="utf-8")
    assert text.count("[[steps]]") == 3
    assert "# interval 1: rotating" in text
    with pytest.raises(InvalidInputError, match="every step's role is 'skip'"):
        parse_step_file(text)


def test_step_file_model_refuses_a_bool_axis():
    with pytest.raises(InvalidInputError, match="axis"):
        parse_step_file(HEAD + RATE.replace('axis = "pitch"', "axis = true"))
    assert StepFile.model_fields["version"].default == 1
