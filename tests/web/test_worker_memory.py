"""The run worker's own memory stays bounded over a long run (issue 31; docs/web.md, "Measured").

A P2 twin run (two units, the chamber, four temperature points: some 2800 s of station time,
every kind of step the live view follows) is run in-process as the worker runs it: the runner
of ``imucalib run`` on a tapped station, :class:`~imucalib.web.run_reporter.RunReporter` as its
status callback. After every tick the test measures what the worker's own objects retain
(the reporter, its :class:`~imucalib.web.live_follow.LiveFollower`, the
:class:`~imucalib.web.run_tap.SignalTap` with its binned moments and rate holds): the bytes of
every container and array they reach, an array counted with the whole buffer it keeps alive
(a view of a block keeps the block). It must not grow with the run: the most retained over the
second half of the run is within a small margin of the most over the first half, and every
buffer stays within its design bound. (Measured every tenth tick: the walk is the test's cost.)
"""

from __future__ import annotations

import dataclasses
import sys
from collections import deque
from pathlib import Path
from typing import Any

import numpy as np

from imucalib.plan.schema import Plan
from imucalib.station.operator import OperatorAnswer
from imucalib.station.session import RunStatus
from imucalib.web.live_follow import MAX_TICKS
from imucalib.web.rate_hold import MAX_ROWS
from imucalib.web.run_files import LOG_TAIL, RunFiles
from imucalib.web.run_reporter import RunReporter
from imucalib.web.run_tap import SignalTap
from imucalib.web.window_stats import MAX_BINS

#: What the worker's objects may retain at most over this run (the design bounds of its
#: buffers at the test's rates are far below; samples kept per tick would be tens of MiB). [B]
RETAINED_BOUND_BYTES = 8 << 20
#: Slack of the second half's peak over the first half's (a soak's rows, a step's ticks). [B]
GROWTH_SLACK_BYTES = 256 << 10


def _root_array(a: np.ndarray) -> np.ndarray:
    while isinstance(a.base, np.ndarray):
        a = a.base
    return a


def retained_bytes(root: object, skip: tuple[type, ...]) -> int:
    """Return the bytes reachable from `root` through containers and imucalib.web objects.

    Containers (dict, list, tuple, deque, set), objects of :mod:`imucalib.web` (their
    ``__dict__``) and dataclasses are walked; an array counts its root buffer's ``nbytes``
    once; other objects count :func:`sys.getsizeof`. Objects of a type in `skip` (the plan,
    the run's files) and callables are not walked.
    """
    seen: set[int] = set()
    total = 0
    stack: list[object] = [root]
    while stack:
        obj = stack.pop()
        if isinstance(obj, np.ndarray):
            obj = _root_array(obj)
        if id(obj) in seen or isinstance(obj, skip) or callable(obj):
            continue
        seen.add(id(obj))
        if isinstance(obj, np.ndarray):
            total += obj.nbytes + sys.getsizeof(np.empty(0))
            continue
        total += sys.getsizeof(obj)
        if isinstance(obj, dict):
            stack.extend(obj.keys())
            stack.extend(obj.values())
        elif isinstance(obj, list | tuple | deque | set | frozenset):
            stack.extend(obj)
        elif dataclasses.is_dataclass(obj) or type(obj).__module__.startswith("imucalib.web"):
            stack.extend(vars(obj).values())
    return total


class _Operator:
    """Answers every operator check at once, through the reporter's prompt (as the page)."""

    def __init__(self, rep: RunReporter) -> None:
        self.rep = rep

    def confirm(self, item: str) -> OperatorAnswer:
        self.rep.open_prompt(item)
        self.rep.close_prompt(True, "alice")
        return OperatorAnswer(True, "alice", note="(test)")


def test_the_worker_s_own_objects_stay_bounded_over_a_long_run(tmp_path: Path) -> None:
    from imucalib.drivers.station_spec import make_station
    from imucalib.procedures.p2.plan import generate_p2_plan
    from imucalib.station.runner import RunOptions, run_plan
    from imucalib.web.run_tap import tap_station

    plan = generate_p2_plan(n_imus=2, temperatures_degc=(25.0, 30.0, 35.0, 40.0),
                            held_out_degc=(), rate_dps=60.0, revolutions=1, static_s=10.0,
                            settle_s=5.0, ramp_degc_per_min=10.0, stable_for_s=30.0,
                            resoak_s=0.0, sample_rate_hz=200.0, name="memory-p2")
    files = RunFiles(tmp_path / "20261129T120000Z-abcdef")
    files.folder.mkdir()
    tap = SignalTap()
    rep = RunReporter(files, plan, "alice", tap)
    samples: list[tuple[float, int]] = []
    lengths: list[dict[str, int]] = []
    follow = rep.on_status

    def on_status(status: RunStatus) -> None:
        follow(status)
        if len(lengths) % 10 == 0:                     # every 10th tick: the walk costs
            samples.append((status.time_s, retained_bytes(rep, (Plan, RunFiles))))
        lengths.append({
            "ticks": len(rep.live.ticks), "soak_rows": len(rep.live.soak_rows),
            "log_tail": len(rep.log_tail),
            "bins": max((len(m) for m in tap.moments.values()), default=0),
            "rate_rows": max((h._rows for h in tap.rate_holds.values()), default=0)})

    bare, station_toml = make_station("sim", plan)
    options = RunOptions(tick_s=2.0, operator=_Operator(rep), on_status=on_status,
                         on_log=rep.on_recording_log)
    options.station_toml = station_toml
    options.truth = getattr(bare, "truth", None)
    summary = run_plan(plan, tap_station(bare, tap), tmp_path / "run.h5", options=options)
    samples.append((rep.time_s, retained_bytes(rep, (Plan, RunFiles))))
    rep.close()
    assert summary.status == "done"
    assert rep.done_seen == len(plan.steps)
    windows = files.events.read_text(encoding="utf-8").count('"type": "window"')
    assert windows >= 20                               # the statics and rates were followed

    end_s = samples[-1][0]
    assert end_s > 2000.0                               # a long run: every point's soak
    first = max(b for t, b in samples if t <= end_s / 2)
    second = max(b for t, b in samples if t > end_s / 2)
    assert second <= first + GROWTH_SLACK_BYTES, (first, second)
    assert max(b for _t, b in samples) <= RETAINED_BOUND_BYTES
    worst = {k: max(row[k] for row in lengths) for k in lengths[0]}
    assert worst["ticks"] <= MAX_TICKS and worst["soak_rows"] <= MAX_TICKS
    assert worst["log_tail"] <= LOG_TAIL
    assert worst["bins"] <= MAX_BINS and worst["rate_rows"] <= MAX_ROWS


def test_the_measure_counts_what_a_view_keeps_alive() -> None:
    block = np.zeros(10_000)
    kept: dict[str, Any] = {"last": block[-1:]}
    assert retained_bytes(kept, ()) >= block.nbytes
    assert retained_bytes({"last": block[-1:].copy()}, ()) < 1_000
