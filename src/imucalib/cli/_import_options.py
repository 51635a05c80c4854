"""The import options of every command that reads a log, declared once.

The commands ``segments``, ``import``, ``allan``, ``calibrate`` and ``apply`` share them.
One definition of each option (:data:`ImportFile`, :data:`ColumnMap`, …), one decorator,
:func:`with_import_options`, that adds them all to a command, and one function,
:func:`import_spec_from_options`, that turns them (over an ``--import`` TOML file) into the
:class:`~imucalib.io.import_spec.ImportSpec` that :func:`~imucalib.io.import_spec.read_imu_table`
reads with (docs/import.md, "Import specification").
"""

from __future__ import annotations

import functools
import inspect
import typing
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

import typer

__all__ = ["IMPORT_OPTIONS", "AccelFile", "AccelOffset", "AccelScale", "AccelUnit", "ColumnMap",
           "Delimiter", "GyroOffset", "GyroScale", "GyroUnit", "ImportFile", "ImportOptions",
           "SampleRate", "SkipRows", "TimeColumn", "TimeUnit", "Units",
           "import_spec_from_options", "with_import_options"]

ImportFile = Annotated[Path | None, typer.Option(
    "--import", help="Import specification (TOML): columns, units, scale, offset, time column "
                     "or sample rate, delimiter, header rows (docs/import.md). The options below "
                     "override it.")]
ColumnMap = Annotated[str | None, typer.Option(
    "--column-map", help="Which column is what: gx=GyroX,ax=AccX,t=Time,… (or "
                         "GyroX=gyro_x_rps,…).")]
Units = Annotated[str | None, typer.Option(
    "--units", help="Units of single columns: gx=deg/s,t=ms,…")]
GyroUnit = Annotated[str | None, typer.Option(
    "--gyro-unit", help="Unit of every gyro column: deg/s, rad/s, deg/h or counts.")]
AccelUnit = Annotated[str | None, typer.Option(
    "--accel-unit", help="Unit of every accelerometer column: g, m/s^2, mg or counts.")]
GyroScale = Annotated[float | None, typer.Option(
    "--gyro-scale", help="Gyro counts per unit (per °/s with --gyro-unit counts).")]
AccelScale = Annotated[float | None, typer.Option(
    "--accel-scale", help="Accelerometer counts per unit (per g with --accel-unit counts).")]
GyroOffset = Annotated[float | None, typer.Option(
    "--gyro-offset", help="Gyro offset subtracted before the scale [counts].")]
AccelOffset = Annotated[float | None, typer.Option(
    "--accel-offset", help="Accelerometer offset subtracted before the scale [counts].")]
TimeColumn = Annotated[str | None, typer.Option(
    "--time-column", help="Name of the time column.")]
TimeUnit = Annotated[str | None, typer.Option(
    "--time-unit", help="Unit of the time column: s, ms, us or ns.")]
SampleRate = Annotated[float | None, typer.Option(
    "--sample-rate-hz", "--sample-rate",
    help="Sample rate [Hz] when there is no time column (or it is a sample counter).")]
Delimiter = Annotated[str | None, typer.Option(
    "--delimiter", help="Field separator: ',', ';', 'tab' or 'whitespace' (default ',').")]
SkipRows = Annotated[int | None, typer.Option(
    "--skip-rows", help="Lines before the header line (a vendor's preamble).")]
AccelFile = Annotated[Path | None, typer.Option(
    "--accel-file", help="imu_tk's accelerometer file (time x y z); DATA is then its gyro "
                         "file.")]


def import_spec_from_options(import_file: Path | None = None, *, column_map: str | None = None,
                             units: str | None = None, **options: Any) -> Any:
    """Return the :class:`~imucalib.io.import_spec.ImportSpec` of the import options.

    `import_file` is read first (:func:`~imucalib.io.import_spec.load_import_spec`); every
    option given overrides it. `options` are the other fields of the spec, by name.

    Raises
    ------
    InvalidInputError
        A bad ``--column-map`` / ``--units`` item or import file.
    """
    from imucalib.io.csv_layouts import parse_pairs
    from imucalib.io.import_spec import ImportSpec, load_import_spec

    base = load_import_spec(import_file) if import_file is not None else ImportSpec()
    return base.merged(column_map=parse_pairs(column_map, "--column-map") or None,
                       units=parse_pairs(units, "--units") or None, **options)


#: The import options by parameter name, in the order the commands list them.
IMPORT_OPTIONS: dict[str, Any] = {
    "import_file": ImportFile, "column_map": ColumnMap, "units": Units,
    "gyro_unit": GyroUnit, "accel_unit": AccelUnit, "gyro_scale": GyroScale,
    "accel_scale": AccelScale, "gyro_offset": GyroOffset, "accel_offset": AccelOffset,
    "time_column": TimeColumn, "time_unit": TimeUnit, "sample_rate_hz": SampleRate,
    "delimiter": Delimiter, "skip_rows": SkipRows, "accel_file": AccelFile,
}


class ImportOptions:
    """The import options a command was given; :meth:`spec` reads them (it may raise)."""

    def __init__(self, given: dict[str, Any]) -> None:
        self.given = given

    def any(self) -> bool:
        """Whether any import option was given."""
        return any(v is not None for v in self.given.values())

    def spec(self) -> Any:
        """Return the ImportSpec (:func:`import_spec_from_options`).

        Raises
        ------
        InvalidInputError
            A bad ``--column-map`` / ``--units`` item or import file.
        """
        opts = dict(self.given)
        return import_spec_from_options(opts.pop("import_file"), **opts)


def with_import_options(command: Callable[..., Any]) -> Callable[..., Any]:
    """Add the import options to a command: it receives them as ``import_options``.

    The command declares a parameter ``import_options: ImportOptions`` (last); the decorator
    replaces it, in the signature typer reads, by the options of :data:`IMPORT_OPTIONS`, so
    every command that reads a log has the same options, declared once.
    """
    sig = inspect.signature(command)
    kept = [p for name, p in sig.parameters.items() if name != "import_options"]
    added = [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=None,
                               annotation=annotation)
             for name, annotation in IMPORT_OPTIONS.items()]

    @functools.wraps(command)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        given = {name: kwargs.pop(name, None) for name in IMPORT_OPTIONS}
        return command(*args, import_options=ImportOptions(given), **kwargs)

    hints = typing.get_type_hints(command, include_extras=True)
    hints.pop("import_options", None)
    wrapper.__annotations__ = {**hints, **IMPORT_OPTIONS}
    wrapper.__signature__ = sig.replace(  # type: ignore[attr-defined]
        parameters=[p.replace(annotation=hints.get(p.name, p.annotation)) for p in kept]
        + added)
    return wrapper
