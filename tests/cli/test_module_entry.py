"""``python -m imucalib`` is the ``imucalib`` command."""

from __future__ import annotations

import subprocess
import sys


def test_python_dash_m_imucalib_runs_the_command_line():
    done = subprocess.run([sys.executable, "-m", "imucalib", "scenarios"], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "dual-axis-p1" in done.stdout


def test_python_dash_m_imucalib_reports_errors_with_the_cli_exit_code():
    done = subprocess.run([sys.executable, "-m", "imucalib", "inspect", "/nonexistent/x.h5"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr.startswith("error: ")
    assert "Traceback" not in done.stderr
