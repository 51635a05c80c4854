"""Run `imucalib inspect` and `imucalib export` on many files in one process (not a test module).

Usage: python _open_many.py WORKDIR FILE...
Prints one JSON line per command: {"args", "code", "out", "err"}. Each command runs under a
20-second alarm: a command that hangs kills this process with SIGALRM, which the test reports.
"""

from __future__ import annotations

import contextlib
import io
import json
import signal
import sys
from pathlib import Path

from imucalib.cli import main


def run(args: list[str]) -> dict[str, object]:
    out, err = io.StringIO(), io.StringIO()
    sys.argv = ["imucalib", *args]
    signal.alarm(20)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                main()
                code = 0
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 1
    finally:
        signal.alarm(0)
    return {"args": args, "code": code, "out": out.getvalue(), "err": err.getvalue()}


def main_many() -> None:
    work = Path(sys.argv[1])
    for name in sys.argv[2:]:
        print(json.dumps(run(["inspect", name])), flush=True)
        csv = work / (Path(name).stem + ".csv")
        print(json.dumps(run(["export", name, "--stream", "imu/IMU-0001", "--out", str(csv)])),
              flush=True)


if __name__ == "__main__":
    main_many()
