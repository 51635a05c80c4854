"""Step files: what each interval of a log without step records is (docs/import.md).

A step file is a small TOML document that says, for IMU data that came without step records (a
CSV export, a vendor log), which time intervals are measurements, what each one is for in its
procedure (its role ``<procedure>.<purpose>``, :mod:`imucalib.io.step_roles`) and the table state
it was taken at. With it, :func:`imucalib.io.csv_recording.recording_from_csv` turns the data into
a Recording that the procedure analyses as it does a planned run.

Format (version 1)
------------------
::

    format = "imucalib-steps"      # optional; version = 1
    unit = "IMU-0001"              # the IMU's name (default: the data file's stem)
    latitude_deg = 48.137          # the site (the Earth-rate projection needs it)
    heading_deg = 0.0              # table heading, clockwise from north
    table_axes = ["pitch", "roll"] # outer axis first (docs/conventions.md)
    sample_rate_hz = 200.0         # optional: the IMU's rate (default: from the time column)

    [[steps]]
    start_s = 12.0                 # the interval to average, in the data's time base [s]
    end_s = 42.0
    role = "p1.accel-position"     # what it is for: any procedure's role (or "skip")
    label = "z-up"
    tags = ["repetition=1"]
    angles_deg = [0.0, 0.0]        # table angles held, outer axis first [°]

    [[steps]]
    start_s = 100.0
    end_s = 118.0                  # whole revolutions are taken from inside the interval
    role = "p1.gyro-rate"
    axis = "pitch"                 # the turning axis (a name of table_axes, or its index)
    rate_dps = 60.0                # its rate [°/s]
    angles_deg = [0.0, 0.0]        # the angles at start_s [°]

Roles
-----
This module checks a role's grammar only (``<procedure>.<purpose>``, or :data:`SKIP`): which
roles exist is the procedures' fact, checked against the registry where the step file is used
(:func:`imucalib.procedures.registry.check_roles`, run by ``imucalib import`` and ``imucalib
calibrate --steps``; ``imucalib procedures NAME`` lists a procedure's roles). The table state is
generic: an interval that gives ``axis`` and ``rate_dps`` is a turn (kind ``"rate"``), any other a
static interval; when one interval gives ``angles_deg``, every one must (the table stream is
reconstructed from them), and ``latitude_deg`` is then required. Tags (``axis=x``,
``angle=30`` …) are carried to the Recording as the procedure's analysis reads them.

Equipment and specification limits the analysis would otherwise take from a plan may be given
at the top level: ``table_position_accuracy_arcsec``, ``table_orthogonality_arcsec`` (Type B
uncertainty of the table angles) and ``accel_accuracy_g``, ``gyro_accuracy_dps`` (held-out
limits), and the unit's ``grade`` (``consumer``, ``tactical``, ``navigation``: the noise it
declares, which P1 takes for the biases' flicker when the static records are too short to show
it, docs/p1.md "Noise model of the window means").

Contents
--------
:class:`StepFile`, :class:`StepEntry`
    The validated document.
:func:`load_step_file`, :func:`parse_step_file`, :func:`step_file_to_toml`
    Read (every defect named with its step and field) and write.
:func:`step_file_from_recording`
    The step file of a Recording's executed steps (what ``imucalib export --step-file`` writes).
:func:`step_file_skeleton`
    A step file to complete by hand from the intervals ``imucalib segments`` found.
"""

from __future__ import annotations

import itertools
import math
import tomllib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final, Literal

import tomli_w
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    field_validator,
    model_validator,
)

from imucalib.conventions import TABLE_AXIS_VECTORS
from imucalib.errors import InvalidInputError
from imucalib.io.context import RecordingContext
from imucalib.io.step_roles import is_role, role_from_tags, split_role

if TYPE_CHECKING:
    from imucalib.io.reader import Recording

__all__ = [
    "FORMAT_NAME",
    "MAX_ANGLE_DEG",
    "SKIP",
    "StepEntry",
    "StepFile",
    "load_step_file",
    "parse_step_file",
    "step_file_from_recording",
    "step_file_skeleton",
    "step_file_to_toml",
]

FORMAT_NAME: Final = "imucalib-steps"
#: The role of an interval to leave out (what a skeleton starts every interval with); the one
#: role a step file knows without a procedure.
SKIP = "skip"
#: What a role looks like, for messages.
_ROLE_FORM = "'<procedure>.<purpose>' (`imucalib procedures NAME` lists a procedure's roles)"

_TIME_BOUND_S = 1e10
#: Largest table angle in magnitude: a turn either way, as a plan's (docs/import.md). [°]
MAX_ANGLE_DEG: Final = 360.0


class StepEntry(BaseModel):
    """One interval of the data: when, what for, and at which table state.

    Attributes
    ----------
    start_s, end_s : float
        The interval, in the data's time base (the valid window that is averaged). [s]
    role : str
        A step role ``<procedure>.<purpose>`` (:func:`~imucalib.io.step_roles.split_role`; that
        the procedure has it is checked against the registry where the file is used), or
        :data:`SKIP`.
    label : str
    tags : tuple of str
        Free tags, carried to the Recording (``repetition=<k>`` numbers a P1 repetition; a
        tumble record needs ``axis=`` and ``angle=`` …, as the procedure's plan sets them).
    angles_deg : tuple of float, optional
        The table angles held, outer axis first (a rate step: at `start_s`). [°]
    axis : str or int, optional
        A rate step's turning axis: a name of the file's ``table_axes`` or its index. Given
        with `rate_dps`, it makes the interval a turn (:attr:`kind` ``"rate"``).
    rate_dps : float, optional
        A rate step's rate about that axis. [°/s]
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    start_s: float = Field(ge=-_TIME_BOUND_S, le=_TIME_BOUND_S, allow_inf_nan=False)
    end_s: float = Field(ge=-_TIME_BOUND_S, le=_TIME_BOUND_S, allow_inf_nan=False)
    role: str
    label: str = Field("", max_length=200)
    tags: tuple[str, ...] = ()
    angles_deg: tuple[float, ...] | None = Field(None, min_length=1, max_length=3)
    axis: str | int | None = None
    rate_dps: float | None = Field(None, ge=-36000.0, le=36000.0)

    @field_validator("axis", mode="before")
    @classmethod
    def _no_bool_axis(cls, value: Any) -> Any:
        if isinstance(value, bool):
            raise ValueError(f"`axis` must be a table axis name or an index; got {value!r}")
        return value

    @model_validator(mode="after")
    def _consistent(self) -> StepEntry:
        if not (math.isfinite(self.start_s) and math.isfinite(self.end_s)):
            raise ValueError("`start_s` and `end_s` must be finite")
        if not self.end_s > self.start_s:
            raise ValueError(f"`end_s` ({self.end_s:g} s) must be after `start_s` "
                             f"({self.start_s:g} s)")
        if self.role != SKIP:
            try:
                split_role(self.role)
            except ValueError:
                raise ValueError(f"role {self.role!r} is neither {_ROLE_FORM} nor "
                                 f"{SKIP!r}") from None
        if self.angles_deg is not None and not all(math.isfinite(a) for a in self.angles_deg):
            raise ValueError("`angles_deg` must be finite")
        if self.angles_deg is not None and any(abs(a) > MAX_ANGLE_DEG for a in self.angles_deg):
            bad = next(a for a in self.angles_deg if abs(a) > MAX_ANGLE_DEG)
            raise ValueError(f"`angles_deg` holds {bad:g}°; a table angle is within "
                             f"±{MAX_ANGLE_DEG:g}° (a turn either way)")
        if self.rate_dps is not None and not math.isfinite(self.rate_dps):
            raise ValueError("`rate_dps` must be finite")
        if self.role != SKIP and self.axis is not None and self.rate_dps is None:
            raise ValueError(f"a turn (a {self.role} step with `axis`) needs `rate_dps`, its "
                             "rate about that table axis")
        if self.role != SKIP and self.axis is None and self.rate_dps not in (None, 0.0):
            raise ValueError(f"a turn (a {self.role} step with `rate_dps`) needs `axis` (the "
                             "turning table axis)")
        return self

    @property
    def kind(self) -> Literal["static", "rate"]:
        """``"rate"`` for a turn (the step gives `axis`), else ``"static"``."""
        return "rate" if self.axis is not None else "static"


class StepFile(BaseModel):
    """A validated step file (module docstring)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    format: Literal["imucalib-steps"] = FORMAT_NAME
    version: Literal[1] = 1
    unit: str | None = Field(None, min_length=1, max_length=100, pattern=r"^[A-Za-z0-9_.+-]+$")
    latitude_deg: float | None = Field(None, ge=-90.0, le=90.0)
    heading_deg: float = Field(0.0, ge=-360.0, le=360.0)
    table_axes: tuple[str, ...] = Field(("pitch", "roll"), min_length=1, max_length=3)
    sample_rate_hz: float | None = Field(None, gt=0.0, le=1e6)
    bandwidth_hz: float | None = Field(None, gt=0.0, le=1e6)
    table_position_accuracy_arcsec: float | None = Field(None, ge=0.0, le=3600.0)
    table_orthogonality_arcsec: float | None = Field(None, ge=0.0, le=3600.0)
    accel_accuracy_g: float | None = Field(None, gt=0.0, le=100.0)
    gyro_accuracy_dps: float | None = Field(None, gt=0.0, le=1000.0)
    grade: Literal["consumer", "tactical", "navigation"] | None = None
    steps: tuple[StepEntry, ...] = Field(min_length=1)

    @model_validator(mode="after")
    def _consistent(self) -> StepFile:
        for name in self.table_axes:
            if name not in TABLE_AXIS_VECTORS:
                raise ValueError(f"table_axes: {name!r} is not a table axis "
                                 f"({', '.join(TABLE_AXIS_VECTORS)})")
        if len(set(self.table_axes)) != len(self.table_axes):
            raise ValueError(f"table_axes: {list(self.table_axes)} names an axis twice")
        k = len(self.table_axes)
        for i, step in enumerate(self.steps):
            where = f"steps[{i}]" + (f" ({step.label})" if step.label else "")
            if step.angles_deg is not None and len(step.angles_deg) != k:
                raise ValueError(f"{where}: `angles_deg` has {len(step.angles_deg)} angle(s); "
                                 f"the table has {k} axes {list(self.table_axes)}")
            if step.axis is not None:
                self.axis_index(step.axis, where)
        used = sorted((s.start_s, s.end_s, i) for i, s in enumerate(self.steps)
                      if s.role != SKIP)
        if not used:
            raise ValueError(f"every step's role is {SKIP!r}: give at least one interval a role "
                             f"{_ROLE_FORM}")
        for (a0, a1, i), (b0, _b1, j) in itertools.pairwise(used):
            if b0 < a1:
                raise ValueError(f"steps[{i}] ({a0:g}–{a1:g} s) and steps[{j}] (from {b0:g} s) "
                                 "overlap: each sample belongs to one step")
        given = [i for _, _, i in used if self.steps[i].angles_deg is not None]
        if given and len(given) != len(used):
            i = min(i for _, _, i in used if self.steps[i].angles_deg is None)
            step = self.steps[i]
            where = f"steps[{i}]" + (f" ({step.label})" if step.label else "")
            raise ValueError(f"{where}: a {step.role} step needs `angles_deg` (the table angles, "
                             f"outer axis first), as steps[{given[0]}] gives them: the table "
                             "stream is reconstructed from every step's angles")
        if self.latitude_deg is None and self.has_table:
            raise ValueError("`latitude_deg` is required when the steps give table angles or "
                             "turns: the reference inputs (gravity, the Earth-rate projection) "
                             "need the site's latitude")
        return self

    @property
    def has_table(self) -> bool:
        """Whether a used step gives table angles or a turn (a table stream is reconstructed)."""
        return any(s.angles_deg is not None or s.axis is not None for s in self.used_steps)

    def axis_index(self, axis: str | int, where: str = "") -> int:
        """Return the index in :attr:`table_axes` of an axis given by name or index."""
        names = list(self.table_axes)
        if isinstance(axis, bool):
            raise ValueError(f"{where}: `axis` must be a name of {names} or an index")
        if isinstance(axis, int):
            if 0 <= axis < len(names):
                return axis
            raise ValueError(f"{where}: `axis` {axis} is not an index of table_axes {names}")
        if axis in names:
            return names.index(axis)
        raise ValueError(f"{where}: `axis` {axis!r} is not one of table_axes {names}")

    @property
    def used_steps(self) -> tuple[StepEntry, ...]:
        """The steps whose role is not :data:`SKIP`, in time order."""
        return tuple(sorted((s for s in self.steps if s.role != SKIP), key=lambda s: s.start_s))


def _field_path(loc: Sequence[int | str]) -> str:
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out or "the file"


def parse_step_file(text: str, source: str = "<step file>") -> StepFile:
    """Parse and validate step-file TOML.

    Raises
    ------
    InvalidInputError
        Not TOML, or a field missing, unknown or out of range: one line naming the source, the
        step and the field, what was expected and what was found.
    """
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InvalidInputError(f"{source} is not valid TOML: {exc}") from exc
    fmt = doc.get("format", FORMAT_NAME)
    if fmt != FORMAT_NAME:
        raise InvalidInputError(f"{source}: format is {fmt!r}; expected {FORMAT_NAME!r} (a step "
                                "file, docs/import.md)")
    try:
        return StepFile.model_validate(doc)
    except ValidationError as exc:
        err = exc.errors()[0]
        loc = _field_path(err["loc"])
        msg = str(err["msg"]).removeprefix("Value error, ")
        more = f" (and {exc.error_count() - 1} more)" if exc.error_count() > 1 else ""
        got = "" if err["type"] in ("value_error", "missing") else f"; got {err.get('input')!r}"
        raise InvalidInputError(f"{source}: {loc}: {msg}{got}{more}") from None


def load_step_file(path: str | Path) -> StepFile:
    """Read a step file (:func:`parse_step_file`)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InvalidInputError(f"step file {p} does not exist") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidInputError(f"cannot read step file {p}: {exc}") from exc
    return parse_step_file(text, str(p))


def _toml_line(key: str, value: Any) -> str:
    """``key = value`` with arrays on one line (tomli_w breaks every array over lines)."""
    if isinstance(value, list):
        return f"{key} = [{', '.join(_toml_line('x', v)[4:] for v in value)}]"
    return tomli_w.dumps({key: value}).rstrip("\n")


def step_file_to_toml(step_file: StepFile) -> str:
    """Return the TOML text of a step file (optional fields left out when unset).

    One line per field, arrays inline, one ``[[steps]]`` table per step; it parses back to an
    equal :class:`StepFile` (:func:`parse_step_file`).
    """
    doc = step_file.model_dump(mode="json", exclude_none=True)
    steps = doc.pop("steps")
    lines = [_toml_line(k, v) for k, v in doc.items()]
    for step in steps:
        lines += ["", "[[steps]]"]
        lines += [_toml_line(k, v) for k, v in step.items() if v not in ("", [])]
    return "\n".join(lines) + "\n"


def _held_angles(commanded: Mapping[str, Any], last: tuple[float, ...] | None
                 ) -> tuple[float, ...] | None:
    angles = commanded.get("angles_deg")
    if isinstance(angles, list) and all(isinstance(a, int | float) for a in angles):
        return tuple(float(a) for a in angles)
    return last


def step_file_from_recording(rec: Recording, unit: str | None = None) -> StepFile:
    """Return the step file of a Recording's completed steps that have a role.

    Any procedure's roles (a role the registry does not know is refused when the file is
    imported, not here). Each step's valid window becomes an interval with its role, label and
    tags; its table angles are those it commanded (a position step) or the last commanded
    before it (a rate step turns from there), none when the run commanded none; a rate step
    gives its commanded axis and rate. Site, table axes and the IMU rate come from the
    Recording's metadata and table stream.

    Raises
    ------
    InvalidInputError
        The Recording has no completed step with a role, a step before any commanded table
        angles while later ones have them, a rate step without its commanded axis and rate, or
        a centrifuge step (a step file describes a table).
    """
    import json

    from imucalib.io.streams import DEVICE_IMU, DEVICE_TABLE

    meta = rec.metadata
    tables = [s for s in rec.streams if s.device == DEVICE_TABLE]
    axes = tuple(c[len("angle_"):-len("_rad")] for c in tables[0].columns
                 if c.startswith("angle_") and c.endswith("_rad")) if tables else ("pitch", "roll")
    imus = [s.unit for s in rec.streams if s.device == DEVICE_IMU]
    name = unit or (imus[0] if len(imus) == 1 else None)
    identities = meta.get("imu_identity_json") or {}
    if isinstance(identities, str):
        try:
            identities = json.loads(identities)
        except ValueError:
            identities = {}
    ident = identities.get(name or "", {}) if isinstance(identities, dict) else {}
    steps: list[StepEntry] = []
    last: tuple[float, ...] | None = None
    unplaced: Any = None  # the first step written before any commanded table angles
    for step in rec.steps:
        cmd = step.commanded if isinstance(step.commanded, dict) else {}
        last = _held_angles(cmd, last)
        role = step.role or role_from_tags(step.kind, step.tags)
        if (not is_role(role) or step.status != "done" or not step.has_valid_window
                or (name is not None and not step.concerns(name))):
            continue
        if step.kind == "centrifuge":
            raise InvalidInputError(f"{rec.path}: step {step.index} ({step.label}) is a "
                                    "centrifuge step: a step file describes a table's states, "
                                    "not a centrifuge's")
        entry: dict[str, Any] = {"start_s": step.valid_start_s, "end_s": step.valid_end_s,
                                 "role": role, "label": step.label, "tags": step.tags}
        if last is not None:
            entry["angles_deg"] = last
        elif unplaced is None:
            unplaced = step
        if step.kind == "rate":
            axis, rate = cmd.get("axis"), cmd.get("rate_dps")
            if (not isinstance(axis, int) or isinstance(axis, bool)
                    or not isinstance(rate, int | float)):
                raise InvalidInputError(f"{rec.path}: rate step {step.index} ({step.label}) "
                                        "does not record its commanded axis and rate")
            entry["axis"], entry["rate_dps"] = axis, float(rate)
        steps.append(StepEntry(**entry))
    if not steps:
        raise InvalidInputError(f"{rec.path}: no completed step with a role: nothing to write "
                                "into a step file")
    if unplaced is not None and any(s.angles_deg is not None for s in steps):
        raise InvalidInputError(f"{rec.path}: step {unplaced.index} ({unplaced.label}) has no "
                                "commanded table angles before it")
    context = RecordingContext.of(meta)  # the equipment accuracies and held-out limits
    limits: dict[str, float] = {**context.equipment,
                                **{k: v for k, v in context.imu_spec.items()
                                   if k in ("accel_accuracy_g", "gyro_accuracy_dps")}}
    lat = meta.get("latitude_deg")
    rate_hz = ident.get("sample_rate_hz") if isinstance(ident, dict) else None
    band_hz = ident.get("bandwidth_hz") if isinstance(ident, dict) else None
    return StepFile(unit=name, latitude_deg=float(lat) if lat is not None else None,
                    heading_deg=float(meta.get("heading_deg", 0.0)), table_axes=axes,
                    sample_rate_hz=float(rate_hz) if rate_hz else None,
                    bandwidth_hz=float(band_hz) if band_hz else None, steps=tuple(steps),
                    grade=_grade(context.imu_unit.get("grade")), **limits)


def _grade(text: str | None) -> Literal["consumer", "tactical", "navigation"] | None:
    """Return the recording's stated grade as a step file holds it (None: none, or another)."""
    grades: dict[str | None, Literal["consumer", "tactical", "navigation"]] = {
        "consumer": "consumer", "tactical": "tactical", "navigation": "navigation"}
    return grades.get(text)


def step_file_skeleton(intervals: Sequence[tuple[str, float, float]], *,
                       unit: str | None = None) -> str:
    """Return a step file to complete by hand: one ``skip`` step per interval.

    Parameters
    ----------
    intervals : sequence of (kind, start_s, end_s)
        What :func:`imucalib.processing.detect_segments` found (``"static"`` or
        ``"rotating"``).
    unit : str, optional

    Returns
    -------
    str
        TOML in which every step has role ``"skip"`` and a comment saying what to fill in; the
        operator sets the role, the angles (and a rotation's axis and rate) of the intervals to
        use.
    """
    lines = ["# Step file skeleton written by `imucalib segments --step-file` (docs/import.md).",
             "# For each interval to use: set `role`, `angles_deg` (table angles, outer axis",
             "# first), and for a rotation `axis` and `rate_dps`; leave the others as \"skip\".",
             "# Roles: '<procedure>.<purpose>', e.g. \"p1.accel-position\"; `imucalib",
             "# procedures NAME` lists a procedure's roles. Give the tags its plan sets.",
             f'format = "{FORMAT_NAME}"']
    if unit:
        lines.append(f'unit = "{unit}"')
    lines += ["# latitude_deg = 0.0  # the site's latitude [°]: required with table angles",
              "heading_deg = 0.0", 'table_axes = ["pitch", "roll"]', ""]
    for i, (kind, t0, t1) in enumerate(intervals):
        lines += ["[[steps]]", f"# interval {i}: {kind}, {t1 - t0:.3f} s",
                  f"start_s = {t0!r}", f"end_s = {t1!r}", f'role = "{SKIP}"',
                  f'label = "{kind} {i}"']
        if kind == "rotating":
            lines += ['# axis = "pitch"', "# rate_dps = 0.0"]
        lines += ["# angles_deg = [0.0, 0.0]", ""]
    return "\n".join(lines)
