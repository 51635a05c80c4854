"""The procedures by name, and which one a recording belongs to.

``imucalib plan new NAME``, ``imucalib calibrate``, the demo and the tests find a procedure here.
The built-in ones are listed in :data:`BUILTIN` (name → the module holding its ``PROCEDURE``)
and imported on first use, so that importing the registry imports no analysis; a new procedure
folder adds one line there, or calls :func:`register` with its object.

Which procedure a recording belongs to (:func:`identify`): its steps' roles when they carry
them (a role ``"p1.accel-position"`` names procedure ``p1``: the part before the first dot), else
the ``procedure`` field of the plan stored in its metadata.

Contents
--------
:func:`get`, :func:`names`, :func:`register`, :func:`identify`, :func:`procedure_of_roles`,
:data:`BUILTIN`
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable
from typing import TYPE_CHECKING

from imucalib.errors import ConfigurationError
from imucalib.procedures.common.procedure import Procedure

if TYPE_CHECKING:
    from imucalib.io.reader import Recording

__all__ = ["BUILTIN", "get", "identify", "names", "procedure_of_roles", "register"]

#: Built-in procedures: name → module whose ``PROCEDURE`` implements it.
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

_registered: dict[str, Procedure] = {}


def register(procedure: Procedure, *, replace: bool = False) -> Procedure:
    """Register `procedure` under its name; return it.

    Raises
    ------
    ConfigurationError
        If it does not satisfy :class:`~imucalib.procedures.common.procedure.Procedure`, or the
        name is taken and `replace` is false.
    """
    if not isinstance(procedure, Procedure):
        raise ConfigurationError(f"{procedure!r} is not a Procedure (name, description, "
                                 "plan_options, analysis_options, outputs, generate_plan, "
                                 "analyze)")
    name = procedure.name
    if not name or "." in name:
        raise ConfigurationError(f"procedure name {name!r} must be non-empty and hold no dot "
                                 "(step roles are '<procedure>.<role>')")
    if not replace and name in names():
        raise ConfigurationError(f"procedure {name!r} is already registered")
    _registered[name] = procedure
    return procedure


def _builtin(name: str) -> Procedure:
    module = importlib.import_module(BUILTIN[name])
    proc = module.PROCEDURE
    assert isinstance(proc, Procedure), BUILTIN[name]
    return proc


def names() -> tuple[str, ...]:
    """Return the registered procedure names, built-ins first."""
    return (*BUILTIN, *(n for n in _registered if n not in BUILTIN))


def get(name: str) -> Procedure:
    """Return the procedure registered as `name`.

    Raises
    ------
    ConfigurationError
        If no procedure has that name (the message lists the known ones).
    """
    if name in _registered:
        return _registered[name]
    if name in BUILTIN:
        _registered[name] = _builtin(name)
        return _registered[name]
    raise ConfigurationError(f"unknown procedure {name!r}; known: {', '.join(names())}")


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


def identify(recording: Recording) -> str:
    """Return the name of the procedure an open Recording belongs to (module docstring).

    Raises
    ------
    ConfigurationError
        If neither roles nor a plan say which, or the plan's procedure is not registered.
    """
    from imucalib.plan.io import parse_plan

    path = recording.path
    by_role = procedure_of_roles(getattr(s, "role", None) for s in recording.steps)
    if by_role is not None:
        return by_role
    plan_toml = recording.metadata.get("plan_toml")
    if not plan_toml:
        raise ConfigurationError(f"{path} holds no plan: `imucalib calibrate` needs a "
                                 "recording made by `imucalib run`")
    procedure = parse_plan(str(plan_toml), str(path)).procedure
    if procedure not in names():
        raise ConfigurationError(f"{path}: plan procedure {procedure!r} has no analysis here; "
                                 f"known: {', '.join(names())}")
    return str(procedure)
