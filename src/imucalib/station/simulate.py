"""Simulate a twin scenario: its plan run by the station runner on the simulated station.

``imucalib simulate`` and :func:`simulate_scenario` are a station run like any other: the
scenario's steps become a plan (:meth:`~imucalib.sim.scenario.Scenario.to_plan`), its equipment a
:class:`~imucalib.station.sim.SimStation`, and :func:`~imucalib.station.runner.run_plan` executes
the plan with the one set of settling rules, valid windows, guards and stream layouts. The
Recording grows as the virtual clock passes, so a killed run keeps what was flushed.

Contents
--------
:func:`simulate_scenario`
    Scenario → Recording file; returns a :class:`SimulationSummary`.
:func:`estimate_scenario_recording`
    The size of that Recording before it runs (:mod:`imucalib.plan.budget`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from pydantic import ValidationError

from imucalib.errors import ConfigurationError
from imucalib.io.opening import open_recording
from imucalib.io.reader import StepRecord
from imucalib.plan.bounds import format_validation_error
from imucalib.plan.budget import (
    RecordingEstimate,
    StationFacts,
    estimate_plan_recording,
    plan_run_duration_s,
)
from imucalib.plan.schema import Plan
from imucalib.sim.scenario import Scenario
from imucalib.station.runner import run_plan
from imucalib.station.session import RunOptions, RunStatus
from imucalib.station.sim import SimStation

__all__ = ["SIMULATE_TICK_S", "ProgressCallback", "SimulationSummary",
           "estimate_scenario_recording", "scenario_station_and_plan", "simulate_scenario"]

#: Station time between acquisitions and guard checks of a simulated run: 2 s, as
#: ``imucalib run --station sim`` (0.5 s on equipment); the twin's cost is mostly per generated
#: block. While nothing is decided (a dwell, a record of fixed length) the ticks are the
#: scenario's ``chunk_s``. [s]
SIMULATE_TICK_S = 2.0

ProgressCallback = Callable[[float, float], None]


@dataclass(frozen=True)
class SimulationSummary:
    """What :func:`simulate_scenario` wrote.

    Attributes
    ----------
    path : Path
        The Recording.
    scenario : str
        The scenario's name.
    steps : tuple of StepRecord
        The step rows of the Recording.
    virtual_duration_s : float
        Station time from the first to the last acquisition. [s]
    wall_time_s : float
        Wall-clock time of the whole simulation. [s]
    samples : dict of str to int
        Rows per stream, ``"device/unit"``.
    status : str
        ``"done"``, or ``"aborted"`` with `reason` (a guard that stopped the run).
    """

    path: Path
    scenario: str
    steps: tuple[StepRecord, ...]
    virtual_duration_s: float
    wall_time_s: float
    samples: dict[str, int] = field(default_factory=dict)
    status: str = "done"
    reason: str = ""

    def describe(self) -> str:
        """Return a short human-readable account (for the CLI)."""
        rate = self.virtual_duration_s / self.wall_time_s if self.wall_time_s > 0 else math.inf
        lines = [f"wrote {self.path}: scenario {self.scenario!r}, {len(self.steps)} steps, "
                 f"{self.virtual_duration_s:,.1f} s of virtual time in {self.wall_time_s:.1f} s "
                 f"({rate:,.0f}× real time)"]
        if self.status != "done":
            lines.append(f"  run {self.status}: {self.reason}")
        lines += [f"  {name}: {n:,} samples" for name, n in self.samples.items()]
        return "\n".join(lines)


def scenario_station_and_plan(sc: Scenario) -> tuple[SimStation, Plan]:
    """Return the simulated station of `sc`'s equipment and the plan of its steps.

    The plan's limits are the twin's own (:meth:`SimStation.plan_limits`), and its position
    tolerance is widened to what the twin's encoders can show
    (:meth:`SimStation.position_tolerance_arcsec`; 5″ stays for a high-grade table).

    Raises
    ------
    LimitExceededError
        If a step asks a device of the twin for more than its limits.
    ConfigurationError
        If the steps do not make a valid plan on that station.
    """
    station = SimStation(sc.equipment, truth_streams=sc.store_truth_streams)
    station.check_steps(sc.steps)
    try:
        plan = sc.to_plan(station.plan_limits())
    except ValidationError as exc:
        raise ConfigurationError(format_validation_error(exc, repr(sc.name))) from exc
    reachable = station.position_tolerance_arcsec()
    if reachable > plan.guards.position_tolerance_arcsec:
        guards = plan.guards.model_copy(update={"position_tolerance_arcsec": reachable})
        plan = plan.model_copy(update={"guards": guards})
    return station, plan


def estimate_scenario_recording(sc: Scenario) -> RecordingEstimate:
    """Return the estimated recording ``imucalib simulate`` writes for `sc` (its plan's).

    Raises
    ------
    LimitExceededError, ConfigurationError
        As :func:`scenario_station_and_plan`.
    """
    _, plan = scenario_station_and_plan(sc)
    return estimate_plan_recording(plan, StationFacts.of_twin(sc))


def simulate_scenario(sc: Scenario, path: str | Path, *,
                      progress: ProgressCallback | None = None, overwrite: bool = False,
                      flush_interval_s: float = 1.0,
                      tick_s: float = SIMULATE_TICK_S) -> SimulationSummary:
    """Run scenario `sc` on the twin and write its Recording to `path`.

    Parameters
    ----------
    sc : Scenario
        What to simulate.
    path : str or Path
        The Recording to create.
    progress : callable, optional
        ``progress(done_s, total_s)`` as the run goes, in virtual seconds from its start
        (`total_s` is the plan's estimated duration until the run ends, then its end).
    overwrite : bool
        Replace an existing file.
    flush_interval_s : float
        Wall-clock interval between flushes of the writer. [s]
    tick_s : float
        Station time between acquisitions and guard checks (``sc.chunk_s`` while nothing is
        decided: ``RunOptions.idle_tick_s``). [s]

    Returns
    -------
    SimulationSummary

    Raises
    ------
    LimitExceededError
        If a step asks a device of the twin for more than its limits (before anything is
        written).
    ConfigurationError
        If the steps do not fit the station the equipment describes.
    RecordingError
        If the file exists (without `overwrite`) or cannot be written.
    """
    wall0 = time.perf_counter()
    station, plan = scenario_station_and_plan(sc)
    start_s = station.clock.now_s()
    total_s = plan_run_duration_s(plan, StationFacts.of_twin(sc))
    on_status = None
    if progress is not None:
        report = progress

        def on_status(status: RunStatus) -> None:
            done = status.time_s - start_s
            report(done, max(total_s, done))

    options = RunOptions(tick_s=tick_s, idle_tick_s=max(sc.chunk_s, tick_s),
                         truth=station.truth, flush_interval_s=flush_interval_s,
                         on_status=on_status)
    run = run_plan(plan, station, path, options=options, overwrite=overwrite,
                   truth_source=station,
                   extra_metadata={"scenario_json": sc.model_dump_json()})
    duration_s = run.end_s - start_s
    if progress is not None:
        progress(duration_s, duration_s)
    with open_recording(path) as rec:
        steps = tuple(rec.steps)
        samples = {f"{info.device}/{info.unit}": info.n_samples for info in rec.streams}
    return SimulationSummary(path=Path(path), scenario=sc.name, steps=steps,
                             virtual_duration_s=duration_s,
                             wall_time_s=time.perf_counter() - wall0, samples=samples,
                             status=run.status, reason=run.reason)
