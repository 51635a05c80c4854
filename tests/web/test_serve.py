"""``imucalib serve``: loopback by default; another host needs TLS or --insecure-http."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from imucalib.cli import serve as serve_module
from imucalib.cli._app import app
from imucalib.errors import InvalidInputError


@pytest.mark.parametrize("host", ["127.0.0.1", "localhost", "::1", "127.0.0.2", "[::1]"])
def test_loopback_needs_nothing(host):
    assert serve_module.check_bind(host, None, None, False) == ""


@pytest.mark.parametrize("host", ["0.0.0.0", "192.168.1.20", "::", "station.lab"])
def test_another_host_without_tls_is_refused(host):
    with pytest.raises(InvalidInputError, match="needs TLS"):
        serve_module.check_bind(host, None, None, False)
    warning = serve_module.check_bind(host, None, None, True)
    assert warning.startswith("warning:") and "\n" not in warning


def test_tls_needs_both_files_that_exist(tmp_path):
    cert, key = tmp_path / "cert.pem", tmp_path / "key.pem"
    with pytest.raises(InvalidInputError, match="both --certfile and --keyfile"):
        serve_module.check_bind("0.0.0.0", cert, None, False)
    with pytest.raises(InvalidInputError, match="is not a file"):
        serve_module.check_bind("0.0.0.0", cert, key, False)
    cert.write_text("x")
    key.write_text("x")
    assert serve_module.check_bind("0.0.0.0", cert, key, False) == ""


def test_the_command_refuses_in_one_line(tmp_path, monkeypatch):
    monkeypatch.setenv("IMUCALIB_DB", str(tmp_path / "r.db"))
    result = CliRunner().invoke(app, ["serve", "--host", "0.0.0.0", "--runs-dir",
                                      str(tmp_path / "runs")])
    assert result.exit_code == 2
    lines = [ln for ln in result.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "needs TLS" in lines[0] and "Traceback" not in result.output


def test_a_port_in_use_is_one_line(tmp_path):
    import socket

    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        result = CliRunner().invoke(app, ["serve", "--port", str(port), "--db",
                                          str(tmp_path / "r.db")])
    assert result.exit_code == 2 and f"cannot listen on 127.0.0.1:{port}" in result.output


def test_serve_imports_no_server_until_it_runs():
    code = ("import sys, imucalib.cli.serve; "
            "print(any(m.split('.')[0] in ('fastapi', 'uvicorn', 'starlette') "
            "for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=Path(__file__).parent)
    assert out.stdout.strip() == "False"


def test_the_abort_bound_reaches_the_supervisor(tmp_path):
    """``serve --abort-escalate-s`` → create_app → the supervisor the server makes."""
    from imucalib.web.abort_watch import ABORT_ESCALATE_S
    from imucalib.web.app import create_app

    for given, expected in ((None, ABORT_ESCALATE_S), (3.5, 3.5)):
        web = create_app(f"sqlite:///{tmp_path / 'r.db'}", tmp_path / f"runs-{given}",
                         abort_escalate_s=given).state.web
        try:
            assert web.runs().abort_escalate_s == expected
        finally:
            web.close()
    refused = CliRunner().invoke(app, ["serve", "--abort-escalate-s", "0", "--db",
                                       str(tmp_path / "r.db")])
    assert refused.exit_code == 2 and "--abort-escalate-s" in refused.output
    assert "Traceback" not in refused.output
