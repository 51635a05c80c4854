"""Analysis speed of every procedure against the bare read of its recording, and its memory.

For P1, P2 (8 units), P3, the tumble, the field calibration and the Allan characterisation a
recording is made on the twin through the command line (``imucalib plan new NAME ...`` then
``imucalib run PLAN --station sim``, in subprocesses), and a copy of it is written with each
codec (:func:`~imucalib.io.recover.compact_recording`): ``gzip`` (HDF5's shuffle + deflate, the
default) and ``blosc-lz4``. Then, for each measurement, a fresh child process

1. warms up: analyses a small recording of the same procedure once, untimed (the ``--quick``
   one; with ``--quick``, the measured recording itself), so that imports, the numba kernels'
   compile or cache load and the first calls are not timed;
2. reads the two copies bare: h5py opens the file and reads every dataset under ``/streams``
   whole (``ds[()]``), best of 3 (Blosc through ``hdf5plugin``); the page cache is warm, the
   files having just been written;
3. analyses the gzip copy (``procedure_of(path).analyze(path, unit=None, options=...)``: every
   unit of a P2 lot), best of ``--repeat`` (2). Its peak memory is the resident high-water mark
   after the analyses (``VmHWM``, reset through ``/proc/self/clear_refs`` right before them)
   minus the resident size before them, taken after ``malloc_trim(0)`` (the C heap keeps the
   warm-up's and the bare read's freed memory resident otherwise, and the analysis would reuse
   it unseen). ``ru_maxrss`` alone would carry the warm-up's and the bare read's peaks, and the
   parent's (it survives fork and exec).

The measuring children run with one thread of every numerical library (BLAS, OpenMP, Blosc,
numba, the Allan engine; ``--threads default`` leaves them alone): the aim is the analysis on
one core, and on a shared machine the BLAS threads' contention otherwise swamps the
measurement (docs/performance.md, "BLAS threads on a busy machine").

Printed: a markdown table, one row a procedure (IMU samples of every unit, file sizes, bare
reads, analysis, analysis / gzip read by wall-clock and by process CPU time — the latter moves
less when other processes share the cores —, peak memory, and for P1 and P2 the analysis with 2
workers and its speed-up), the CPU-time ratios again with the CPU of the child processes
each analysis forked and waited for (``RUSAGE_CHILDREN``: the opening's probe,
docs/recording-format.md, "Hangs and crashes inside HDF5"; on one core its time is the
analysis's too), then for P1 and P2 the peak memory of longer recordings (P1: the static and
position records ×4, which makes the longest step 4× longer, and the repetitions ×4, which does
not; P2: the sample rate ×4, since the twin's P2 run costs station time, not samples),
for the field calibration the marginal analysis / read ratio (its recording at twice
the sample rate, the same poses: (A₂ − A₁)/(R₂ − R₁), the cost of a sample without the fixed
costs that dominate so small a read), the codecs' file sizes and the machine.

Run:  .venv/bin/python bench/bench_analysis.py [--quick] [--keep DIR] [--only p1,p2,...]
      [--repeat 2] [--profile NAME|slowest]

``--keep DIR`` makes the recordings there and reuses them on the next run (the plan's flags are
stored beside them: changed flags make them again). ``--profile`` runs one more analysis under
cProfile (``slowest``: the procedure with the largest analysis / read ratio) and prints the top
entries by cumulative time. About 9 minutes on a shared 2-core machine, most of it the twin's
runs (about 1 minute with ``--keep`` and the recordings there); ``--quick`` under 2 minutes.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
CODECS = ("gzip", "blosc-lz4")  # the first is the default codec, the one analysed


@dataclass(frozen=True)
class Spec:
    """One procedure: its plan flags at each size."""

    name: str  # registry name (``plan new NAME``)
    label: str
    full: str
    quick: str
    #: the memory rows (P1, P2): (what was made longer, full flags, quick flags)
    longer: tuple[tuple[str, str, str], ...] = ()
    workers: bool = False  # time the analysis with 2 workers too
    #: (what was made longer, full flags, quick flags) of a second length: the marginal
    #: analysis / read ratio, (A₂ − A₁)/(R₂ − R₁), for a procedure whose ratio its fixed costs
    #: dominate
    marginal: tuple[str, str, str] | None = None


_P2 = ("--n-imus {n} --static-s {s} --settle-s 2 --sample-rate-hz {hz} --revolutions 1 "
       "--temperatures 0,25,50 --held-out 10 --no-hysteresis --stable-for-s 60 --resoak-s 30 "
       "--ramp-degc-per-min 10")
_P1 = "--repetitions {n} --static-s {s} --record-s {r} --warm-up-s 300"
_P1_QUICK = ("--repetitions {n} --static-s {s} --record-s {r} --settle-s 2 --rate-settle-s 2 "
             "--warm-up-s 5 --revolutions 1 --sample-rate-hz 100")

SPECS = (
    Spec("p1", "P1", full=_P1.format(n=1, s=600, r=10), quick=_P1_QUICK.format(n=1, s=20, r=5),
         longer=(("static and position records ×4", _P1.format(n=1, s=2400, r=40),
                  _P1_QUICK.format(n=1, s=80, r=20)),
                 ("repetitions ×4", _P1.format(n=4, s=600, r=10),
                  _P1_QUICK.format(n=4, s=20, r=5))),
         workers=True),
    Spec("p2", "P2", full=_P2.format(n=8, s=10, hz=100),
         quick=_P2.format(n=2, s=5, hz=25),
         longer=(("sample rate ×4", _P2.format(n=8, s=10, hz=400),
                  _P2.format(n=2, s=5, hz=100)),), workers=True),
    Spec("p3", "P3", full="--sample-rate-hz 100",
         quick="--rate-record-s 5 --rest-record-s 5 --tumble-record-s 5 --settle-s 2 "
               "--n-rates 4 --sample-rate-hz 100"),
    Spec("tumble", "tumble", full="--sample-rate-hz 200",
         quick="--record-s 5 --settle-s 2 --sample-rate-hz 100"),
    Spec("field", "field calibration", full="--sample-rate-hz 1000 --n-poses 24",
         quick="--static-s 3 --init-static-s 10 --sample-rate-hz 100",
         marginal=("sample rate ×2", "--sample-rate-hz 2000 --n-poses 24",
                   "--static-s 3 --init-static-s 10 --sample-rate-hz 200")),
    Spec("allan", "Allan characterisation", full="--record-s 600 --warm-up-s 5",
         quick="--record-s 600 --warm-up-s 5 --sample-rate-hz 50"),
)


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


# ----------------------------------------------------------------------------- recordings


@dataclass(frozen=True)
class Files:
    """A recording's copies, one per codec, and its facts."""

    paths: dict[str, Path]  # codec → file
    imu_samples: int
    units: int  # IMU streams
    largest_step: int  # samples of one unit in the longest step window

    @property
    def analysed(self) -> Path:
        return self.paths[CODECS[0]]


def _cli(*args: str) -> None:
    cmd = [sys.executable, "-m", "imucalib", *args]
    done = subprocess.run(cmd, capture_output=True, text=True, check=False, cwd=ROOT)
    if done.returncode != 0:
        raise SystemExit(f"failed: {' '.join(cmd)}\n{done.stdout[-2000:]}{done.stderr[-3000:]}")


def _imu_samples(path: Path) -> tuple[int, int, int]:
    """The IMU samples of every unit, the units, and the samples of the longest step's window."""
    from imucalib.io.opening import open_recording

    with open_recording(path) as rec:
        imus = [s for s in rec.streams if s.device == "imu"]
        largest = 0
        for step in rec.steps:
            if step.has_valid_window:
                i0, i1 = rec.row_range("imu", imus[0].unit, step.valid_start_s,
                                       step.valid_end_s)
                largest = max(largest, i1 - i0)
        return sum(s.n_samples for s in imus), len(imus), largest


def recording(base: Path, name: str, flags: str) -> Files:
    """Make (or reuse) the recording of ``plan new NAME FLAGS`` in its folder under `base`."""
    from imucalib.io.recover import compact_recording

    folder = base / f"{name}-{hashlib.sha256(flags.encode()).hexdigest()[:10]}"
    stamp = folder / "flags.txt"
    paths = {c: folder / f"run.{c}.h5" for c in CODECS}
    if stamp.is_file() and stamp.read_text() == flags and all(p.is_file() for p in paths.values()):
        log(f"  reusing {folder}")
        return Files(paths, *_imu_samples(paths[CODECS[0]]))
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    t0 = time.perf_counter()
    plan, run = folder / "plan.toml", folder / "run.h5"
    _cli("plan", "new", name, "--out", str(plan), *flags.split())
    _cli("run", str(plan), "--station", "sim", "--out", str(run), "--yes", "--no-record", "-q")
    t_sim = time.perf_counter() - t0
    for codec in CODECS[1:]:
        shutil.copyfile(run, paths[codec])
        compact_recording(paths[codec], codec)
    compact_recording(run, CODECS[0])
    os.replace(run, paths[CODECS[0]])
    stamp.write_text(flags)
    files = Files(paths, *_imu_samples(paths[CODECS[0]]))
    log(f"  made {name} {flags!r}: {files.imu_samples:,} IMU samples, twin run {t_sim:.0f} s, "
        f"copies {time.perf_counter() - t0 - t_sim:.0f} s")
    return files


# ----------------------------------------------------------------------------- the child


def _status(key: str) -> int:
    """The ``/proc/self/status`` value `key` (``VmRSS``, ``VmHWM``) [KiB]."""
    with open("/proc/self/status", encoding="ascii") as fh:
        for line in fh:
            if line.startswith(key + ":"):
                return int(line.split()[1])
    return -1


def _malloc_trim() -> bool:
    """Give the C heap's free memory back to the system (glibc); whether it could."""
    import ctypes
    import ctypes.util

    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.malloc_trim(0)
    except (OSError, AttributeError):
        return False
    return True


def _children_cpu() -> float:
    """CPU time of this process's children that have ended (the open's forked probe) [s]."""
    import resource

    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _bare_read(path: Path) -> float:
    """Open `path` with h5py and read every dataset under /streams whole [s]."""
    return _bare_read_times(path)[0]


def _bare_read_times(path: Path) -> tuple[float, float]:
    """:func:`_bare_read`'s wall-clock and process CPU times [s]."""
    import h5py

    t0, c0 = time.perf_counter(), time.process_time()
    with h5py.File(path, "r") as f:
        names: list[str] = []
        f["streams"].visititems(
            lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
        for n in names:
            data = f["streams"][n][()]
            del data
    return time.perf_counter() - t0, time.process_time() - c0


def child(job: dict[str, Any]) -> dict[str, Any]:
    """One measurement (module docstring): warm-up, bare reads, the analysis."""
    import gc

    import hdf5plugin  # noqa: F401  (the Blosc filter, for the bare read)

    from imucalib.calibration import procedure_of

    out: dict[str, Any] = {}
    path = Path(job["path"])
    options = job["options"] or None
    proc = procedure_of(path)
    t0 = time.perf_counter()
    proc.analyze(job["warm"], unit=None, options=None)  # workers=2: its pool starts anew
    out["warm_s"] = time.perf_counter() - t0
    for codec in reversed(CODECS):  # the analysed codec last, right before the analysis
        if codec in job["reads"]:
            reads = [_bare_read_times(Path(job["reads"][codec])) for _ in range(3)]
            out[f"read_{codec}"] = min(r[0] for r in reads)
            out[f"read_{codec}_cpu"] = min(r[1] for r in reads)
    gc.collect()
    out["trimmed"] = _malloc_trim()
    try:
        with open("/proc/self/clear_refs", "w", encoding="ascii") as fh:
            fh.write("5")  # VmHWM := VmRSS
        out["hwm_reset"] = True
    except OSError:
        out["hwm_reset"] = False
    rss0 = _status("VmRSS")
    if job.get("profile"):
        import cProfile
        import io
        import pstats

        prof = cProfile.Profile()
        t0 = time.perf_counter()
        prof.runcall(proc.analyze, path, unit=None, options=options)
        out["analysis_s"] = time.perf_counter() - t0
        text = io.StringIO()
        pstats.Stats(prof, stream=text).sort_stats("cumulative").print_stats(job["profile"])
        out["profile"] = text.getvalue()
    else:
        times, cpu, total = [], [], []
        for _ in range(job["repeat"]):
            t0, c0, k0 = time.perf_counter(), time.process_time(), _children_cpu()
            proc.analyze(path, unit=None, options=options)
            times.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
            total.append(cpu[-1] + _children_cpu() - k0)
        out["analysis_s"] = min(times)
        out["analysis_cpu_s"] = min(cpu)
        out["analysis_cpu_children_s"] = min(total)
    out["peak_mib"] = max(_status("VmHWM") - rss0, 0) / 1024
    return out


def measure(files: Files, warm: Path, *, options: dict[str, Any] | None = None,
            reads: bool = True, profile: int = 0, repeat: int = 2) -> dict[str, Any]:
    job = {"path": str(files.analysed), "warm": str(warm), "options": options or {},
           "reads": {c: str(p) for c, p in files.paths.items()} if reads else {},
           "profile": profile, "repeat": repeat}
    done = subprocess.run([sys.executable, __file__, "--child", json.dumps(job)],
                          capture_output=True, text=True, check=False, cwd=ROOT)
    lines = [ln for ln in done.stdout.splitlines() if ln.startswith("RESULT ")]
    if done.returncode != 0 or not lines:
        raise SystemExit(f"measurement of {files.analysed} failed:\n{done.stderr[-4000:]}")
    result: dict[str, Any] = json.loads(lines[-1][len("RESULT "):])
    return result


# ----------------------------------------------------------------------------- the report


def _mb(path: Path) -> float:
    return path.stat().st_size / 1e6


def _row(cells: list[str]) -> str:
    return "| " + " | ".join(cells) + " |"


def kernels(n: int = 3_300_000, repeat: int = 3) -> None:
    """Print the running median's cost per sample: the compiled paths against the partition.

    The outlier rule's median of each sample's 8 neighbours (h = 4) on one Gaussian column,
    side by side in this process: the sorting network (numba), the sorted window (numba, any
    h; timed with h = 4 through its loop), and the former ``np.partition`` of blocks of
    windows (the numpy path). Best of `repeat`. Then the exact median of
    ``processing/_select_kernel.py`` against ``np.median`` (:func:`_medians`) on `n` and on
    10,000 values.
    """
    import numpy as np

    from imucalib.processing import _median_kernel as mk

    x = np.random.default_rng(0).normal(size=n)
    mk.neighbour_median(x[:100], 4)  # compile or load the kernels
    found = mk._kernels()
    ways: list[tuple[str, Any]] = [("partition (numpy)",
                                    lambda: mk.neighbour_median(x, 4, backend="numpy"))]
    if found is not None:
        general, eight = found[0], found[1]
        out = np.zeros(n)
        ways = [("sorting network (numba)", lambda: eight(x, out)),
                ("sorted window (numba)", lambda: general(x, 4, out)), *ways]
    print(f"\nrunning median of 8 neighbours, {n / 1e6:.1f} M samples (best of {repeat}):")
    floor = None
    for name, run in ways:
        best = min(_timed(run) for _ in range(repeat))
        floor = floor or best
        print(f"  {name:26s} {best * 1e9 / n:6.1f} ns/sample   {best / floor:5.1f}×")
    for size in (n, 10_000):
        _medians(np.random.default_rng(1).normal(size=size), n // size, repeat)


def _medians(x: Any, calls: int, repeat: int) -> None:
    """Print the exact Floyd–Rivest median (and MAD) against ``np.median`` on `x`, ns/sample.

    The outlier rule's two medians per column: of the residuals, and of their absolute
    deviations (materialised as the rule does, and fused). Each timing makes `calls` calls.
    """
    import numpy as np

    from imucalib.processing import _select_kernel as sk

    sk.median(x[:1000])  # compile or load the kernel
    c = float(np.median(x))
    dev = np.abs(x - c)
    ways: list[tuple[str, Any]] = [
        ("median: np.median", lambda: np.median(x)),
        ("median: Floyd-Rivest", lambda: sk.median(x)),
        ("MAD: np.median(|x - c|)", lambda: np.median(np.abs(x - c))),
        ("MAD: Floyd-Rivest of dev", lambda: sk.median(dev)),
        ("MAD: Floyd-Rivest, fused", lambda: sk.median_abs_deviation(x, c)),
    ]
    kernel = "numba" if sk._kernel() is not None else "numpy (no numba)"
    print(f"\nexact median, {x.size:,} samples × {calls} calls ({kernel}, best of {repeat}):")
    floor = None
    for name, run in ways:
        def many(run: Any = run) -> None:
            for _ in range(calls):
                run()

        best = min(_timed(many) for _ in range(repeat))
        per = best * 1e9 / (x.size * calls)
        floor = floor or per
        print(f"  {name:26s} {per:6.2f} ns/sample   {per / floor:5.2f}×")


def _timed(run: Any) -> float:
    t = time.perf_counter()
    run()
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kernels", action="store_true",
                    help="only the running-median kernel timings (seconds, no recordings)")
    ap.add_argument("--quick", action="store_true", help="small recordings (a smoke run)")
    ap.add_argument("--keep", type=Path, default=None,
                    help="make the recordings in DIR and reuse those already there")
    ap.add_argument("--only", default="", help="comma-separated procedure names (default: all)")
    ap.add_argument("--profile", default="", metavar="NAME|slowest",
                    help="one more analysis of NAME under cProfile; print its top entries")
    ap.add_argument("--profile-top", type=int, default=15)
    ap.add_argument("--repeat", type=int, default=2, help="analyses per child (the best)")
    ap.add_argument("--threads", choices=("one", "default"), default="one",
                    help="one thread of every numerical library in the measuring children "
                         "(default: the analysis on one core), or the libraries' defaults")
    ap.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child is not None:
        print("RESULT " + json.dumps(child(json.loads(args.child))), flush=True)
        return
    if args.kernels:
        kernels()
        return
    specs = [s for s in SPECS if not args.only or s.name in args.only.split(",")]
    if args.threads == "one":  # inherited by the children (workers.py's list)
        from imucalib.procedures.common.workers import THREAD_VARIABLES

        os.environ.update(dict.fromkeys(THREAD_VARIABLES, "1"))
    tmp = None
    if args.keep is None:
        tmp = tempfile.TemporaryDirectory(prefix="bench-analysis-")
        base = Path(tmp.name)
    else:
        base = args.keep
        base.mkdir(parents=True, exist_ok=True)
    from imucalib.procedures import registry

    start = time.perf_counter()
    load0 = os.getloadavg()
    try:
        rows, mem_rows, measured = [], [], {}
        with_children: list[str] = []
        marginal_rows: list[str] = []
        for spec in specs:
            log(f"{spec.label}:")
            warm = recording(base, spec.name, spec.quick)
            main_files = warm if args.quick else recording(base, spec.name, spec.full)
            m = measure(main_files, warm.analysed, repeat=args.repeat)
            label = spec.label + (f" ({main_files.units} units)" if main_files.units > 1 else "")
            measured[spec.name] = (main_files, m, label)
            read_gz = m[f"read_{CODECS[0]}"]
            cells = [label, f"{main_files.imu_samples / 1e6:.2f} M",
                     " / ".join(f"{_mb(main_files.paths[c]):.1f}" for c in CODECS),
                     *(f"{m[f'read_{c}']:.2f}" for c in CODECS), f"{m['analysis_s']:.2f}",
                     f"{m['analysis_s'] / read_gz:.1f}",
                     f"{m['analysis_cpu_s'] / m[f'read_{CODECS[0]}_cpu']:.1f}",
                     f"{m['peak_mib']:.0f}"]
            if spec.workers and "workers" in registry.get(spec.name).analysis_options:
                w = measure(main_files, warm.analysed, options={"workers": 2}, reads=False,
                            repeat=args.repeat)
                cells += [f"{w['analysis_s']:.2f}", f"{m['analysis_s'] / w['analysis_s']:.2f}×"]
            else:
                cells += ["n/a", "n/a"]
            rows.append(_row(cells))
            log(f"  {cells}")
            cpu_all = m["analysis_cpu_children_s"] / m[f"read_{CODECS[0]}_cpu"]
            with_children.append(f"{label} {cpu_all:.1f}")
            versions = [("×1", main_files, m)]
            for how, full, quick in spec.longer:
                longer = recording(base, spec.name, quick if args.quick else full)
                lm = measure(longer, warm.analysed, reads=False, repeat=args.repeat)
                versions.append((how, longer, lm))
                log(f"  {how}: {longer.imu_samples:,} samples, {lm['analysis_s']:.2f} s, "
                    f"{lm['peak_mib']:.0f} MiB")
            if spec.marginal is not None:
                how, full, quick = spec.marginal
                second = recording(base, spec.name, quick if args.quick else full)
                sm = measure(second, warm.analysed, repeat=args.repeat)
                d_an = sm["analysis_s"] - m["analysis_s"]
                d_read = sm[f"read_{CODECS[0]}"] - read_gz
                marginal_rows.append(
                    f"{label}, {how} ({main_files.imu_samples / 1e6:.2f} → "
                    f"{second.imu_samples / 1e6:.2f} M samples): analysis {m['analysis_s']:.3f} → "
                    f"{sm['analysis_s']:.3f} s, gzip read {read_gz:.3f} → "
                    f"{sm[f'read_{CODECS[0]}']:.3f} s; marginal analysis / read "
                    + (f"{d_an / d_read:.1f}" if d_read > 0 else "n/a (the read did not grow)"))
                log(f"  {marginal_rows[-1]}")
            for how, f, mm in versions if spec.longer else ():
                mem_rows.append(_row([label, how, f"{f.imu_samples / 1e6:.2f} M",
                                      f"{f.largest_step:,}", f"{_mb(f.analysed):.1f}",
                                      f"{mm['analysis_s']:.2f}", f"{mm['peak_mib']:.0f}"]))
        print()
        print(f"machine: {platform.platform()}, {platform.processor() or platform.machine()}, "
              f"{os.cpu_count()} CPUs, Python {platform.python_version()}; load average "
              f"{load0[0]:.1f} at the start, {os.getloadavg()[0]:.1f} at the end; "
              f"{'--quick' if args.quick else 'full'} sizes, "
              f"bench {time.perf_counter() - start:.0f} s")
        print("warm-up: each child first analyses a small recording of the same procedure, "
              "untimed" + (" (with --quick: the measured one itself)" if args.quick else "")
              + f"; bare reads best of 3, page cache warm; analysis of the gzip copy best of "
              f"{args.repeat}; peak memory: VmHWM (reset before the analyses) minus VmRSS before "
              "them (after malloc_trim); "
              + ("one thread of every numerical library (--threads one)"
                 if args.threads == "one" else "the numerical libraries' default threads"))
        print()
        print(_row(["procedure", "IMU samples", "file MB gzip / blosc-lz4",
                    "read gzip [s]", "read blosc-lz4 [s]", "analysis [s]",
                    "analysis / read gzip", "the same, CPU times", "peak memory [MiB]",
                    "analysis, 2 workers [s]", "speed-up"]))
        print(_row(["---"] * 11))
        print("\n".join(rows))
        print()
        print("analysis / read gzip by CPU times with the CPU of the processes the analysis "
              "forked and waited for (the open's probe: a child the column above does not "
              "count): " + "; ".join(with_children))
        if mem_rows:
            print()
            print(_row(["procedure", "recording", "IMU samples", "largest step (one unit)",
                        "file MB (gzip)", "analysis [s]", "peak memory [MiB]"]))
            print(_row(["---"] * 7))
            print("\n".join(mem_rows))
        if marginal_rows:
            print()
            print("marginal cost (a second recording of the same plan, more samples per "
                  "window): " + "; ".join(marginal_rows))
        print()
        sizes = "; ".join(
            f"{label} " + ", ".join(f"{c} {_mb(files.paths[c]):.1f} MB" for c in CODECS)
            for files, _, label in measured.values())
        print(f"codec sizes: {sizes}")
        if args.profile:
            name = args.profile
            if name == "slowest":
                name = max(measured, key=lambda k: measured[k][1]["analysis_s"]
                           / measured[k][1][f"read_{CODECS[0]}"])
            files = measured[name][0]
            warm = recording(base, name, next(s.quick for s in SPECS if s.name == name))
            prof = measure(files, warm.analysed, reads=False, profile=args.profile_top)
            print(f"\ncProfile of the {name} analysis ({prof['analysis_s']:.2f} s under the "
                  "profiler), by cumulative time:")
            print(prof["profile"])
    finally:
        if tmp is not None:
            tmp.cleanup()


if __name__ == "__main__":
    main()
