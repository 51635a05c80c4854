"""Commands of the digital twin: ``simulate`` and ``scenarios``."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from imucalib.cli._app import app, console, fail
from imucalib.cli._progress import QUIET_HELP, progress_bar
from imucalib.errors import CalibrationError, ConfigurationError

__all__ = ["scenarios", "simulate"]


@app.command()
def scenarios() -> None:
    """List the built-in twin scenarios."""
    from imucalib.sim.scenario import BUILTIN_SCENARIOS

    table = Table("name", "steps", "description")
    for name, make in BUILTIN_SCENARIOS.items():
        sc = make()
        table.add_row(name, str(len(sc.steps)), sc.description)
    console.print(table)


@app.command()
def simulate(
    scenario: Annotated[str, typer.Argument(help="Built-in scenario name or a TOML file.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Recording to write (.h5).")],
    seed: Annotated[int | None, typer.Option(help="Override the scenario's seed.")] = None,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing file.")] = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help=QUIET_HELP)] = False,
) -> None:
    """Run a scenario on the digital twin and write its Recording.

    The scenario's steps run as a plan through the station runner on the simulated station
    (the same settling, valid windows and guards as `imucalib run --station sim`). A scenario
    file in the former format is read with a note per renamed field. The recording's size is
    estimated first; a scenario whose file would not fit in the free
    space of the output's filesystem is refused before anything is written.
    """
    from pydantic import ValidationError

    from imucalib.plan.bounds import format_validation_error
    from imucalib.plan.budget import check_free_space
    from imucalib.sim.scenario import Scenario, ScenarioFormatWarning, load_scenario
    from imucalib.station.simulate import estimate_scenario_recording, simulate_scenario

    try:
        with warnings.catch_warnings(record=True) as notes:
            warnings.simplefilter("always", ScenarioFormatWarning)
            sc = load_scenario(scenario)
        for note in notes:
            console.print(f"note: {note.message}", style="yellow", highlight=False,
                          soft_wrap=True)
        if seed is not None:
            sc = Scenario.model_validate({**sc.model_dump(), "seed": seed})
        estimate = estimate_scenario_recording(sc)
        replaced = out.stat().st_size if overwrite and out.is_file() else 0
        check_free_space(estimate.total_bytes, out, replaced_bytes=replaced,
                         what=f"the recording of scenario {sc.name!r}")
        with progress_bar(sc.name, quiet=quiet) as update:

            def on_progress(done_s: float, total_s: float) -> None:
                update(done_s / total_s if total_s > 0 else 1.0,
                       f"{done_s:,.0f} / {total_s:,.0f} s virtual")

            summary = simulate_scenario(sc, out, progress=on_progress, overwrite=overwrite)
    except ValidationError as exc:  # --seed outside the scenario's bounds
        raise fail(ConfigurationError(format_validation_error(exc, scenario))) from exc
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(summary.describe(), highlight=False, soft_wrap=True)
