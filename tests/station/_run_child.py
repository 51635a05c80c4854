"""Run a plan on the twin in a child process that the durability tests kill (not a test module).

Usage: python _run_child.py PLAN.toml OUT.h5 MODE [ARG]
  MODE "done K"     SIGKILL itself right after the K-th step was marked done (and flushed);
                    when OUT.h5 exists, resume it and count the steps this session does
  MODE "close"      SIGKILL itself when the writer starts its final close
  MODE "fsize N T [M]"  at station time T [s] limit the file to N bytes more than it holds
                    (N < 0: fewer), with min_free_bytes M; the run goes on
  MODE "stall"      run, then wait (for the test's SIGKILL) when the writer starts its final close
  MODE "none"       run to the end
The exit code is the CLI's convention: 0 done, 1 aborted, 2 an imucalib error (printed).
"""

from __future__ import annotations

import os
import resource
import signal
import sys
import time

from imucalib.cli import _exit, _printed_error, _unraisable
from imucalib.errors import CalibrationError
from imucalib.io.recording import RecordingWriter
from imucalib.plan import load_plan
from imucalib.station.runner import RunOptions, resume_run, run_plan
from imucalib.station.sim import SimStation


def main() -> None:
    sys.unraisablehook, sys.excepthook = _unraisable, _printed_error  # as the CLI's main()
    plan = load_plan(sys.argv[1])
    out, mode = sys.argv[2], sys.argv[3:]
    station = SimStation(plan.twin)
    options = RunOptions(truth=station.truth, tick_s=2.0)
    if mode[0] == "done":
        k = int(mode[1])

        def on_status(status):  # called after every tick and after every step
            if status.steps_done >= k:
                os.kill(os.getpid(), signal.SIGKILL)

        options.on_status = on_status
    elif mode[0] in ("close", "stall"):
        original = RecordingWriter.close

        def close(self):
            if mode[0] == "stall":
                while True:
                    time.sleep(1.0)
            os.kill(os.getpid(), signal.SIGKILL)
            original(self)

        RecordingWriter.close = close
    elif mode[0] == "fsize":
        extra, at_s = int(mode[1]), float(mode[2])
        options.min_free_bytes = int(mode[3]) if len(mode) > 3 else options.min_free_bytes

        def lower() -> None:
            size = os.path.getsize(out)
            resource.setrlimit(resource.RLIMIT_FSIZE, (size + extra, resource.RLIM_INFINITY))

        station.at(at_s, lower)
    try:
        if os.path.exists(out):
            summary = resume_run(out, lambda p, t: SimStation(p.twin, start_time_s=t),
                                 options=options)
        else:
            summary = run_plan(plan, station, out, options=options)
    except CalibrationError as exc:
        print(f"error: {exc}", file=sys.stderr)
        _exit(2)
    print(summary.status)
    _exit(0 if summary.status == "done" else 1)


if __name__ == "__main__":
    main()
