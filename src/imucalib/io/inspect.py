"""Summarise a Recording for people: streams, units, steps, durations, sample rates, gaps.

Contents
--------
:func:`summarize_recording`
    Scan a Recording in bounded memory and return a :class:`RecordingSummary`.
:class:`RecordingSummary`, :class:`StreamSummary`
    The result; :meth:`RecordingSummary.render` draws it with rich.

Gaps are counted two ways: from the sample counter where a stream has one (a jump other than +1,
modulo the counter's wrap, is a gap of that many samples), and from time (an interval longer than
the median interval by more than max(half the median, six robust standard deviations of the
intervals), so that receive-time jitter is not taken for gaps; median and spread come from the
first chunk).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from imucalib.conventions import COUNTER_COLUMN, TIME_COLUMN
from imucalib.io.events import EventKind
from imucalib.io.opening import open_recording

if TYPE_CHECKING:
    from rich.console import Console

__all__ = ["RecordingSummary", "StreamSummary", "summarize_recording"]


@dataclass(frozen=True)
class StreamSummary:
    """What one stream holds."""

    device: str
    unit: str
    columns: dict[str, str]  # name -> unit
    n_samples: int
    t_first_s: float
    t_last_s: float
    median_interval_s: float
    time_gaps: int
    counter_gaps: int | None
    missing_samples: int | None

    @property
    def duration_s(self) -> float:
        """Time from the first to the last sample. [s]"""
        return self.t_last_s - self.t_first_s if self.n_samples else 0.0

    @property
    def sample_rate_hz(self) -> float:
        """Sample rate [Hz].

        Counted samples (delivered + missing) over the duration when the stream has a counter
        (robust to receive-time jitter), else one over the median interval.
        """
        if self.missing_samples is not None and self.n_samples > 1 and self.duration_s > 0:
            return (self.n_samples - 1 + self.missing_samples) / self.duration_s
        return 1.0 / self.median_interval_s if self.median_interval_s > 0 else float("nan")


@dataclass(frozen=True)
class RecordingSummary:
    """What a Recording holds."""

    path: Path
    format_version: int
    metadata: dict[str, Any]
    streams: list[StreamSummary]
    steps: list[Any]
    n_events: int
    was_open_for_write: bool
    #: (time [s], message) of each logged fixture remount (P2's operator checks): the station
    #: events of kind ``remount`` (:mod:`imucalib.io.events`).
    remounts: tuple[tuple[float, str], ...] = ()
    #: (time [s], message) of each logged unit swap and centrifuge load change (P3): the
    #: station events of kinds ``swap`` and ``load``, in the order logged.
    swaps_and_loads: tuple[tuple[float, str], ...] = ()

    def render(self, console: Console) -> None:
        """Print the summary as rich tables."""
        from rich.markup import escape
        from rich.table import Table

        console.print(f"[bold]{escape(str(self.path))}[/]  format v{self.format_version}")
        if self.was_open_for_write:
            console.print(
                f"  [yellow]still marked open for writing: its writer crashed, was killed while "
                f"closing, or is still running. `imucalib run --resume {escape(str(self.path))}` "
                "finishes a station run (it recovers and closes the file first); `imucalib "
                f"recover {escape(str(self.path))}` copies what was flushed into a cleanly "
                "closed file.[/]", highlight=False, soft_wrap=True)
        for key in ("created_utc", "software_version", "scenario_name"):
            if key in self.metadata:
                console.print(f"  {key}: {self.metadata[key]}")
        # Units in brackets are text, not markup. On a terminal the tables fit its width (the
        # stream names are never cut); without one (a pipe, a file) they are printed at their
        # natural width, so nothing is cut or folded at 80 columns.
        table = Table(title="Streams")
        longest = max((len(s.device) + 1 + len(s.unit) for s in self.streams), default=6)
        table.add_column("stream", no_wrap=True, min_width=longest)
        for header in ("samples", "duration [s]", "rate [Hz]", "time gaps",
                       "counter gaps (missing)", "columns [unit]"):
            table.add_column(escape(header))
        for s in self.streams:
            cols = ", ".join(f"{k} [{u}]" for k, u in s.columns.items() if k != TIME_COLUMN)
            cg = "—" if s.counter_gaps is None else f"{s.counter_gaps} ({s.missing_samples})"
            table.add_row(escape(f"{s.device}/{s.unit}"), f"{s.n_samples:,}",
                          f"{s.duration_s:,.3f}", f"{s.sample_rate_hz:,.3f}", str(s.time_gaps),
                          cg, escape(cols))
        _print_whole(console, table)
        steps = Table(title="Steps")
        for header in ("#", "kind", "label", "role", "tags", "valid window [s]", "status"):
            steps.add_column(escape(header))
        for st in self.steps:
            tags = ", ".join(st.tags)
            if st.units:
                tags += (", " if tags else "") + "units: " + " ".join(st.units)
            steps.add_row(str(st.index), st.kind, escape(st.label), escape(st.role or "—"),
                          escape(tags or "—"),
                          f"{st.valid_start_s:,.3f} – {st.valid_end_s:,.3f}", st.status)
        _print_whole(console, steps)
        for time_s, message in self.remounts:
            console.print(f"  {time_s:,.3f} s: {escape(message)}", highlight=False)
        for time_s, message in self.swaps_and_loads:
            console.print(f"  {time_s:,.3f} s: {escape(message)}", highlight=False)
        console.print(f"{self.n_events} logged event(s)"
                      + (f", {len(self.remounts)} fixture remount(s) above" if self.remounts
                         else "")
                      + (f", {len(self.swaps_and_loads)} unit swap(s) or load change(s) above"
                         if self.swaps_and_loads else ""))


def _print_whole(console: Console, table: Any) -> None:
    """Print `table` to fit a terminal, or at its natural width when `console` is not one."""
    from rich.measure import Measurement
    from rich.segment import Segments

    if console.is_terminal:
        console.print(table)
        return
    natural = Measurement.get(console, console.options.update_width(10_000), table).maximum
    width = max(console.width, natural)
    console.print(Segments(console.render(table, console.options.update(width=width))),
                  crop=False)


def _counter_steps(c: np.ndarray) -> np.ndarray:
    """Counter increments, unwrapping a wrap at the next power of two above the previous value."""
    dc = np.diff(c)
    wrapped = dc < 0
    if np.any(wrapped):
        prev = c[:-1][wrapped]
        modulus = np.left_shift(1, np.ceil(np.log2(prev + 1.0)).astype(np.int64))
        dc[wrapped] += modulus
    return dc


def _scan_stream(rec: Any, info: Any, chunk_samples: int) -> StreamSummary:
    """One bounded-memory pass; the median interval comes from the first chunk."""
    has_counter = COUNTER_COLUMN in info.columns
    wanted = [TIME_COLUMN] + ([COUNTER_COLUMN] if has_counter else [])
    median = threshold = 0.0
    time_gaps = counter_gaps = missing = 0
    last_t: float | None = None
    last_c: int | None = None
    for chunk in rec.iter_stream(info.device, info.unit, chunk_samples=chunk_samples,
                                 columns=wanted):
        t = np.asarray(chunk.time_s, dtype=np.float64)
        if t.size == 0:
            continue
        if last_t is not None:
            t = np.concatenate(([last_t], t))
        dt = np.diff(t)
        if median == 0.0 and dt.size:
            median = float(np.median(dt))
            sigma = 1.4826 * float(np.median(np.abs(dt - median)))
            threshold = median + max(0.5 * median, 6.0 * sigma)
        if median > 0:
            time_gaps += int(np.count_nonzero(dt > threshold))
        last_t = float(t[-1])
        if has_counter:
            c = np.asarray(chunk.columns[COUNTER_COLUMN], dtype=np.int64)
            if last_c is not None:
                c = np.concatenate(([last_c], c))
            dc = _counter_steps(c)
            jumps = dc != 1
            counter_gaps += int(np.count_nonzero(jumps))
            missing += int(np.sum(np.clip(dc[jumps] - 1, 0, None)))
            last_c = int(c[-1])
    return StreamSummary(
        device=info.device,
        unit=info.unit,
        columns={k: v.unit for k, v in info.columns.items()},
        n_samples=int(info.n_samples),
        t_first_s=float(info.t_first_s) if info.n_samples else float("nan"),
        t_last_s=float(info.t_last_s) if info.n_samples else float("nan"),
        median_interval_s=median,
        time_gaps=time_gaps,
        counter_gaps=counter_gaps if has_counter else None,
        missing_samples=missing if has_counter else None,
    )


def summarize_recording(path: str | Path, *, chunk_samples: int = 1 << 18) -> RecordingSummary:
    """Scan a Recording and summarise it, reading one chunk at a time.

    Parameters
    ----------
    path : str or Path
        The Recording.
    chunk_samples : int
        Rows read at a time (bounds memory).

    Returns
    -------
    RecordingSummary
        Streams with sample counts, rates and gaps; steps; event count.

    Raises
    ------
    RecordingFormatError, RecordingCorruptError
        From :func:`~imucalib.io.opening.open_recording`.
    """
    with open_recording(path) as rec:
        streams = [_scan_stream(rec, info, chunk_samples) for info in rec.streams]
        log = rec.log
        events = [(float(e.time_s), str(e.message), e.kind) for e in log]
        return RecordingSummary(
            path=Path(path),
            format_version=int(rec.format_version),
            metadata=dict(rec.metadata),
            streams=streams,
            steps=list(rec.steps),
            n_events=len(log),
            was_open_for_write=bool(getattr(rec, "was_open_for_write", False)),
            remounts=tuple((t, m) for t, m, k in events if k is EventKind.REMOUNT),
            swaps_and_loads=tuple((t, m) for t, m, k in events
                                  if k in (EventKind.SWAP, EventKind.LOAD)),
        )
