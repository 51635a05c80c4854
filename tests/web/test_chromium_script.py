"""scripts/chromium.sh prints the browser the tests use (installing Debian's when missing)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "chromium.sh"


def test_a_named_browser_is_printed_as_it_is():
    env = {**os.environ, "IMUCALIB_TEST_CHROMIUM": sys.executable}
    out = subprocess.run([str(SCRIPT)], capture_output=True, text=True, env=env, check=True,
                         timeout=60)
    assert out.stdout.strip() == sys.executable
