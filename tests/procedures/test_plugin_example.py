"""A procedure from outside imucalib: the example plug-in, installed, through the whole CLI.

``examples/imucalib-scale-factor`` is installed as a distribution into a folder outside
``src/imucalib`` and put on ``PYTHONPATH`` of the ``imucalib`` console script, which finds it
only through its entry point (group ``imucalib.procedures``; docs/plugins.md): plan new → run on
the twin → calibrate → the report JSON, the parameters CSV, the report PDF and the records.

The distribution is built by pip offline (``--no-build-isolation --no-index``) when the venv's
setuptools can build a wheel by itself (≥ 70.1, or with the ``wheel`` package); otherwise (the
setuptools 65 a Python 3.11 venv starts with) its ``.dist-info`` is written by hand from the
example's ``pyproject.toml`` — what an installer writes that ``importlib.metadata`` reads.
"""

from __future__ import annotations

import csv
import importlib.metadata
import json
import os
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from imucalib.io.opening import open_recording

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "imucalib-scale-factor"
UNIT = "IMU-0001"


def _version(distribution: str) -> tuple[int, int] | None:
    """Return (major, minor) of an installed distribution, or None."""
    try:
        text = importlib.metadata.version(distribution)
    except importlib.metadata.PackageNotFoundError:
        return None
    major, minor = (int(p) for p in [*re.findall(r"\d+", text), "0"][:2])
    return major, minor


def _can_build_wheels() -> bool:
    """Whether setuptools in this environment builds a wheel without fetching anything.

    ``bdist_wheel`` is part of setuptools from 70.1; before, it came from the ``wheel`` package,
    whose own command was removed in 0.46.
    """
    setuptools, wheel = _version("setuptools"), _version("wheel")
    if setuptools is None:
        return False
    return setuptools >= (70, 1) or (wheel is not None and wheel < (0, 46))


def _install_by_hand(source: Path, target: Path) -> None:
    """Install `source` into `target` as an installer would: the package and its .dist-info."""
    project = tomllib.loads((source / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    name, version = project["name"], project["version"]
    where = source / "src"
    for package in (p for p in where.iterdir() if (p / "__init__.py").is_file()):
        shutil.copytree(package, target / package.name,
                        ignore=shutil.ignore_patterns("__pycache__"))
    info = target / f"{re.sub(r'[-_.]+', '_', name)}-{version}.dist-info"
    info.mkdir()
    requires = "".join(f"Requires-Dist: {r}\n" for r in project.get("dependencies", ()))
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n"
                                   f"{requires}", encoding="utf-8")
    lines = [f"[{group}]\n" + "".join(f"{k} = {v}\n" for k, v in eps.items())
             for group, eps in project.get("entry-points", {}).items()]
    (info / "entry_points.txt").write_text("\n".join(lines), encoding="utf-8")
    (info / "INSTALLER").write_text("tests/procedures/test_plugin_example.py\n",
                                    encoding="utf-8")
    (info / "RECORD").write_text("", encoding="utf-8")


@pytest.fixture(scope="module")
def plugin_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The example installed into a folder of its own (module docstring)."""
    root = tmp_path_factory.mktemp("plugin")
    source = root / "source"  # a copy: a build writes build/ and *.egg-info beside the sources
    shutil.copytree(EXAMPLE, source, ignore=shutil.ignore_patterns(
        "__pycache__", "build", "*.egg-info", "tests"))
    target = root / "site"
    if _can_build_wheels():
        done = subprocess.run(
            [sys.executable, "-m", "pip", "install", "--no-deps", "--no-build-isolation",
             "--no-index", "--quiet", "--target", str(target), str(source)],
            capture_output=True, text=True, timeout=300,
            env={**os.environ, "PIP_DISABLE_PIP_VERSION_CHECK": "1", "PIP_NO_INPUT": "1"})
        assert done.returncode == 0, done.stdout + done.stderr
    else:
        target.mkdir()
        _install_by_hand(source, target)
    assert (target / "imucalib_scale_factor" / "procedure.py").is_file()
    assert [p.name for p in target.glob("imucalib_scale_factor-*.dist-info")]
    return target


def _imucalib(plugin: Path, db: Path, cwd: Path, *args: str) -> str:
    """Run the venv's ``imucalib`` console script with the plug-in on its path; return stdout."""
    script = Path(sys.executable).with_name("imucalib")
    command = [str(script)] if script.is_file() else [sys.executable, "-m", "imucalib"]
    env = {**os.environ, "PYTHONPATH": str(plugin), "IMUCALIB_DB": str(db), "COLUMNS": "200",
           "NO_COLOR": "1", "TERM": "dumb"}
    done = subprocess.run([*command, *args], capture_output=True, text=True, cwd=cwd, env=env,
                          timeout=300)
    assert done.returncode == 0, f"imucalib {' '.join(args)}:\n{done.stdout}\n{done.stderr}"
    return done.stdout


def test_the_plugin_runs_through_plan_run_calibrate_and_records(plugin_path: Path,
                                                               tmp_path: Path) -> None:
    db = tmp_path / "records.db"

    def cli(*args: str) -> str:
        return _imucalib(plugin_path, db, tmp_path, *args)

    listing = " ".join(cli("plan", "new", "--help").split())
    # the procedure's name with its description (PROCEDURE.description), after the built-ins
    assert re.search(r"scale-factor one-axis gyro scale factor \(plug-in example\): turns "
                     r"about the unit's z axis", listing), listing
    assert listing.index("field") < listing.index("scale-factor")  # after the built-ins

    cli("plan", "new", "scale-factor", "--out", "p.toml", "--rates", "30,60,90",
        "--sample-rate-hz", "50", "--settle-s", "2")
    cli("run", "p.toml", "--station", "sim", "--out", "r.h5", "--yes")
    cli("calibrate", "r.h5", "--out", "out")

    stem = tmp_path / "out" / f"r.{UNIT}.scale-factor"
    report = json.loads(Path(f"{stem}.report.json").read_text(encoding="utf-8"))
    assert report["procedure"] == "scale-factor" and report["unit"] == UNIT
    with open_recording(tmp_path / "r.h5") as rec:
        m_zz = float(rec.truth["imu_models"][UNIT]["gyro"]["scale_misalignment"][2][2])
    k1_true = 1.0 + m_zz  # the twin's z gyro scale: output = (1 + M_zz)·ω_z + …
    assert abs(report["k1"] - k1_true) < 4.0 * report["k1_std"], (report["k1"], k1_true)
    assert 0.0 < report["k1_std"] < 1e-4 and report["dof"] == 4

    with open(f"{stem}.parameters.csv", encoding="utf-8", newline="") as fh:
        rows = {r["parameter"]: r for r in csv.DictReader(fh)}
    assert set(rows) == {"gyro_K1_z", "gyro_bias_z"}
    assert float(rows["gyro_K1_z"]["value"]) == report["k1"]
    assert float(rows["gyro_bias_z"]["std_uncertainty"]) == report["bias_std_rps"]
    assert rows["gyro_bias_z"]["unit"] == "rad/s"

    pdf = Path(f"{stem}.report.pdf")
    assert pdf.read_bytes()[:4] == b"%PDF"

    units = json.loads(cli("records", "list", "--json"))
    assert [u["serial"] for u in units] == [UNIT]
    history = json.loads(cli("records", "history", UNIT, "--json"))
    assert [h["procedure"] for h in history] == ["scale-factor"]
    assert {p["name"] for p in history[0]["parameters"]} == {"gyro_K1_z", "gyro_bias_z"}
