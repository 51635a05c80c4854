"""Kill campaign: SIGKILL `imucalib run` the moment a step reads ``done``, then check the file.

Runs the default P1 plan at 200 Hz on the twin (as a user would, through the CLI), watches the
Recording from another process (SWMR) and kills the runner as soon as plan step ``--step``
(default 9, the 60-minute level static record) reads ``done``. Each try then checks that every
``done`` step holds its valid window's samples (``uncovered_done_steps``), and every
``--resume-every``-th try resumes the run to the end and checks the finished file the same way.
Prints one line per try and a summary; the figures go in docs/reliability.md.

    .venv/bin/python bench/reliability_campaign.py --tries 20
"""

from __future__ import annotations

import argparse
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from imucalib.errors import RecordingError
from imucalib.io import open_recording
from imucalib.io.coverage import uncovered_done_steps

CLI = [sys.executable, "-m", "imucalib.cli"]


def one_try(plan: Path, out: Path, step: int, timeout_s: float) -> tuple[Path, int, int, float]:
    """Run, kill at the step's done; return the file, done steps, short steps, samples kept."""
    proc = subprocess.Popen([*CLI, "run", str(plan), "--station", "sim", "--yes", "--no-live",
                             "--out", str(out)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + timeout_s
    path = None
    try:
        while time.monotonic() < deadline and proc.poll() is None:
            files = list(out.glob("*.h5"))
            if files:
                path = files[0]
                try:
                    with open_recording(path) as rec:
                        if any(s.status == "done" and s.commanded.get("plan_step") == step
                               for s in rec.steps):
                            break
                except RecordingError:
                    pass
            time.sleep(0.005)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    assert path is not None, "no recording appeared"
    with open_recording(path) as rec:
        done = [s for s in rec.steps if s.status == "done"]
        short = uncovered_done_steps(rec)
        target = [s for s in done if s.commanded.get("plan_step") == step]
        kept = 0.0
        if target:
            s = target[-1]
            n = len(rec.read_step(s.index, "imu", "IMU-0001", ["gyro_x_rps"]))
            kept = n / (200.0 * (s.valid_end_s - s.valid_start_s))
    return path, len(done), len(short), kept


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tries", type=int, default=20)
    parser.add_argument("--step", type=int, default=9)
    parser.add_argument("--resume-every", type=int, default=5)
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="imucalib-kills-"))
    plan = work / "p1.toml"
    subprocess.run([*CLI, "plan", "new", "p1", "--out", str(plan), "--sample-rate-hz", "200"],
                   check=True, capture_output=True)
    n_short = n_resumed = n_resume_ok = 0
    t0 = time.monotonic()
    for i in range(args.tries):
        out = work / f"try{i:02d}"
        path, n_done, n_bad, kept = one_try(plan, out, args.step, 300.0)
        n_short += n_bad > 0
        line = (f"try {i + 1:2d}: {n_done:3d} step(s) done at the kill, {n_bad} short of their "
                f"samples; step {args.step} holds {kept:.4%} of its window's samples")
        if args.resume_every and (i + 1) % args.resume_every == 0:
            n_resumed += 1
            r = subprocess.run([*CLI, "run", "--resume", str(path), "--yes", "--no-live"],
                               capture_output=True, text=True)
            with open_recording(path) as rec:
                ok = (r.returncode == 0 and not uncovered_done_steps(rec)
                      and not rec.was_open_for_write)
            n_resume_ok += ok
            line += f"; resumed: exit {r.returncode}, {'complete' if ok else 'NOT complete'}"
        print(line, flush=True)
        shutil.rmtree(out)
    print(f"{args.tries} kills at the moment step {args.step} read done: {n_short} left a done "
          f"step short of its samples; {n_resume_ok}/{n_resumed} resumes completed with every "
          f"done step covered ({time.monotonic() - t0:.0f} s)")
    shutil.rmtree(work)


if __name__ == "__main__":
    main()
