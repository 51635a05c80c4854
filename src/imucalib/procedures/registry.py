"""The procedures by name, and which one a recording belongs to.

``imucalib plan new NAME``, ``imucalib calibrate``, the demo and the tests find a procedure here.
Procedures are discovered in the entry-point group ``imucalib.procedures``
(:data:`ENTRY_POINT_GROUP`, the packaging convention for plug-ins): each entry point's name is
the procedure's name and its value ``module:OBJECT`` the object implementing
:class:`~imucalib.procedures.common.procedure.Procedure`. imucalib declares its own procedures
there (``pyproject.toml``); another distribution adds one by declaring an entry point in the same
group (docs/plugins.md). :data:`BUILTIN` (name → the module holding its ``PROCEDURE``) is the
fallback for the built-in ones when imucalib's own metadata is missing (running from a source
tree), and fixes their order; :func:`register` adds an object at run time.

Loading is lazy: listing (:func:`names`) reads the metadata only, and an entry point is loaded
when its procedure is first asked for (:func:`get`), so importing the registry imports no
analysis. An entry point that fails to load, or whose object is not a ``Procedure`` named as the
entry point, is refused when asked for by name (:class:`~imucalib.errors.ConfigurationError`
naming the entry point and its distribution) and affects no other procedure. An outside
distribution may not declare a built-in name: that entry point is refused and the built-in is
kept (:func:`problems` says so; ``imucalib procedures`` lists it).

Which procedure a recording belongs to (:func:`identify`): its steps' roles when they carry
them (a role ``"p1.accel-position"`` names procedure ``p1``: the part before the first dot), else
the procedure its plan names (the recording's context,
:class:`~imucalib.io.context.RecordingContext`: the ``procedure`` key a run writes, or its
stored plan's). Which roles exist is each procedure's ``roles`` (its folder's ``roles.py``):
:func:`check_roles` refuses a role that its procedure does not have, where step roles come from
outside a plan (a step file).

Contents
--------
:func:`get`, :func:`names`, :func:`origin`, :func:`problems`, :func:`refresh`, :func:`register`,
:func:`identify`, :func:`procedure_of_roles`, :func:`check_roles`, :data:`BUILTIN`,
:data:`ENTRY_POINT_GROUP`
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from importlib.metadata import EntryPoint, entry_points
from typing import TYPE_CHECKING

from imucalib.errors import ConfigurationError
from imucalib.io.step_roles import split_role
from imucalib.procedures.common.procedure import Procedure

if TYPE_CHECKING:
    from imucalib.io.reader import Recording

__all__ = ["BUILTIN", "ENTRY_POINT_GROUP", "check_roles", "get", "identify", "names", "origin",
           "problems", "procedure_of_roles", "refresh", "register"]

#: The entry-point group procedures are declared in: the table
#: ``[project.entry-points."imucalib.procedures"]`` of a ``pyproject.toml`` (docs/plugins.md).
ENTRY_POINT_GROUP = "imucalib.procedures"

#: Built-in procedures: name → module whose ``PROCEDURE`` implements it. The same names are
#: declared as entry points in imucalib's ``pyproject.toml``; this table is used when that
#: metadata is missing, and gives the built-ins' order.
BUILTIN: dict[str, str] = {
    "p1": "imucalib.procedures.p1.procedure",
    "allan": "imucalib.procedures.allan.procedure",
    "p2": "imucalib.procedures.p2.procedure",
    "p3": "imucalib.procedures.p3.procedure",
    "rate-transfer": "imucalib.procedures.rate_transfer.procedure",
    "installation": "imucalib.procedures.installation.procedure",
    "g-sensitivity": "imucalib.procedures.g_sensitivity.procedure",
    "earth-rate-bias": "imucalib.procedures.earth_rate_bias.procedure",
    "random-drift": "imucalib.procedures.random_drift.procedure",
    "tumble": "imucalib.procedures.tumble.procedure",
    "field": "imucalib.procedures.field.procedure",
}

#: The distribution whose entry points may carry the built-in names.
_OWN_DISTRIBUTION = "imucalib"
#: The members :class:`Procedure` asks for (named when an object lacks some).
_MEMBERS = tuple(n for n in vars(Procedure) if not n.startswith("_"))

_registered: dict[str, Procedure] = {}


@dataclass
class _Discovery:
    """What the metadata of the installed distributions declares in :data:`ENTRY_POINT_GROUP`."""

    builtin: dict[str, EntryPoint] = field(default_factory=dict)
    outside: dict[str, list[EntryPoint]] = field(default_factory=dict)
    refused: list[str] = field(default_factory=list)


_discovered: _Discovery | None = None


def _normalised(name: str) -> str:
    """Return a distribution name as packaging compares it (PEP 503)."""
    return re.sub(r"[-_.]+", "-", name).lower()


def _distribution(ep: EntryPoint) -> str:
    """Return "the distribution <name> <version>" declaring `ep` (or that it is unknown)."""
    dist = getattr(ep, "dist", None)
    if dist is None:
        return "an unknown distribution"
    name = getattr(dist, "name", None) or dist.metadata["Name"] or "?"
    return f"the distribution {name} {dist.version}"


def _is_own(ep: EntryPoint) -> bool:
    dist = getattr(ep, "dist", None)
    name = getattr(dist, "name", None) or (dist.metadata["Name"] if dist is not None else "")
    return _normalised(str(name or "")) == _OWN_DISTRIBUTION


def _describe(ep: EntryPoint) -> str:
    """Return how an entry point is named in messages: its line and its distribution."""
    return (f"entry point '{ep.name} = {ep.value}' (group {ENTRY_POINT_GROUP}) of "
            f"{_distribution(ep)}")


def _discover() -> _Discovery:
    """Read the entry points of :data:`ENTRY_POINT_GROUP` once (:func:`refresh` reads again)."""
    global _discovered
    if _discovered is not None:
        return _discovered
    found = _Discovery()
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        if ep.name in BUILTIN:
            if _is_own(ep):
                found.builtin[ep.name] = ep
            else:
                found.refused.append(
                    f"the {_describe(ep)} is refused: a plug-in may not shadow the built-in "
                    f"procedure {ep.name!r} (the built-in is used); rename the plug-in's "
                    "procedure")
        elif not ep.name or "." in ep.name:
            found.refused.append(f"the {_describe(ep)} is refused: a procedure name must be "
                                 "non-empty and hold no dot (step roles are "
                                 "'<procedure>.<role>')")
        else:
            found.outside.setdefault(ep.name, []).append(ep)
    _discovered = found  # the refusals are listed by problems() (`imucalib procedures`)
    return found


def refresh() -> None:
    """Forget the entry points read so far; the next lookup reads the metadata again.

    For a distribution installed while the process runs. Procedures already loaded stay.
    """
    global _discovered
    _discovered = None


def problems() -> tuple[str, ...]:
    """Return why entry points of :data:`ENTRY_POINT_GROUP` were refused (one line each).

    A plug-in that declares a built-in name, or a name holding a dot; an entry point that fails
    to load is said by :func:`get` when its procedure is asked for.
    """
    return tuple(_discover().refused)


def register(procedure: Procedure, *, replace: bool = False) -> Procedure:
    """Register `procedure` under its name; return it.

    Raises
    ------
    ConfigurationError
        If it does not satisfy :class:`~imucalib.procedures.common.procedure.Procedure`, or the
        name is taken and `replace` is false.
    """
    if not isinstance(procedure, Procedure):
        raise ConfigurationError(f"{procedure!r} is not a Procedure ({', '.join(_MEMBERS)})")
    name = procedure.name
    if not name or "." in name:
        raise ConfigurationError(f"procedure name {name!r} must be non-empty and hold no dot "
                                 "(step roles are '<procedure>.<role>')")
    if not replace and name in names():
        raise ConfigurationError(f"procedure {name!r} is already registered")
    _registered[name] = procedure
    return procedure


def _checked(obj: object, name: str, where: str) -> Procedure:
    """Return `obj` if it is a Procedure named `name`; else refuse it naming `where`."""
    if not isinstance(obj, Procedure):
        missing = [m for m in _MEMBERS if not hasattr(obj, m)]
        lacks = f"it lacks {', '.join(missing)}; " if missing else ""
        raise ConfigurationError(f"procedure {name!r}: the object of the {where} is not a "
                                 f"Procedure ({lacks}docs/plugins.md)")
    if obj.name != name:
        raise ConfigurationError(f"procedure {name!r}: the object of the {where} is named "
                                 f"{obj.name!r}; the entry point's name must be the "
                                 "procedure's name")
    return obj


def _load(ep: EntryPoint) -> Procedure:
    """Load an entry point's object and check it (module docstring)."""
    try:
        obj = ep.load()
    except Exception as exc:  # any failure of a plug-in's import is reported, not raised
        raise ConfigurationError(f"procedure {ep.name!r}: the {_describe(ep)} failed to load "
                                 f"({type(exc).__name__}: {exc})") from exc
    return _checked(obj, ep.name, _describe(ep))


def _builtin(name: str) -> Procedure:
    ep = _discover().builtin.get(name)
    if ep is not None:
        return _load(ep)
    module = importlib.import_module(BUILTIN[name])  # no metadata: a source tree
    return _checked(getattr(module, "PROCEDURE", None), name, f"module {BUILTIN[name]}")


def names() -> tuple[str, ...]:
    """Return the procedure names: the built-ins first, then the others sorted by name.

    The others are the outside entry points and the procedures given to :func:`register`;
    nothing is loaded to list them.
    """
    others = (set(_discover().outside) | set(_registered)) - set(BUILTIN)
    return (*BUILTIN, *sorted(others))


def origin(name: str) -> str:
    """Return where procedure `name` comes from, in words (for a listing).

    ``"built-in"``, ``"registered at run time"``, or the entry point and its distribution.

    Raises
    ------
    ConfigurationError
        If no procedure has that name.
    """
    if name in BUILTIN:
        return "built-in"
    eps = _discover().outside.get(name)
    if eps:
        return "; ".join(_describe(ep) for ep in eps)
    if name in _registered:
        return "registered at run time"
    raise ConfigurationError(f"unknown procedure {name!r}; known: {', '.join(names())}")


def get(name: str) -> Procedure:
    """Return the procedure named `name`, loading it on first use (module docstring).

    Raises
    ------
    ConfigurationError
        If no procedure has that name (the message lists the known ones); if its entry point
        fails to load, or its object is not a Procedure of that name (the message names the
        entry point and its distribution); if several distributions declare the name.
    """
    if name in _registered:
        return _registered[name]
    if name in BUILTIN:
        _registered[name] = _builtin(name)
        return _registered[name]
    eps = _discover().outside.get(name)
    if not eps:
        raise ConfigurationError(f"unknown procedure {name!r}; known: {', '.join(names())}")
    if len(eps) > 1:
        raise ConfigurationError(
            f"procedure {name!r} is declared by several entry points: "
            f"{'; '.join(_describe(ep) for ep in eps)}; uninstall all but one")
    _registered[name] = _load(eps[0])
    return _registered[name]


def procedure_of_roles(roles: Iterable[str | None]) -> str | None:
    """Return the procedure the step roles name (the prefix before the first dot), or None.

    Roles without a dot (``"warm-up"``) and prefixes that name no registered procedure are
    ignored.

    Raises
    ------
    ConfigurationError
        If the roles name more than one procedure.
    """
    known = set(names())
    found = sorted({r.split(".", 1)[0] for r in roles if r and "." in r} & known)
    if len(found) > 1:
        raise ConfigurationError(f"the steps' roles name several procedures ({', '.join(found)})"
                                 "; analyse a recording of one procedure at a time")
    return found[0] if found else None


def check_roles(roles: Iterable[str]) -> None:
    """Refuse a step role that its procedure does not have.

    Each role names its procedure (:func:`~imucalib.io.step_roles.split_role`: the part before
    the first dot), which must be registered and list the role in its ``roles``. For roles given
    outside a plan: a step file's (``imucalib import``, ``imucalib calibrate --steps``).

    Parameters
    ----------
    roles : iterable of str
        The roles to check (a step file's used steps': ``"skip"`` left out).

    Raises
    ------
    ConfigurationError
        One line, for the first role refused: not ``<procedure>.<purpose>``; its procedure not
        registered (the message lists the known ones); or not among its procedure's roles (the
        message lists them). Also a procedure that fails to load (:func:`get`).

    Examples
    --------
    >>> check_roles(["p1.accel-position", "p1.gyro-rate"])
    >>> check_roles(["allan.dynamic"])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    imucalib.errors.ConfigurationError: step role 'allan.dynamic' is not a role ...: allan.static
    """
    for role in dict.fromkeys(roles):
        try:
            procedure, _ = split_role(role)
        except ValueError as exc:
            raise ConfigurationError(f"step {exc}") from None
        if procedure not in names():
            raise ConfigurationError(f"step role {role!r} names no known procedure "
                                     f"({procedure!r}); known: {', '.join(names())}")
        known = get(procedure).roles
        if role not in known:
            raise ConfigurationError(f"step role {role!r} is not a role of procedure "
                                     f"{procedure}; its roles: {', '.join(known) or 'none'}")


def identify(recording: Recording) -> str:
    """Return the name of the procedure an open Recording belongs to (module docstring).

    Raises
    ------
    ConfigurationError
        If neither roles nor a plan say which, or the plan's procedure is not registered.
    """
    from imucalib.io.context import RecordingContext

    path = recording.path
    by_role = procedure_of_roles(getattr(s, "role", None) for s in recording.steps)
    if by_role is not None:
        return by_role
    context = RecordingContext.of(recording.metadata)
    if not context.procedure:
        if not context.has_plan:
            raise ConfigurationError(f"{path} holds no plan: `imucalib calibrate` needs a "
                                     "recording made by `imucalib run`")
        raise ConfigurationError(f"{path}: its plan names no procedure; name it: `imucalib "
                                 "calibrate PROCEDURE DATA`")
    if context.procedure not in names():
        raise ConfigurationError(f"{path}: plan procedure {context.procedure!r} has no analysis "
                                 f"here; known: {', '.join(names())}")
    return context.procedure
