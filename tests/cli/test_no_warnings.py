"""No Python warning reaches a CLI user (docs/field.md): `imucalib calibrate field` and `apply`
run under `python -W error` (every warning an exception, so one would end in an error line) on
each kind of twin session and in the layouts users have: a gentle session in imucal's CSV, a
harsh one in signed 16-bit counts with a preamble, a harsh tactical one in imu_tk's two files,
and one whose rotations are all unusable (a partial result)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from imucalib.sim import handheld_session, harsh_handheld_session, write_session_csv

CASES = {
    "gentle-imucal": (lambda: handheld_session("consumer", seed=31, noise="white"),
                      {"layout": "imucal"}, 0),
    "harsh-counts": (lambda: harsh_handheld_session("consumer", seed=2),
                     {"layout": "counts", "signed": True}, 0),
    "harsh-imu_tk": (lambda: harsh_handheld_session("tactical", seed=3),
                     {"layout": "imu_tk"}, 0),
    "partial": (lambda: handheld_session("consumer", seed=5, noise="white",
                                         gyro_range_dps=20.0), {"layout": "counts"}, 3),
}


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-W", "error", "-m", "imucalib", *args],
                          capture_output=True, text=True, timeout=300, check=False)


@pytest.mark.parametrize("kind", sorted(CASES))
def test_calibrate_and_apply_print_no_warning_under_w_error(kind: str, tmp_path: Path):
    make, layout, code = CASES[kind]
    written = write_session_csv(make(), tmp_path / "log.txt", **layout)
    out = tmp_path / "out"
    res = _cli("calibrate", "field", str(written.path), *written.cli_args, "--latitude", "45",
               "-o", str(out), "--no-record", "--quiet")
    text = res.stdout + res.stderr
    assert res.returncode == code, text
    for bad in ("Warning", "warning:", "internal error", "Traceback"):
        assert bad not in text, text
    if kind not in ("harsh-counts", "partial"):
        return  # apply's own path is the same for every layout: two cases suffice
    (result,) = out.glob("*.result.json")
    res = _cli("apply", str(result), str(written.path), *written.cli_args, "-o",
               str(tmp_path / "corrected.csv"))
    assert res.returncode == 0, res.stdout + res.stderr
    assert "Warning" not in res.stdout + res.stderr


def test_a_library_warning_is_one_note_line(monkeypatch, capsys):
    import warnings

    import imucalib.cli as cli

    def warn_then_finish() -> None:
        warnings.warn("a library said something", RuntimeWarning, stacklevel=1)

    monkeypatch.setattr(cli, "app", warn_then_finish)
    monkeypatch.setattr(warnings, "showwarning", warnings.showwarning)
    monkeypatch.setattr(sys, "unraisablehook", sys.unraisablehook)
    monkeypatch.setattr(sys, "excepthook", sys.excepthook)
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        with pytest.raises(SystemExit) as done:
            cli.main()
    assert done.value.code == 0
    err = capsys.readouterr().err
    assert err.strip() == "note: a library said something"


def test_debug_shows_the_traceback_of_an_internal_error(monkeypatch):
    import imucalib.cli as cli

    def broken() -> None:
        raise RuntimeError("a bug")

    monkeypatch.setattr(cli, "app", broken)
    monkeypatch.setenv("IMUCALIB_DEBUG", "1")
    monkeypatch.setattr(sys, "excepthook", sys.excepthook)
    monkeypatch.setattr(sys, "unraisablehook", sys.unraisablehook)
    import warnings

    monkeypatch.setattr(warnings, "showwarning", warnings.showwarning)
    with pytest.raises(RuntimeError, match="a bug"):
        cli.main()
    assert sys.excepthook is sys.__excepthook__  # Python prints it, not the quiet hook


def test_a_rotation_of_180_degrees_raises_no_warning():
    """A gravity-referenced rotation of 180° has opposite up directions: no turn axis, and no
    division by zero for it (it gave `RuntimeWarning: invalid value encountered in divide`)."""
    import warnings

    from imucalib.procedures.common.static_intervals import FieldLog
    from imucalib.procedures.field.analysis import FieldOptions, analyze_field

    s = harsh_handheld_session("consumer", seed=11)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = analyze_field(FieldLog("IMU", "twin", s.time_s, s.gyro_rps, s.accel_mps2),
                          FieldOptions(latitude_deg=45.0))
    assert r.result.has_triad("gyro")
