"""A uvicorn server on 127.0.0.1 (a free port) in a thread, and Debian's chromium to drive it.

Import it by its path. :func:`chromium_path` fails the test (never skips it) when no chromium
is there: ``scripts/chromium.sh`` installs it, ``.ci/run`` exports its path as
``IMUCALIB_TEST_CHROMIUM``.
"""

from __future__ import annotations

import os
import socket
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

CHROMIUM_ENV = "IMUCALIB_TEST_CHROMIUM"
#: Chromium's switches for a headless run that reaches nothing but the test's server.
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync"]
REPO = Path(__file__).resolve().parents[2]


def chromium_path() -> str:
    """Return chromium's path, or fail the test with one line saying how to get it."""
    for candidate in (os.environ.get(CHROMIUM_ENV, ""), "/usr/bin/chromium",
                      "/usr/bin/chromium-browser"):
        if candidate and os.access(candidate, os.X_OK):
            return candidate
    pytest.fail(f"the browser tests need chromium: none at ${CHROMIUM_ENV}, /usr/bin/chromium "
                "or /usr/bin/chromium-browser (run scripts/chromium.sh)", pytrace=False)


def screenshot_dir(test_name: str) -> Path:
    """Return the folder of a test's screenshots: ``out/web/<test>`` (``out/`` is ignored)."""
    folder = REPO / "out" / "web" / test_name
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@contextmanager
def live_server(app: Any, *, lifespan: bool = False) -> Iterator[str]:
    """Serve `app` on 127.0.0.1 in a thread; yield its base URL; stop it afterwards.

    With `lifespan` the app's lifespan runs (the calibrate watcher, docs/web.md).
    """
    import uvicorn

    config = uvicorn.Config(app, host="127.0.0.1", port=_free_port(), ws="websockets-sansio",
                            log_level="warning", access_log=False,
                            lifespan="on" if lifespan else "off")
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, name="uvicorn", daemon=True)
    thread.start()
    deadline = time.monotonic() + 20
    while not server.started:
        if not thread.is_alive() or time.monotonic() > deadline:
            pytest.fail("the test's uvicorn server did not start on 127.0.0.1", pytrace=False)
        time.sleep(0.02)
    try:
        yield f"http://127.0.0.1:{config.port}"
    finally:
        server.should_exit = True
        thread.join(timeout=30)
