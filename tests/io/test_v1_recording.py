"""A format-v1 Recording from before v2 (tests/data/p1_v1.h5) still reads and calibrates.

Version 1 ``/steps`` had no role, tags or units: the reader takes the tags from each step's
``commanded`` state (or the stored plan) and the role from the tags, as the P1 generator now
sets it. P1 then calibrates the file to the very numbers it gave before v2
(tests/data/p1_v1_estimates.json).
"""

from __future__ import annotations

import importlib.util
import json
import shutil
from collections import Counter
from pathlib import Path

import h5py
import numpy as np
import pytest
from rich.console import Console

from imucalib.io import open_recording
from imucalib.io.inspect import summarize_recording
from imucalib.io.recover import recover_recording
from imucalib.plan import parse_plan
from imucalib.procedures.p1.analysis import P1Options, analyze_p1
from imucalib.procedures.p1.roles import ROLES as P1_ROLES

DATA = Path(__file__).parents[1] / "data"
V1_FILE = DATA / "p1_v1.h5"
#: The model the pinned values were computed with, before the data chose the accelerometer's
#: K2 (docs/p1.md, "Model terms"): what these tests hold is the v1 reader, not the choice.
FAST = P1Options(hash_recording=False, terms="-k2")


def _generator():
    """tests/data/make_v1_recording.py (not a package): its plan, generated with today's code."""
    spec = importlib.util.spec_from_file_location("make_v1_recording",
                                                  DATA / "make_v1_recording.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def before() -> dict:
    return json.loads((DATA / "p1_v1_estimates.json").read_text())


@pytest.fixture
def v1_copy(tmp_path) -> Path:
    path = tmp_path / "v1.h5"
    shutil.copyfile(V1_FILE, path)
    return path


def _rewrite_commanded(path: Path, change) -> None:
    """Replace every step's commanded JSON by change(dict) (the v1 layout stays)."""
    with h5py.File(path, "r+") as f:
        ds = f["steps/commanded"]
        for i in range(ds.shape[0]):
            cmd = json.loads(ds[i].decode()) if ds[i] else None
            if isinstance(cmd, dict):
                ds[i] = json.dumps(change(cmd)).encode()


def test_the_file_is_small_and_version_1():
    assert V1_FILE.stat().st_size < 1_000_000
    with h5py.File(V1_FILE, "r") as f:
        assert int(f.attrs["format_version"]) == 1
        assert "role" not in f["steps"] and "tags" not in f["steps"]


def test_v1_steps_get_the_roles_and_tags_the_generator_now_sets():
    plan = _generator().tiny_p1_plan()  # the same plan, as today's generator writes it
    with open_recording(V1_FILE) as rec:
        assert rec.format_version == 1
        steps = rec.steps
        stored = parse_plan(rec.metadata["plan_toml"])
    assert len(steps) == len(plan.steps) == 29
    for step in steps:
        k = step.commanded["plan_step"]
        assert step.tags == plan.steps[k].tags == stored.steps[k].tags
        assert step.role == plan.steps[k].role, step.label
        assert step.units == ()
        assert step.concerns("IMU-0001")
    counts = Counter(s.role for s in steps)
    assert counts == {"": 6, "p1.accel-position": 6, "p1.gyro-bias": 1, "p1.gyro-rate": 9,
                      "p1.held-out-rate": 3, "p1.held-out-position": 4}
    assert set(counts) - {""} == set(P1_ROLES)
    assert steps[2].tag_value("repetition") is None and "rep1" in steps[2].tags


def test_v1_tags_come_from_the_stored_plan_when_commanded_lacks_them(v1_copy):
    with open_recording(V1_FILE) as rec:
        expected = [(s.role, s.tags) for s in rec.steps]
    _rewrite_commanded(v1_copy, lambda c: {"plan_step": c["plan_step"]})
    with open_recording(v1_copy) as rec:
        assert [(s.role, s.tags) for s in rec.steps] == expected
    with h5py.File(v1_copy, "r+") as f:  # neither commanded tags nor a plan: no tags, no role
        del f.attrs["plan_toml"]
    with open_recording(v1_copy) as rec:
        assert all(s.role == "" and s.tags == () for s in rec.steps)


def test_p1_calibrates_the_v1_file_as_before(before):
    analysis = analyze_p1(V1_FILE, options=FAST)
    res = analysis.result
    assert list(res.param_names) == before["param_names"]
    np.testing.assert_allclose(res.values, before["values"], rtol=1e-9, atol=1e-15)
    sigma = np.sqrt(np.diag(res.covariance))
    np.testing.assert_allclose(sigma, before["sigma"], rtol=1e-9)
    checks = {c.name: c.passed for c in analysis.checks}
    assert checks.pop("specification") is None  # the v1 file's plan states no limits
    assert checks == before["checks"]
    windows = [(w.step_index, w.role, w.kind) for w in analysis.observations.windows]
    assert windows == [(w["step_index"], w["role"], w["kind"]) for w in before["windows"]]


def test_p1_calibrates_the_v1_file_without_its_plan(v1_copy, before):
    """The roles and rates come from the steps; limits and Type B from the defaults."""
    with h5py.File(v1_copy, "r+") as f:
        del f.attrs["plan_toml"]
    analysis = analyze_p1(v1_copy, options=FAST)
    assert not analysis.observations.context.has_plan
    np.testing.assert_allclose(analysis.result.values, before["values"], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(np.sqrt(np.diag(analysis.result.covariance)), before["sigma"],
                               rtol=1e-9)
    assert any("holds no plan" in n for n in analysis.result.notes)


def test_p1_takes_axis_and_rate_from_the_table_when_commanded_lacks_them(v1_copy, before):
    _rewrite_commanded(v1_copy, lambda c: {k: v for k, v in c.items()
                                           if k not in ("axis", "rate_dps", "revolutions")})
    analysis = analyze_p1(v1_copy, options=FAST)
    values, sigma = analysis.result.values, np.sqrt(np.diag(analysis.result.covariance))
    np.testing.assert_allclose(values, before["values"], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(sigma, before["sigma"], rtol=1e-9)


def test_recovery_copies_a_v1_file_as_v1(v1_copy, tmp_path):
    out = tmp_path / "copy.h5"
    recover_recording(v1_copy, out)
    with open_recording(V1_FILE) as rec:
        expected = [(s.role, s.tags, s.commanded) for s in rec.steps]
    with open_recording(out) as rec:
        assert rec.format_version == 1
        assert [(s.role, s.tags, s.commanded) for s in rec.steps] == expected


def test_inspect_shows_roles_and_tags():
    console = Console(record=True, width=200)
    summarize_recording(V1_FILE).render(console)
    text = console.export_text()
    assert "format v1" in text
    assert "p1.accel-position" in text and "six-position" in text
