"""How ``tests/data/p1_v1.h5`` was made: a tiny P1 plan run on the twin station, format version 1.

The file is a Recording of format version 1, written by the station runner as it was at commit
``b46ed73`` (before ``/steps`` carried roles, tags and units). It exists so that the tests can
check that today's reader still opens a v1 file, recovers its steps' roles and tags, and that
P1 still calibrates it (``tests/io/test_v1_recording.py``).

Running this script reproduces a *version 1* file only at a commit whose writer is still at
version 1 (``git checkout b46ed73``); at a later commit it writes the current version, which is
not what the test wants. Run it from the repository root::

    PYTHONPATH=src python tests/data/make_v1_recording.py tests/data/p1_v1.h5

The plan is P1's default structure made small: one repetition, a 100 Hz IMU, one-second
settling and two-second records, a 20 s static record, table feedback at 50 Hz, rates of
±180 °/s over two revolutions plus one held-out rate of 90 °/s.
The runner's output (including the twin's truth under ``/truth``) is then repacked by
:func:`compact`: every group, dataset (shape, dtype, chunk shape, maximum shape, fill value) and
attribute is copied unchanged, only with gzip and shuffle filters, because the fixed-width text
tables ``/steps`` and ``/log`` otherwise fill whole uncompressed chunks (1.7 MB of padding).
"""

from __future__ import annotations

import sys
from pathlib import Path

import h5py

from imucalib.procedures import generate_p1_plan
from imucalib.station.runner import RunOptions, run_plan
from imucalib.station.sim import SimStation


def tiny_p1_plan():
    """The plan of the stored file: seed 7, consumer grade, 5 s warm-up window, 50 Hz feedback."""
    plan = generate_p1_plan(
        name="p1-v1-sample", grade="consumer", rates_dps=(-180.0, 0.0, 180.0),
        held_out_rates_dps=(90.0,), revolutions=2, static_s=20.0, settle_s=1.0, record_s=2.0,
        rate_settle_s=1.0, repetitions=1, warm_up_s=2.0, sample_rate_hz=100.0, seed=7)
    steps = list(plan.steps)
    steps[1] = steps[1].model_copy(update={"window_s": 5.0})
    assert plan.twin is not None
    table = plan.twin.table.model_copy(update={"feedback_rate_hz": 50.0})
    twin = plan.twin.model_copy(update={"table": table})
    return plan.model_copy(update={"steps": tuple(steps), "twin": twin})


def compact(src: Path, dst: Path) -> None:
    """Copy `src` to `dst` unchanged but for gzip and shuffle filters on every chunked dataset."""

    def copy(name: str, obj: h5py.Group | h5py.Dataset) -> None:
        if isinstance(obj, h5py.Dataset):
            kwargs = {}
            if obj.chunks is not None:
                kwargs = dict(chunks=obj.chunks, maxshape=obj.maxshape, compression="gzip",
                              compression_opts=9, shuffle=True)
            new = out.create_dataset(name, data=obj[()], dtype=obj.dtype,
                                     fillvalue=obj.fillvalue, **kwargs)
        else:
            new = out.require_group(name)
        for key, value in obj.attrs.items():
            new.attrs[key] = value

    with h5py.File(src, "r") as f, h5py.File(dst, "w", libver="latest") as out:
        for key, value in f.attrs.items():
            out.attrs[key] = value
        f.visititems(copy)


def main(out: Path) -> None:
    plan = tiny_p1_plan()
    assert plan.twin is not None
    station = SimStation(plan.twin)
    raw = out.with_suffix(".raw.h5")
    summary = run_plan(plan, station, raw, overwrite=True,
                       options=RunOptions(tick_s=1.0, truth=station.truth, min_free_bytes=0))
    if summary.status != "done":
        raise SystemExit(f"run ended {summary.status}: {summary.reason}")
    compact(raw, out)
    raw.unlink()
    print(f"{out}: {out.stat().st_size} bytes, {summary.steps_done} steps done")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "tests/data/p1_v1.h5"))
