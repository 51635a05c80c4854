"""What a page shows of a supervised run: :class:`RunView`, :class:`StepView`, :class:`PromptView`.

A view is built from the run's ``run.json`` and ``state.json`` (:mod:`imucalib.web.run_files`)
and whether its worker process is alive; :meth:`RunView.to_dict` is its JSON form (the
``snapshot`` event, :mod:`imucalib.web.events`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

__all__ = ["LIVE_STATUSES", "STATUSES", "PromptView", "RunView", "StepView", "build_view"]

#: Every status of a run.
STATUSES = ("starting", "running", "waiting", "aborting", "stopped", "finished", "failed")
#: The statuses of a run whose worker is (still) at work.
LIVE_STATUSES = frozenset({"starting", "running", "waiting", "aborting"})


@dataclass(frozen=True)
class StepView:
    """One plan step: its index, kind, label and state (pending, running, done, failed)."""

    index: int
    kind: str
    label: str
    state: str


@dataclass(frozen=True)
class PromptView:
    """An operator check waiting for its answer.

    ``details`` holds what the check puts in place, when it does (``remount``,
    ``remount_yaw_deg``, ``swap_units``, ``centrifuge_load_kg``), for the page to draw.
    """

    prompt_id: int
    step_index: int
    text: str
    details: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class RunView:
    """A supervised run as a page shows it.

    Attributes
    ----------
    run_id, plan_name, recording_path, operator, started_utc : str
    status : str
        One of :data:`STATUSES`.
    step_index : int
        The current (or last) plan step; -1 before the first.
    n_steps : int
    steps : tuple of StepView
    time_left_s : float
        The plan's least station time left (the current step's rest and the steps after it). [s]
    prompt : PromptView or None
    error : str or None
        Why the run failed or stopped.
    log_tail : tuple of str
        The last lines of the run's log.
    signals : dict
        The latest decimated values: ``time_s``, ``table`` (``angle_deg``, ``rate_dps``),
        ``centrifuge`` (``rate_dps``), ``chamber`` (``setpoint_degc``, ``air_degc``),
        ``imus`` (per unit ``gyro_dps``, ``accel_g``, ``temperature_degc``, ``rate_hz``,
        ``error``), ``guards`` (``recording``, ``trips``, ``last_trip``, device faults).
    station : str
        ``"sim"`` or the station file.
    serials : tuple of str
    resumed : int
        How often the run was resumed.
    records_run_id : int, optional
        The run's id in the records database, once recorded (at its end, as ``imucalib run``
        records it); None before, or when the supervisor does not record.
    """

    run_id: str
    plan_name: str
    status: str
    recording_path: str
    operator: str
    started_utc: str
    step_index: int
    n_steps: int
    steps: tuple[StepView, ...]
    time_left_s: float
    prompt: PromptView | None
    error: str | None
    log_tail: tuple[str, ...]
    signals: dict[str, Any]
    station: str = "sim"
    serials: tuple[str, ...] = ()
    resumed: int = 0
    records_run_id: int | None = None

    def to_dict(self) -> dict[str, Any]:
        """Return the view as JSON-serialisable dict."""
        return dataclasses.asdict(self)


def build_view(config: Mapping[str, Any], state: Mapping[str, Any] | None,
               alive: bool) -> RunView:
    """Return the view of a run from its ``run.json``, its ``state.json`` and its worker's life.

    A run whose state says it is live but whose worker is gone is shown ``failed``: its
    recording was left as the worker left it (``imucalib run --resume`` and
    :meth:`~imucalib.web.supervisor.RunSupervisor.resume` recover it).
    """
    st: Mapping[str, Any] = state or {}
    kinds = config.get("steps") or []
    states = st.get("steps") or ["pending"] * len(kinds)
    steps = tuple(StepView(i, str(k), str(label), str(states[i] if i < len(states) else "pending"))
                  for i, (k, label) in enumerate(kinds))
    status = str(st.get("status") or "starting")
    error = st.get("error")
    if status in LIVE_STATUSES and not alive:
        status = "failed"
        error = error or ("the worker process ended without closing the run; its recording "
                          "can be resumed")
        steps = tuple(dataclasses.replace(s, state="failed") if s.state == "running" else s
                      for s in steps)
    p = st.get("prompt")
    prompt = (PromptView(int(p["prompt_id"]), int(p["step_index"]), str(p["text"]),
                         dict(p.get("details") or {}))
              if isinstance(p, Mapping) and status == "waiting" else None)
    return RunView(
        run_id=str(config["run_id"]), plan_name=str(config.get("plan_name", "")),
        status=status, recording_path=str(config.get("recording", "")),
        operator=str(st.get("operator") or config.get("operator", "")),
        started_utc=str(config.get("started_utc", "")),
        step_index=int(st.get("step_index", -1)), n_steps=len(kinds), steps=steps,
        time_left_s=float(st.get("time_left_s", config.get("least_time_s", 0.0))),
        prompt=prompt, error=str(error) if error else None,
        log_tail=tuple(str(line) for line in st.get("log_tail") or ()),
        signals=dict(st.get("signals") or {}), station=str(config.get("station", "sim")),
        serials=tuple(str(s) for s in config.get("serials") or ()),
        resumed=int(st.get("resumed", 0)),
        records_run_id=int(st["records_run_id"]) if st.get("records_run_id") else None)
