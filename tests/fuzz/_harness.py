"""What every fuzz test of the CLI shares: running a command, judging and tallying its outcome.

Not a test module. Every mutated input must end in exit code 0 (or 1, a decision that failed;
3, ``calibrate``'s partial result) or in exit code 2 with one ``error:`` line: never a
traceback, never the ``internal error`` safety net of :func:`imucalib.cli.main`, never a hang,
never a signal.

- :func:`run_cli` runs :func:`imucalib.cli.main` in this process under a per-case time limit
  (``IMUCALIB_FUZZ_TIMEOUT_S``, default 60 s): a command still running then is stopped by
  SIGALRM and reported as a hang; should the alarm not get through (a loop inside C code),
  :mod:`faulthandler` ends the process at twice the limit, which fails the run just as well.
- :func:`check_outcome` asserts the rules above and, with ``IMUCALIB_FUZZ_TALLY=FILE``, first
  appends the outcome to FILE as one JSON line (``door``, ``code``, ``one_line``, ``error``,
  ``usage``, ``traceback``, ``internal``, ``hang``, ``signal``), which ``tests/fuzz/tally.py``
  counts. A plan's or scenario's refusal is an ``error:`` line followed by one line per
  offending field (``error`` without ``one_line``).
  Exit 2 is either imucalib's one ``error:`` line or, for an option value of the wrong type,
  the command-line parser's ``Usage:`` and ``Error:`` lines (``usage``).
- ``IMUCALIB_FUZZ_EXAMPLES=N`` multiplies every test's example count (:func:`fuzz_settings`);
  hypothesis runs derandomised, so a given N always draws the same cases.
"""

from __future__ import annotations

import contextlib
import faulthandler
import io
import json
import os
import re
import signal
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

import imucalib.cli
from imucalib.cli import main

__all__ = ["ODD_NUMBERS", "SCALE", "TALLY", "TIMEOUT_S", "CaseTimeout", "assert_finite_csv",
           "check_outcome", "damage_bytes", "fuzz_settings", "mutate_lines", "mutate_numbers",
           "run_child", "run_cli", "tally"]

#: The multiplier of every example count (``IMUCALIB_FUZZ_EXAMPLES``; 1 in ``make test``).
SCALE = int(os.environ.get("IMUCALIB_FUZZ_EXAMPLES", "1"))
#: The file each outcome is appended to (``IMUCALIB_FUZZ_TALLY``), or None.
TALLY = os.environ.get("IMUCALIB_FUZZ_TALLY")
#: The per-case time limit [s]; a command that runs longer is a hang.
TIMEOUT_S = float(os.environ.get("IMUCALIB_FUZZ_TIMEOUT_S", "60"))

NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")
ODD_NUMBERS = st.sampled_from(["nan", "inf", "-inf", "1e308", "-1e308", "0", "-1", "1e-320",
                               "\"x\"", "", "9" * 40, "-0.0", "1e9", "true", "1e30", "-1e30"])


def fuzz_settings(examples: int, *, scale: int | None = None) -> Any:
    """Hypothesis settings: `examples` × the scale, derandomised, no deadline.

    `scale` overrides :data:`SCALE` (the costly doors grow more slowly in a campaign).
    """
    return settings(max_examples=max(1, examples * (SCALE if scale is None else scale)),
                    deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture,
                                           HealthCheck.too_slow, HealthCheck.data_too_large])


class CaseTimeout(BaseException):
    """A command ran past :data:`TIMEOUT_S` (a BaseException: the CLI's nets let it through)."""


def _alarm(signum: int, frame: object) -> None:
    raise CaseTimeout


def _plain_exit(code: int) -> None:
    raise SystemExit(code)


def run_cli(*args: str, timeout_s: float | None = None) -> tuple[int, str, str]:
    """Run :func:`imucalib.cli.main` in this process; return exit code, stdout, stderr.

    The exit code is -1 when the command ran past `timeout_s` (default :data:`TIMEOUT_S`).
    The CLI's final :func:`os._exit` (after HDF5 failed to write a file) is a plain exit here,
    so that one case cannot end the test process.
    """
    limit = TIMEOUT_S if timeout_s is None else timeout_s
    out, err = io.StringIO(), io.StringIO()
    argv = sys.argv
    sys.argv = ["imucalib", *args]
    saved_exit = getattr(imucalib.cli, "_exit", None)
    if saved_exit is not None:
        imucalib.cli._exit = _plain_exit  # type: ignore[attr-defined]
    previous = signal.signal(signal.SIGALRM, _alarm)
    faulthandler.dump_traceback_later(2 * limit, exit=True)
    signal.setitimer(signal.ITIMER_REAL, limit)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                main()
                code = 0
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 1
    except CaseTimeout:
        code = -1
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        faulthandler.cancel_dump_traceback_later()
        signal.signal(signal.SIGALRM, previous)
        if saved_exit is not None:
            imucalib.cli._exit = saved_exit  # type: ignore[attr-defined]
        sys.argv = argv
    return code, out.getvalue(), err.getvalue()


CHILD = Path(__file__).with_name("_open_many.py")


def run_child(workdir: Path, files: Sequence[Path], commands: Sequence[str]
              ) -> list[dict[str, Any]]:
    """Run `commands` on each of `files` in one child process (``_open_many.py``).

    Returns the outcomes (``args``, ``code``, ``out``, ``err``) in order. A child that dies
    (SIGALRM: a hang; SIGSEGV …) is tallied and fails the test, naming the case it died on.
    The reader's metadata probe gets 3 s (``IMUCALIB_FUZZ_PROBE_TIMEOUT_S``) instead of 10.
    """
    env = {**os.environ, "IMUCALIB_FUZZ_PROBE_TIMEOUT_S":
           os.environ.get("IMUCALIB_FUZZ_PROBE_TIMEOUT_S", "3")}
    proc = subprocess.run([sys.executable, str(CHILD), str(workdir), *map(str, files),
                           "--commands", ",".join(commands)], env=env,
                          capture_output=True, text=True, timeout=60 + 30 * len(files))
    outcomes = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]
    if proc.returncode != 0:
        k = len(outcomes)
        door = commands[k % len(commands)]
        case = f"{door} {files[k // len(commands)]}" if k < len(files) * len(commands) else "?"
        hang = proc.returncode == -signal.SIGALRM
        for o in outcomes:
            tally(str(o["args"][0]), int(o["code"]), str(o["out"]), str(o["err"]))
        tally(door, -1 if hang else proc.returncode, "", proc.stderr,
              signal_number=-proc.returncode if proc.returncode < 0 else None)
        raise AssertionError(f"the child died ({proc.returncode}{', a hang' if hang else ''}) "
                             f"on {case}:\n{proc.stderr[-3000:]}")
    return outcomes


def tally(door: str, code: int, out: str, err: str, *, signal_number: int | None = None
          ) -> None:
    """Append one outcome to :data:`TALLY` (when set); `code` -1 is a hang."""
    if not TALLY:
        return
    text = out + err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    row = {"door": door, "what": door, "code": code,
           "one_line": code == 2 and len(lines) == 1 and lines[0].startswith("error: "),
           "error": code == 2 and err.startswith("error: "),
           "usage": code == 2 and _usage(err),
           "traceback": "Traceback" in text, "internal": "internal error" in text,
           "hang": code == -1, "signal": signal_number}
    with open(TALLY, "a", encoding="utf-8") as f:
        f.write(json.dumps(row) + "\n")


def check_outcome(code: int, out: str, err: str, what: str, *, door: str | None = None) -> None:
    """Tally the outcome, then assert the rules of the module docstring.

    `what` describes the case (its first word names the door unless `door` is given).
    """
    words = what.split()
    tally(door or (words[0] if words else what), code, out, err)
    text = out + err
    assert code != -1, f"{what}: a hang (still running after {TIMEOUT_S:g} s)\n{text}"
    assert "Traceback" not in text, f"{what}: traceback\n{text}"
    assert "internal error" not in text, f"{what}: an unexpected exception\n{text}"
    assert code in (0, 1, 2, 3), f"{what}: exit {code}\n{text}"
    if code == 2:
        assert err.startswith("error: ") or _usage(err), f"{what}: exit 2 without a message\n{text}"


def _usage(err: str) -> bool:
    """Whether `err` is the command-line parser's refusal of an option (exit 2).

    Typer answers a value of the wrong type (``--skip-rows ''``) before imucalib sees it, with
    its ``Usage:`` line and one ``Error:`` line naming the option and what it expected.
    """
    lines = [ln for ln in err.splitlines() if ln.strip()]
    return bool(lines) and lines[0].startswith("Usage: ") and any(
        ln.startswith("Error: ") for ln in lines)


def assert_finite_csv(path: Path) -> None:
    """No NaN or inf written to the CSV `path`."""
    text = path.read_text(encoding="utf-8").lower()
    assert "nan" not in text and "inf" not in text, f"non-finite numbers written to {path}"


def damage_bytes(original: bytes, i: int, rng: np.random.Generator) -> bytes:
    """Return a damaged copy of a file's bytes, the damage's kind chosen by ``i % 4``.

    Bytes flipped anywhere, a block of the metadata region (the first 16 KiB) zeroed, the file
    truncated, or random bytes in its data region.
    """
    raw = bytearray(original)
    kind = i % 4
    if kind == 0:
        for _ in range(int(rng.integers(1, 8))):
            raw[int(rng.integers(0, len(raw)))] ^= int(rng.integers(1, 256))
    elif kind == 1:
        a = int(rng.integers(0, min(len(raw), 16384) - 64))
        raw[a:a + 64] = bytes(64)
    elif kind == 2:
        raw = raw[:int(rng.integers(0, len(raw)))]
    else:
        a = int(rng.integers(len(raw) // 2, len(raw) - 64))
        raw[a:a + 64] = rng.integers(0, 256, 64, dtype=np.uint8).tobytes()
    return bytes(raw)


def mutate_numbers(text: str, data: st.DataObject, n: int = 3) -> str:
    """Replace up to `n` numbers of `text` with odd values."""
    spans = [m.span() for m in NUMBER.finditer(text)]
    if not spans:
        return text
    picks = sorted(set(data.draw(st.lists(st.integers(0, len(spans) - 1), min_size=1,
                                          max_size=n))), reverse=True)
    for i in picks:
        a, b = spans[i]
        text = text[:a] + data.draw(ODD_NUMBERS) + text[b:]
    return text


def mutate_lines(text: str, data: st.DataObject) -> str:
    """Drop, duplicate or garble a line, or cut the text there."""
    lines = text.splitlines()
    if not lines:
        return text
    i = data.draw(st.integers(0, len(lines) - 1))
    action = data.draw(st.sampled_from(["drop", "dup", "garble", "truncate"]))
    if action == "drop":
        del lines[i]
    elif action == "dup":
        lines.insert(i, lines[i])
    elif action == "garble":
        lines[i] = data.draw(st.text(max_size=40))
    else:
        lines = lines[:i]
    return "\n".join(lines) + "\n"
