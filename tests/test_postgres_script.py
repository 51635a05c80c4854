"""scripts/postgres.sh: the throw-away PostgreSQL server of the records tests (README.md).

The start/connect/stop cycle runs where a server is known to be startable: when
``IMUCALIB_TEST_PG_URL`` is set (``.ci/run`` sets it after the script itself started the suite's
server, so a broken script has already failed CI). Elsewhere it is not collected, so that a
developer's ``make test`` never installs Debian packages; the argument checks run everywhere,
and shellcheck runs where it is installed.
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import tempfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "scripts" / "postgres.sh"


def _run(*args: str, timeout_s: float = 300.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(SCRIPT), *args], capture_output=True, text=True,
                          timeout=timeout_s, stdin=subprocess.DEVNULL)


def test_the_script_is_executable_and_checks_its_arguments():
    assert os.access(SCRIPT, os.X_OK)
    for argv in ((), ("start",), ("restart", "x"), ("stop", "a", "b")):
        done = _run(*argv)
        assert done.returncode == 2, (argv, done.stderr)
        assert "usage:" in done.stderr


def test_stop_without_a_server_is_a_no_op(tmp_path):
    done = _run("stop", str(tmp_path / "never-started"))
    assert done.returncode == 0, done.stderr
    assert not (tmp_path / "never-started").exists()


def _select_1(url: str) -> int:
    import psycopg

    with psycopg.connect(url.replace("postgresql+psycopg://", "postgresql://"),
                         connect_timeout=10) as conn:
        row = conn.execute("SELECT 1").fetchone()
    assert row is not None
    return int(row[0])


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


if os.environ.get("IMUCALIB_TEST_PG_URL"):

    def test_start_connect_stop_and_start_again_on_another_port():
        # Not pytest's tmp_path: when run as root the server's user must enter the folder's
        # parents, and pytest's base folder is private to root.
        work = Path(tempfile.mkdtemp(prefix="imucalib-pg-test-"))
        try:
            done = _run("start", str(work))
            assert done.returncode == 0, done.stderr
            url = done.stdout.strip()
            assert url.startswith("postgresql+psycopg://") and "@127.0.0.1:" in url
            assert (work / "url").read_text().strip() == url
            assert _select_1(url) == 1

            again = _run("start", str(work))  # already running: the same URL
            assert again.returncode == 0 and again.stdout.strip() == url, again.stderr

            assert _run("stop", str(work)).returncode == 0
            assert _run("stop", str(work)).returncode == 0  # idempotent
            with pytest.raises(Exception, match=r"(?i)connect|refused"):
                _select_1(url)

            port = _free_port()
            done = _run("start", str(work), str(port))
            assert done.returncode == 0, done.stderr
            assert done.stdout.strip().endswith(f"@127.0.0.1:{port}/postgres")
            assert _select_1(done.stdout.strip()) == 1
        finally:
            _run("stop", str(work))
            shutil.rmtree(work, ignore_errors=True)


if shutil.which("shellcheck"):

    def test_the_scripts_are_shellcheck_clean():
        done = subprocess.run(["shellcheck", str(SCRIPT), str(ROOT / ".ci" / "run")],
                              capture_output=True, text=True, timeout=60)
        assert done.returncode == 0, done.stdout
