"""A write that fails behind the free-space guards is a clean stop, and the run resumes.

A disk filled by another program, a network volume or a failing drive makes the file system
answer ENOSPC or EIO although ``statvfs`` still shows room. These tests make that happen with a
write-failure injector: a small shared library, compiled here with gcc and loaded into
``imucalib run`` with ``LD_PRELOAD``, that makes ``write``, ``pwrite``, ``pwrite64`` and ``writev``
fail on the files whose path holds ``IMUCALIB_FAIL_PATH`` once ``IMUCALIB_FAIL_AFTER_CALLS``
calls or ``IMUCALIB_FAIL_AFTER_BYTES`` bytes went through (``IMUCALIB_FAIL_ERRNO``: ``ENOSPC``,
the default, or ``EIO``). A first run counts the write calls of the recording and of its
compressed copy, so that the failures land at chosen points: the file's creation, the
acquisition and step writes, the last flush and the close, and the compression.

Every injected run must end with exit code 2 and one ``error:`` line (no signal, no traceback,
no "Exception ignored"), the equipment stopped, and ``imucalib run --resume FILE`` (without the
injector) must then complete the recording: every plan step done with its samples, compressed,
no partial copy left. ``docs/reliability.md`` lists the promise and these tests.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import textwrap
import threading
from collections import Counter
from collections.abc import Mapping
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

import h5py
import pytest

from imucalib.errors import RecordingWriteError
from imucalib.io import open_recording
from imucalib.io.coverage import uncovered_done_steps
from imucalib.io.recording import RecordingWriter
from imucalib.io.recover import recover_recording, stale_partial
from imucalib.plan import load_plan, write_plan
from imucalib.procedures import generate_p1_plan
from imucalib.station.runner import RunOptions, resume_run, run_plan
from imucalib.station.sim import SimStation

SHIM_C = r"""
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/uio.h>
#include <unistd.h>

static long long bytes_seen, calls_seen, partial_calls;

static int path_of(int fd, char *target, size_t size) {
    char link[64];
    ssize_t n;
    snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
    n = readlink(link, target, size - 1);
    if (n <= 0) return 0;
    target[n] = 0;
    return 1;
}

static long long env_ll(const char *name) {
    const char *v = getenv(name);
    return v != NULL && *v ? atoll(v) : -1;
}

/* 1: fail this write of `count` bytes to `fd` (errno set); 0: let it through */
static int should_fail(int fd, size_t count) {
    const char *want = getenv("IMUCALIB_FAIL_PATH"), *code;
    char target[4096];
    long long after_bytes, after_calls;
    if (want == NULL || *want == 0 || fd < 0 || !path_of(fd, target, sizeof target)) return 0;
    if (strstr(target, want) == NULL) return 0;
    if (strstr(target, ".partial") != NULL) partial_calls++;
    after_bytes = env_ll("IMUCALIB_FAIL_AFTER_BYTES");
    after_calls = env_ll("IMUCALIB_FAIL_AFTER_CALLS");
    calls_seen++;
    if ((after_bytes >= 0 && bytes_seen + (long long)count > after_bytes)
            || (after_calls >= 0 && calls_seen > after_calls)) {
        code = getenv("IMUCALIB_FAIL_ERRNO");
        errno = (code != NULL && strcmp(code, "EIO") == 0) ? EIO : ENOSPC;
        return 1;
    }
    bytes_seen += (long long)count;
    return 0;
}

#define REAL(name) static __typeof__(name) *real; if (!real) real = dlsym(RTLD_NEXT, #name)

ssize_t write(int fd, const void *buf, size_t count) {
    REAL(write);
    return should_fail(fd, count) ? -1 : real(fd, buf, count);
}

ssize_t pwrite(int fd, const void *buf, size_t count, off_t offset) {
    REAL(pwrite);
    return should_fail(fd, count) ? -1 : real(fd, buf, count, offset);
}

ssize_t pwrite64(int fd, const void *buf, size_t count, off_t offset) {
    REAL(pwrite64);
    return should_fail(fd, count) ? -1 : real(fd, buf, count, offset);
}

ssize_t writev(int fd, const struct iovec *iov, int iovcnt) {
    size_t total = 0;
    int i;
    REAL(writev);
    for (i = 0; i < iovcnt; i++) total += iov[i].iov_len;
    return should_fail(fd, total) ? -1 : real(fd, iov, iovcnt);
}

/* IMUCALIB_FAIL_REPORT: where to write "<matched calls> <of them to .partial files>" */
__attribute__((destructor)) static void report(void) {
    const char *out = getenv("IMUCALIB_FAIL_REPORT");
    FILE *f;
    if (out == NULL || *out == 0 || (f = fopen(out, "w")) == NULL) return;
    fprintf(f, "%lld %lld\n", calls_seen, partial_calls);
    fclose(f);
}
"""

RECORDING = "run.h5"
HDF5_IN_USE = threading.Lock()  # held while this process resumes a file (see `imucalib`)
N_CAMPAIGN = int(os.environ.get("IMUCALIB_WRITE_FAIL_CAMPAIGN", "0"))
NOISE = ("Traceback", "Exception ignored", "internal error", "Segmentation", "RuntimeError")


@dataclass(frozen=True)
class Case:
    """One injected failure: on which file, after how many calls (or bytes), which errno."""

    name: str
    path: str  # substring of the failing file's path
    errno: str
    calls: int | None = None
    nbytes: int | None = None

    def env(self) -> dict[str, str]:
        out = {"IMUCALIB_FAIL_PATH": self.path, "IMUCALIB_FAIL_ERRNO": self.errno}
        if self.calls is not None:
            out["IMUCALIB_FAIL_AFTER_CALLS"] = str(self.calls)
        if self.nbytes is not None:
            out["IMUCALIB_FAIL_AFTER_BYTES"] = str(self.nbytes)
        return out


@pytest.fixture(scope="module")
def shim(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The injector, compiled (gcc is part of the build environment: no skip without it)."""
    gcc = shutil.which("gcc") or "/usr/bin/gcc"
    if not Path(gcc).exists():
        pytest.fail("gcc is needed to build the write-failure injector (it is part of the build "
                    "environment: apt-get install gcc)")
    folder = tmp_path_factory.mktemp("shim")
    source = folder / "failwrite.c"
    source.write_text(SHIM_C, encoding="utf-8")
    lib = folder / "failwrite.so"
    subprocess.run([gcc, "-shared", "-fPIC", "-O1", "-o", str(lib), str(source), "-ldl"],
                   check=True, capture_output=True, timeout=60)
    return lib


@pytest.fixture(scope="module")
def plan_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Six steps of a small P1 plan at 100 Hz: check, warm-up, three positions, a static."""
    plan = generate_p1_plan(name="wf", grade="consumer", rates_dps=(-90.0, 0.0, 90.0),
                            held_out_rates_dps=(), revolutions=1, static_s=5.0, settle_s=2.0,
                            record_s=2.0, rate_settle_s=2.0, repetitions=1, warm_up_s=2.0,
                            sample_rate_hz=100.0, seed=3)
    plan = plan.model_copy(update={"steps": tuple(plan.steps[i] for i in (0, 1, 2, 3, 8, 9))})
    return write_plan(plan, tmp_path_factory.mktemp("plan") / "plan.toml")


def imucalib(*args: str, env: Mapping[str, str] | None = None,
             timeout_s: float = 120) -> subprocess.CompletedProcess[str]:
    """Run the command line in a child process (with extra environment variables).

    The child is started under :data:`HDF5_IN_USE`: a child forked while this process holds an
    HDF5 file keeps a copy of its locked descriptor until it runs the new program, and HDF5's
    lock then refuses this process's next opening of the file.
    """
    full = {**os.environ, "COLUMNS": "400", **(env or {})}
    argv = [sys.executable, "-m", "imucalib.cli", *args]
    with HDF5_IN_USE:
        proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env=full)
    try:
        out, err = proc.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        raise
    return subprocess.CompletedProcess(argv, proc.returncode, out, err)


def run_args(plan_file: Path, out: Path) -> tuple[str, ...]:
    return ("run", str(plan_file), "--out", str(out), "--no-record", "--yes", "-q")


@pytest.fixture(scope="module")
def write_calls(shim: Path, plan_file: Path, tmp_path_factory: pytest.TempPathFactory
                ) -> tuple[int, int]:
    """The write calls of a clean run: to its recording, and to the compressed copy of it."""
    folder = tmp_path_factory.mktemp("count")
    report = folder / "calls.txt"
    result = imucalib(*run_args(plan_file, folder / RECORDING),
                      env={"LD_PRELOAD": str(shim), "IMUCALIB_FAIL_PATH": RECORDING,
                           "IMUCALIB_FAIL_REPORT": str(report)})
    assert result.returncode == 0, result.stderr
    total, partial = map(int, report.read_text().split())
    assert total > partial > 20, (total, partial)  # the injector sees HDF5's writes
    return total - partial, partial


def cases(main: int, copy: int) -> list[Case]:
    """21 failures over a run and its compression, ENOSPC and EIO in turn.

    ``IMUCALIB_WRITE_FAIL_CAMPAIGN=N`` adds N failures spread evenly over the run's write calls
    and N / 4 over its compression's (the campaign of ``docs/reliability.md``).
    """
    own = f"/{RECORDING}"  # the recording, not its copy (.run.h5.compact.partial)
    points = [("creation", own, 2)]
    points += [(f"run-{p}%", own, main * p // 100) for p in (10, 20, 35, 50, 65, 80, 90, 95)]
    points += [(f"end-{k}", own, main - k) for k in (16, 8, 4, 2, 1)]  # the last flushes
    points += [(f"compression-{p}%", "compact.partial", max(1, copy * p // 100))
               for p in (0, 25, 50, 75, 99)]
    points += [(f"campaign-run-{k}", own, k)
               for k in sorted({1 + i * (main - 1) // N_CAMPAIGN for i in range(N_CAMPAIGN)})]
    n_copy = N_CAMPAIGN // 4
    points += [(f"campaign-copy-{k}", "compact.partial", k)
               for k in sorted({1 + i * (copy - 1) // max(n_copy, 1) for i in range(n_copy)})]
    out = [Case(name, path, ("ENOSPC", "EIO")[i % 2], calls=k)
           for i, (name, path, k) in enumerate(points)]
    out += [Case("bytes-1MB", own, "EIO", nbytes=1 << 20),
            Case("bytes-20MB", own, "ENOSPC", nbytes=20 << 20)]
    return out


def one_error_line(result: subprocess.CompletedProcess[str]) -> str:
    """The child's stderr, checked to be one ``error:`` line and nothing else."""
    err = result.stderr.strip()
    assert result.returncode == 2, (result.returncode, err[-2000:])
    assert not any(word in err for word in NOISE), err[-2000:]
    assert len(err.splitlines()) == 1 and err.startswith("error: "), err[-2000:]
    return err


def check_complete(path: Path, n_steps: int) -> None:
    """Every plan step done with its samples; closed cleanly, compressed, no partial copy."""
    with open_recording(path, strict=True) as rec:
        done = {s.commanded["plan_step"] for s in rec.steps if s.status == "done"}
        assert done == set(range(n_steps)), [(s.index, s.status) for s in rec.steps]
        assert uncovered_done_steps(rec) == {}
        assert not any(s.status == "running" for s in rec.steps)
    with h5py.File(path, "r") as f:
        assert f["streams/imu/IMU-0001/time_s"].compression == "gzip"
    assert not stale_partial(path).exists()


def inject(case: Case, shim: Path, plan_file: Path, folder: Path) -> tuple[Path, str | None]:
    """Run with the injected failure and check the stop; return the file and the error line.

    The error is None when the run made fewer write calls than the case's (the flushes every
    second of wall-clock time make their number vary a little near the end of a run): it then
    ran to its end, and the injector's report says that no write was refused.
    """
    folder.mkdir()
    path = folder / RECORDING
    report = folder / "calls.txt"
    failed = imucalib(*run_args(plan_file, path),
                      env={"LD_PRELOAD": str(shim), "IMUCALIB_FAIL_REPORT": str(report),
                           **case.env()})
    if failed.returncode == 0 and case.calls is not None and report.exists():
        assert int(report.read_text().split()[0]) <= case.calls, failed.stderr  # not reached
        return path, None
    return path, one_error_line(failed)


def resume(path: Path, plan_file: Path, *, cli: bool) -> None:
    """Resume without the injector (the command line, or the same call in this process)."""
    if cli:
        resumed = imucalib("run", "--resume", str(path), "--no-record", "-q")
        assert resumed.returncode == 0, (resumed.stdout, resumed.stderr)
        assert "Traceback" not in resumed.stderr
    else:
        with HDF5_IN_USE:
            summary = resume_run(path, lambda plan, t0: SimStation(plan.twin, start_time_s=t0),
                                 options=RunOptions(tick_s=2.0))
        assert summary.status == "done", summary
    with HDF5_IN_USE:
        check_complete(path, len(load_plan(plan_file).steps))


def copies_fail_cleanly(path: Path, shim: Path) -> None:
    """`recover` and `run --resume` whose copy of a stopped writer's file fails to be written."""
    before = sorted(p.name for p in path.parent.iterdir())
    for args, copy in ((("recover", str(path)), "recovered.h5"),
                       (("run", "--resume", str(path), "--no-record", "-q"), "recovering.h5")):
        env = {"LD_PRELOAD": str(shim), "IMUCALIB_FAIL_PATH": copy,
               "IMUCALIB_FAIL_AFTER_CALLS": "10", "IMUCALIB_FAIL_ERRNO": "EIO"}
        err = one_error_line(imucalib(*args, env=env))
        assert "the original is unchanged" in err and "Input/output error" in err, err
        assert sorted(p.name for p in path.parent.iterdir()) == before  # no copy left behind


def test_failed_writes_stop_cleanly_and_resume(shim, plan_file, write_calls, tmp_path):
    """≥ 20 injected ENOSPC/EIO over a run and its compression: 0 crashes, all resume."""
    main, copy = write_calls
    todo = cases(main, copy)
    cli = {"run-50%", "end-1", "compression-50%"}  # resumed through the command line
    errors: dict[str, str] = {}
    with ThreadPoolExecutor(max_workers=2) as pool:  # two runs fail while this one resumes
        futures = {pool.submit(inject, c, shim, plan_file, tmp_path / c.name): c for c in todo}
        for future in as_completed(futures):
            case = futures[future]
            path, err = future.result()
            if err is None:  # the run ended before the case's write call
                continue
            errors[case.name] = err
            if "nothing was recorded (the file is removed)" in err:  # failed in the creation
                assert not path.exists()
                continue
            assert str(path) in err and "imucalib run --resume" in err, err
            if case.name == "run-35%":
                copies_fail_cleanly(path, shim)
            resume(path, plan_file, cli=case.name in cli)
    assert len(errors) >= 20, sorted(set(c.name for c in todo) - set(errors))
    todo = [c for c in todo if c.name in errors]
    for c in todo:
        if c.errno == "ENOSPC":
            assert "No space left on device" in errors[c.name], errors[c.name]
        else:
            assert "Input/output error" in errors[c.name], errors[c.name]
    # the failures landed where they were aimed
    assert errors["creation"].startswith("error: creating ")
    assert any("closing" in errors[c.name] or "flushing" in errors[c.name]
               for c in todo if c.name.startswith("end-")), errors
    for c in todo:
        if c.path == "compact.partial":
            assert "is complete and closed but was left uncompressed" in errors[c.name]
    if N_CAMPAIGN:  # where the failures landed, for docs/reliability.md (pytest -s shows it)
        kinds = ("creating", "writing stream", "flushing", "closing", "no room", "uncompressed")
        where = Counter(next((k for k in kinds if k in e), "other") for e in errors.values())
        print(f"\n{len(todo)} runs, 0 crashes, all resumed; stopped at: {dict(where)}")


KILL_CHILD = textwrap.dedent("""
    import os, signal, sys
    from imucalib.io import recover

    copy = recover._copy

    def copy_then_die(*args, **kwargs):  # the copy is written, neither closed nor renamed
        copier = copy(*args, **kwargs)
        os.kill(os.getpid(), signal.SIGKILL)
        return copier

    recover._copy = copy_then_die
    sys.argv = ["imucalib", *sys.argv[1:]]
    from imucalib.cli import main
    main()
""")


def test_kill_during_compression_then_resume_finishes_it(plan_file, tmp_path):
    """SIGKILL with the compressed copy written but not renamed: the file stays the recording."""
    path = tmp_path / RECORDING
    child = tmp_path / "kill_in_compression.py"
    child.write_text(KILL_CHILD, encoding="utf-8")
    killed = subprocess.run([sys.executable, str(child), *run_args(plan_file, path)],
                            capture_output=True, text=True, timeout=120)
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    partial = stale_partial(path)
    assert partial.exists()  # the half-made copy, under its own name
    n_steps = len(load_plan(plan_file).steps)
    with open_recording(path, strict=True) as rec:  # the valid recording: closed, complete
        assert {s.commanded["plan_step"] for s in rec.steps if s.status == "done"} == \
            set(range(n_steps))
    with h5py.File(path, "r") as f:
        assert f["streams/imu/IMU-0001/time_s"].compression is None
    other = tmp_path / "other"
    other.mkdir()
    shutil.copyfile(path, other / RECORDING)
    shutil.copyfile(partial, stale_partial(other / RECORDING))

    resumed = imucalib("run", "--resume", str(path), "--no-record", "-q")
    assert resumed.returncode == 0, resumed.stderr
    assert "the interrupted compression was finished" in resumed.stdout
    check_complete(path, n_steps)
    again = imucalib("run", "--resume", str(path), "--no-record", "-q")
    assert again.returncode == 2
    assert "there is nothing to resume" in again.stderr

    report = recover_recording(other / RECORDING)  # `imucalib recover FILE` works on it too
    assert report.verified and not report.was_open_for_write
    check_complete(report.output, n_steps)
    assert not stale_partial(other / RECORDING).exists()


@pytest.mark.parametrize("where", ["flush", "close"])
def test_a_failed_write_stops_the_equipment_safely(plan_file, tmp_path, monkeypatch, where):
    """As for a full disk: the motion stopped, whether the write fails mid-run or at the close."""
    plan = load_plan(plan_file)
    assert plan.twin is not None
    station = SimStation(plan.twin)
    failure = RecordingWriteError(f"{where} to run.h5 failed: No space left on device (test)")
    original = RecordingWriter.flush

    def fail_late(self: RecordingWriter) -> None:
        if where == "close" or station.clock.now_s() > 20.0:
            self._closed = True  # as an abandoned writer: HDF5 is not called again
            raise failure
        original(self)

    monkeypatch.setattr(RecordingWriter, "_close_file" if where == "close" else "flush",
                        fail_late)
    with pytest.raises(RecordingWriteError) as caught:
        run_plan(plan, station, tmp_path / RECORDING, options=RunOptions(tick_s=2.0))
    assert caught.value is failure
    status = station.table.status()
    assert set(status.modes) == {"off"} and not status.interlock_closed
