"""Progress bars go to a terminal's stderr only: without one, commands print none."""

from __future__ import annotations

import re

from typer.testing import CliRunner

from imucalib.cli import app

runner = CliRunner()

#: An escape sequence of a terminal (colour, cursor movement): progress bars draw with them.
ANSI = re.compile(r"\x1b\[")

SCENARIO = """name = "progress-test"
seed = 3
[table]
kind = "single-axis"
[[imus]]
name = "IMU-7"
grade = "consumer"
sample_rate_hz = 100
[[steps]]
kind = "position"
angles_deg = [90]
settle_s = 1
record_s = 2
"""


def test_commands_print_no_progress_escape_codes_without_a_terminal(tmp_path):
    scenario = tmp_path / "s.toml"
    scenario.write_text(SCENARIO, encoding="utf-8")
    h5 = tmp_path / "s.h5"
    calls = [
        ["simulate", str(scenario), "--out", str(h5)],
        ["export", str(h5), "--stream", "imu/IMU-7", "--out", str(tmp_path / "s.csv")],
        ["inspect", str(h5)],
    ]
    for argv in calls:
        result = runner.invoke(app, argv)
        assert result.exit_code == 0, (argv, result.output)
        assert not ANSI.search(result.output), (argv, result.output)
        if argv[0] != "inspect":  # its tables draw with the same line characters
            assert "━" not in result.output, (argv, result.output)  # a progress bar


def test_quiet_is_accepted(tmp_path):
    scenario = tmp_path / "s.toml"
    scenario.write_text(SCENARIO, encoding="utf-8")
    result = runner.invoke(app, ["simulate", str(scenario), "--out", str(tmp_path / "q.h5"),
                                 "--quiet"])
    assert result.exit_code == 0, result.output
