"""Validating a plan chosen on /runs/new, with its errors per step and field (docs/web.md).

The plan is read by the project's own :func:`~imucalib.plan.io.parse_plan` (the validation of
``imucalib run``); its one-line-per-problem message (``steps.3.rate.rate_dps: …``) is split into
:class:`FieldError` rows that the page shows against the step they concern.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import TYPE_CHECKING, Final

from imucalib.errors import CalibrationError

if TYPE_CHECKING:
    from imucalib.plan.schema import Plan

__all__ = ["FieldError", "check_plan", "check_serials", "split_errors"]

#: The most serials a run takes from the form.
MAX_SERIALS: Final = 64
_STEP = re.compile(r"^steps\.(\d+)(?:\.(.*))?$")
_SERIAL = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._\-/]{0,99}$")


@dataclass(frozen=True)
class FieldError:
    """One problem: the plan step it concerns (None: the plan or the form), the field, why."""

    step: int | None
    field: str
    message: str


def split_errors(message: str) -> list[FieldError]:
    """Return the problems of a plan validation message, one per line after the first."""
    lines = [ln.strip() for ln in message.splitlines() if ln.strip()]
    if len(lines) == 1:                         # "invalid plan X: loc: msg" or a plain line
        head, _, rest = lines[0].partition(": ")
        lines = [rest] if head.startswith("invalid plan") and rest else lines
    else:
        lines = lines[1:]
    out = []
    for line in lines:
        loc, sep, msg = line.partition(": ")
        if not sep or " " in loc:
            out.append(FieldError(None, "", line))
            continue
        found = _STEP.match(loc)
        if found:
            out.append(FieldError(int(found.group(1)), found.group(2) or "", msg))
        else:
            out.append(FieldError(None, loc, msg))
    return out


def check_plan(text: str, source: str, station: str) -> tuple[Plan | None, list[FieldError]]:
    """Return the plan of `text` and its problems (the plan is None when it does not parse).

    `station` is ``sim`` or a station file: ``sim`` needs the plan's ``[twin]`` table.
    """
    from imucalib.plan.io import parse_plan

    try:
        plan = parse_plan(text, source)
    except CalibrationError as exc:
        return None, split_errors(str(exc))
    errors = []
    if station == "sim" and plan.twin is None:
        errors.append(FieldError(None, "twin", f"plan {plan.name!r} has no [twin] table "
                                               "describing the simulated station; choose a "
                                               "station file or add one"))
    return plan, errors


def check_serials(text: str) -> tuple[list[str], list[FieldError]]:
    """Return the serials of the form's field (commas, spaces or lines) and their problems."""
    serials = [s for s in re.split(r"[\s,;]+", text) if s]
    errors = [FieldError(None, "serials", f"a serial is letters, digits and . _ - / (at most "
                                          f"100); got {s!r}")
              for s in serials if not _SERIAL.match(s)]
    if not serials:
        errors.append(FieldError(None, "serials", "name at least one unit serial; got none"))
    if len(serials) > MAX_SERIALS:
        errors.append(FieldError(None, "serials", f"at most {MAX_SERIALS} serials; got "
                                                  f"{len(serials)}"))
    if len(set(serials)) != len(serials):
        errors.append(FieldError(None, "serials", "each serial once; got a repeated one"))
    return serials, errors
