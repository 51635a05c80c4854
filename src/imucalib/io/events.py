"""Station events: the typed entries of a Recording's log (a remount, a unit swap, a load).

A station run logs what the operator did to the set-up between records, so that an analysis, a
report or ``imucalib inspect`` finds it in the file without reading free text: a remount of the
fixture (P2's cube placed with another face up), an exchange of two units on the fixture (P3's
reversal of the references) and a change of the centrifuge arm's test load. Each is one row of
``/log`` (``docs/recording-format.md``, "`/log/<field>`"), stored without any change to the
log's fields or their sizes, so that every reader of the format still reads the file:

- ``source`` is ``"event:<kind>"`` (:func:`event_source`: ``"event:remount"``,
  ``"event:swap"``, ``"event:load"``), which is what a reader keys on (:func:`event_kind`);
- ``level`` is ``"info"``;
- ``message`` is text for people: the event's label, a colon and the details
  (:func:`event_message`: ``"fixture remounted: +x up, yaw 90°"``). Readers never parse it. The
  labels are the version 1 wording, so that an older imucalib, which found these events by that
  wording, still finds them in a new file.

A log row whose ``source`` starts with ``"event:"`` and names a kind this reader does not know
(written by a newer imucalib) has no kind here (:func:`event_kind` returns None).

The one exception is a frozen fact of the file format: :func:`v1_event_kind`, the version 1
mapping, by which a Recording written before the events were typed gets its events (the runner
logged them with source ``"runner"`` and a message starting ``"fixture remounted"``, ``"units
swapped"`` or ``"centrifuge load set"``). Version 1 of the events, not of the file format: it
serves files of every format version written before then. It is kept exactly as it was when the
typed events began, and it is the only place where a message is matched
(``docs/recording-format.md``, "Station events").

Contents
--------
:class:`EventKind`, :data:`EVENT_SOURCE_PREFIX`, :func:`event_source`, :func:`event_message`,
:func:`event_kind`, :func:`as_event_kind`, :func:`v1_event_kind`
"""

from __future__ import annotations

from enum import StrEnum
from typing import Final

from imucalib.errors import InvalidInputError

__all__ = ["EVENT_SOURCE_PREFIX", "EventKind", "as_event_kind", "event_kind", "event_message",
           "event_source", "v1_event_kind"]


class EventKind(StrEnum):
    """What a station event is (the ``<kind>`` of its log ``source`` ``"event:<kind>"``)."""

    #: The fixture was placed in another pose (an axis up, a yaw): ``OperatorCheckStep.remount``.
    REMOUNT = "remount"
    #: Two units exchanged their places on the fixture: ``OperatorCheckStep.swap_units``.
    SWAP = "swap"
    #: The centrifuge arm's test load was set: ``OperatorCheckStep.centrifuge_load_kg``.
    LOAD = "load"


#: How the ``source`` of a station event begins; the kind follows (``"event:remount"``).
EVENT_SOURCE_PREFIX: Final = "event:"

#: The first words of each kind's message (text for people; the version 1 wording, module
#: docstring).
_LABELS: Final[dict[EventKind, str]] = {
    EventKind.REMOUNT: "fixture remounted",
    EventKind.SWAP: "units swapped",
    EventKind.LOAD: "centrifuge load set",
}


def as_event_kind(kind: EventKind | str) -> EventKind:
    """Return `kind` as an :class:`EventKind` (``"remount"`` → ``EventKind.REMOUNT``).

    Raises
    ------
    InvalidInputError
        `kind` is no event kind.
    """
    try:
        return EventKind(kind)
    except ValueError:
        raise InvalidInputError(f"unknown event kind {kind!r}; expected one of "
                                f"{[k.value for k in EventKind]}") from None


def event_source(kind: EventKind | str) -> str:
    """Return the log ``source`` of an event of `kind`.

    Examples
    --------
    >>> event_source(EventKind.SWAP)
    'event:swap'
    """
    return EVENT_SOURCE_PREFIX + as_event_kind(kind).value


def event_message(kind: EventKind | str, detail: str) -> str:
    """Return the log ``message`` of an event of `kind`: its label, then `detail`.

    Examples
    --------
    >>> event_message("load", "5 kg")
    'centrifuge load set: 5 kg'
    """
    return f"{_LABELS[as_event_kind(kind)]}: {detail}"


def event_kind(source: str, message: str) -> EventKind | None:
    """Return the kind of the log event (`source`, `message`), or None for any other event.

    A source ``"event:<kind>"`` says it (None for a kind this reader does not know); any other
    source goes through the frozen version 1 mapping (:func:`v1_event_kind`).

    Examples
    --------
    >>> event_kind("event:remount", "fixture remounted: -z up, yaw 0°")
    <EventKind.REMOUNT: 'remount'>
    >>> event_kind("runner", "units swapped: A ↔ B") is EventKind.SWAP
    True
    >>> event_kind("guard", "accel output jumped") is None
    True
    """
    if source.startswith(EVENT_SOURCE_PREFIX):
        try:
            return EventKind(source[len(EVENT_SOURCE_PREFIX):])
        except ValueError:
            return None
    return v1_event_kind(source, message)


# The version 1 mapping (frozen: module docstring). Do not edit.
_V1_SOURCE: Final = "runner"
_V1_PREFIXES: Final = (
    ("fixture remounted", EventKind.REMOUNT),
    ("units swapped", EventKind.SWAP),
    ("centrifuge load set", EventKind.LOAD),
)


def v1_event_kind(source: str, message: str) -> EventKind | None:
    """Return the kind of an event logged before the events were typed, or None.

    The frozen version 1 mapping (module docstring): the runner's (source ``"runner"``)
    messages starting ``"fixture remounted"``, ``"units swapped"`` or ``"centrifuge load set"``
    are a remount, a swap and a load.

    Examples
    --------
    >>> v1_event_kind("runner", "centrifuge load set: 2 kg (the last completed load, restored "
    ...               "on resume)")
    <EventKind.LOAD: 'load'>
    >>> v1_event_kind("operator:alice", "fixture remounted by hand") is None
    True
    """
    if source != _V1_SOURCE:
        return None
    return next((kind for prefix, kind in _V1_PREFIXES if message.startswith(prefix)), None)
