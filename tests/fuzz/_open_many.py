"""Run imucalib commands on many recordings in one process (not a test module).

Usage: python _open_many.py WORKDIR FILE... [--commands inspect,export,recover]

For each FILE, runs each command (default ``inspect`` and ``export``; ``recover`` writes the
copy into WORKDIR) and prints one JSON line per command: {"args", "code", "out", "err"}. Each
command runs under a 20-second alarm (``IMUCALIB_FUZZ_CHILD_TIMEOUT_S``): a command that hangs
kills this process with SIGALRM, which the parent reports as a hang; any other death by a
signal (SIGSEGV inside HDF5) is reported as such. The CLI's final :func:`os._exit` (taken after
HDF5 failed to write a file) is replaced by a plain exit so that one case cannot end the others.
``IMUCALIB_FUZZ_PROBE_TIMEOUT_S`` shortens the time the reader's probe gives HDF5 to read a
file's metadata (:data:`imucalib.io._probe.PROBE_TIMEOUT_S`, 10 s), which a damaged file can
make HDF5 loop on: the probe's refusal is the same, sooner.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import signal
import sys
from pathlib import Path

import imucalib.cli
from imucalib.cli import main

TIMEOUT_S = int(os.environ.get("IMUCALIB_FUZZ_CHILD_TIMEOUT_S", "20"))


def _plain_exit(code: int) -> None:
    raise SystemExit(code)


def run(args: list[str]) -> dict[str, object]:
    out, err = io.StringIO(), io.StringIO()
    sys.argv = ["imucalib", *args]
    signal.alarm(TIMEOUT_S)
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


def commands(name: str, work: Path, which: list[str]) -> list[list[str]]:
    """The command lines to run on the file `name`."""
    stem = Path(name).stem
    table = {"inspect": ["inspect", name],
             "export": ["export", name, "--stream", "imu/IMU-0001", "--out",
                        str(work / f"{stem}.csv")],
             "recover": ["recover", name, "--out", str(work / f"{stem}.recovered.h5")]}
    return [table[c] for c in which]


def main_many() -> None:
    probe = os.environ.get("IMUCALIB_FUZZ_PROBE_TIMEOUT_S")
    if probe:
        from imucalib.io import _probe

        _probe.PROBE_TIMEOUT_S = float(probe)
    if hasattr(imucalib.cli, "_exit"):
        imucalib.cli._exit = _plain_exit  # type: ignore[attr-defined]
    args = sys.argv[1:]
    which = ["inspect", "export"]
    if "--commands" in args:
        i = args.index("--commands")
        which = args[i + 1].split(",")
        del args[i:i + 2]
    work = Path(args[0])
    for name in args[1:]:
        for line in commands(name, work, which):
            print(json.dumps(run(line)), flush=True)


if __name__ == "__main__":
    main_many()
