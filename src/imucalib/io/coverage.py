"""Whether a Recording's committed samples cover the valid window of each ``done`` step.

Contents
--------
:func:`step_coverage_problem`
    Why one step's committed samples do not cover its valid window (or ``None``).
:func:`uncovered_done_steps`
    Every ``done`` step that claims more data than the file holds, with the reason.

A step is ``done`` only when every IMU stream holds its samples up to the end of the valid
window (the runner waits for samples in transit, then commits; see ``docs/reliability.md``).
Files written before that rule, or damaged later, can still break it; these functions find such
steps so that ``imucalib run --resume`` re-runs them and analysis refuses them.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping

import numpy as np

from imucalib.io.reader import Recording, StepRecord, StreamInfo

__all__ = ["EDGE_PERIODS", "WINDOW_STEP_KINDS", "step_coverage_problem", "uncovered_done_steps"]

#: Step kinds that end ``done`` with a valid window (a warm-up and an operator check have none).
WINDOW_STEP_KINDS = frozenset({"position", "rate", "static", "centrifuge", "soak"})

#: Sample periods within which a stream must hold a sample at each end of a valid window.
EDGE_PERIODS = 5.0
_DEFAULT_PERIOD_S = 0.01  # when an IMU's sample rate is unknown [s]


def _sample_periods_s(rec: Recording) -> dict[str, float]:
    """Nominal sample period of each IMU from ``imu_identity_json`` (absent: not known). [s]"""
    meta: Mapping[str, object] = rec.metadata
    raw = meta.get("imu_identity_json")
    ident = raw if isinstance(raw, dict) else {}
    if isinstance(raw, str):
        try:
            ident = json.loads(raw)
        except ValueError:
            ident = {}
    out: dict[str, float] = {}
    for name, info in ident.items():
        rate = info.get("sample_rate_hz") if isinstance(info, dict) else None
        if isinstance(rate, int | float) and math.isfinite(rate) and rate > 0:
            out[str(name)] = 1.0 / float(rate)
    return out


def step_coverage_problem(rec: Recording, step: StepRecord, imu_streams: list[StreamInfo],
                          periods_s: Mapping[str, float]) -> str | None:
    """Say why a ``done`` step's committed IMU samples do not cover its valid window.

    Each IMU stream must hold committed samples within :data:`EDGE_PERIODS` sample periods of
    both ends of the window. A window cut short by a crash always fails this at its end: the
    stream's time base only grows, so samples lost there can never be appended later (a resumed
    run continues after them).

    Parameters
    ----------
    rec : Recording
        The open Recording.
    step : StepRecord
        The step (only ``done`` steps of :data:`WINDOW_STEP_KINDS` are judged).
    imu_streams : list of StreamInfo
        The IMU streams, with their committed extents.
    periods_s : mapping of str to float
        Nominal sample period per IMU. [s]

    Returns
    -------
    str or None
        The reason, naming the stream and both times; ``None`` when covered.
    """
    if step.status != "done" or step.kind not in WINDOW_STEP_KINDS:
        return None
    if not step.has_valid_window:
        return f"step {step.index} ({step.label}) is done but has no valid window"
    t0, t1 = step.valid_start_s, step.valid_end_s
    for info in imu_streams:
        edge = EDGE_PERIODS * periods_s.get(info.unit, _DEFAULT_PERIOD_S)
        edge = min(edge, 0.5 * (t1 - t0)) if t1 > t0 else edge
        where = f"step {step.index} ({step.label}): stream {info.name}"
        if info.n_samples == 0:
            return f"{where} holds no committed samples; its valid window is {t0:.3f}–{t1:.3f} s"
        i0, i1 = rec.row_range(info.device, info.unit, t1 - edge, t1)
        if i1 <= i0:
            n_in = int(np.subtract(*rec.row_range(info.device, info.unit, t0, t1)[::-1]))
            expected = (t1 - t0) / periods_s.get(info.unit, _DEFAULT_PERIOD_S)
            return (f"{where}: no committed sample in the last {edge:.3g} s of the valid window "
                    f"{t0:.3f}–{t1:.3f} s ({n_in} of about {expected:.0f} samples are in the "
                    "file)")
        i0, i1 = rec.row_range(info.device, info.unit, t0, t0 + edge)
        if i1 <= i0:
            return (f"{where}: no committed sample within {edge:.3g} s of the start of the valid "
                    f"window ({t0:.3f} s)")
    return None


def uncovered_done_steps(rec: Recording) -> dict[int, str]:
    """Return ``{step index: reason}`` for every ``done`` step its samples do not cover.

    Parameters
    ----------
    rec : Recording
        An open Recording.
    """
    imus = [s for s in rec.streams if s.device == "imu"]
    periods = _sample_periods_s(rec)
    out: dict[int, str] = {}
    for step in rec.steps:
        reason = step_coverage_problem(rec, step, imus, periods)
        if reason is not None:
            out[step.index] = reason
    return out
