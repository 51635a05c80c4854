"""The laboratory configuration, ``imucalib.toml``: :func:`load_config` → :class:`LabConfig`.

What a laboratory states once rather than on every command (docs/configuration.md): its name,
address and accreditation (the certificate's heading), its site (latitude, height, local g),
its records database, the default operator, and the certificate's options::

    [laboratory]
    name = "Inertial Calibration Laboratory"
    address = "1 Example Street, 12345 Town"
    accreditation = "not accredited"        # or e.g. "ISO/IEC 17025, DAkkS D-K-00000-01-00"

    [site]
    latitude_deg = 48.137
    height_m = 519.0
    gravity_mps2 = 9.80753                  # optional: the measured local g

    [records]
    database = "sqlite:////srv/imucalib/records.db"   # or a file, relative to this one

    [operator]
    default = "J. Doe"                      # a user of the records database

    [certificate]
    show_budget = true                      # the uncertainty budget table
    statements = ["This certificate shall not be reproduced except in full."]

Which file (:func:`config_path`): the one given (``--config FILE`` of ``imucalib calibrate`` and
``imucalib report``, or :func:`use_config` from Python), else ``$IMUCALIB_CONFIG``, else
``imucalib.toml`` in the working folder, else ``imucalib.toml`` in the user's configuration
directory (``platformdirs.user_config_dir("imucalib")``). No file is no error: every field has
its default (a laboratory "not stated", "not accredited"). A file named but missing, not TOML,
or with a field of the wrong type or an unknown one is refused in one line naming the file and
the field.

This module sits low (it reads a TOML file and nothing of imucalib but :mod:`imucalib.errors`),
so that the records, the report and the command line may all read it.

Contents
--------
:class:`LabConfig`, :class:`Laboratory`, :class:`Site`, :class:`RecordsConfig`,
:class:`OperatorConfig`, :class:`CertificateOptions`, :func:`load_config`, :func:`config_path`,
:func:`use_config`, :data:`CONFIG_FILE`, :data:`ENV_VAR`
"""

from __future__ import annotations

import os
import tomllib
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import Final

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from imucalib.errors import ConfigurationError

__all__ = ["CONFIG_FILE", "ENV_VAR", "CertificateOptions", "LabConfig", "Laboratory",
           "OperatorConfig", "RecordsConfig", "Site", "config_path", "load_config", "use_config"]

#: The configuration file's name, in the working folder or the user's configuration directory.
CONFIG_FILE: Final = "imucalib.toml"
#: The environment variable naming the configuration file.
ENV_VAR: Final = "IMUCALIB_CONFIG"
#: What a field of the laboratory says when the configuration does not state it.
NOT_STATED: Final = "not stated"

_chosen: ContextVar[Path | None] = ContextVar("imucalib_config", default=None)


class _Table(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Laboratory(_Table):
    """``[laboratory]``: who issues the certificate."""

    name: str = NOT_STATED
    address: str = NOT_STATED
    accreditation: str = "not accredited"


class Site(_Table):
    """``[site]``: where the laboratory is (each None: not stated)."""

    latitude_deg: float | None = Field(default=None, ge=-90.0, le=90.0)
    height_m: float | None = Field(default=None, ge=-500.0, le=9000.0)
    gravity_mps2: float | None = Field(default=None, gt=9.7, lt=9.9)


class RecordsConfig(_Table):
    """``[records]``: the records database (a URL or an SQLite file; "" = the default)."""

    database: str = ""


class OperatorConfig(_Table):
    """``[operator]``: the default operator of a run ("" = none: it must be given)."""

    default: str = ""


class CertificateOptions(_Table):
    """``[certificate]``: options of the certificate (the calibration report)."""

    show_budget: bool = True
    statements: tuple[str, ...] = ()


class LabConfig(_Table):
    """The laboratory configuration (module docstring); `source` the file read, "" for none."""

    laboratory: Laboratory = Laboratory()
    site: Site = Site()
    records: RecordsConfig = RecordsConfig()
    operator: OperatorConfig = OperatorConfig()
    certificate: CertificateOptions = CertificateOptions()
    source: str = Field(default="", exclude=True)


def _user_file() -> Path:
    import platformdirs

    return Path(platformdirs.user_config_dir("imucalib")) / CONFIG_FILE


def config_path(path: str | os.PathLike[str] | None = None) -> tuple[Path | None, bool]:
    """Return the configuration file to read and whether it was named (module docstring).

    Returns
    -------
    (Path or None, bool)
        The file (None: none found, the defaults hold) and True when it was named (`path`,
        :func:`use_config` or ``$IMUCALIB_CONFIG``): a named file must exist.
    """
    named = path if path is not None else _chosen.get()
    if named is None and os.environ.get(ENV_VAR):
        named = os.environ[ENV_VAR]
    if named is not None:
        return Path(named).expanduser(), True
    for candidate in (Path.cwd() / CONFIG_FILE, _user_file()):
        if candidate.is_file():
            return candidate, False
    return None, False


def _field(loc: tuple[int | str, ...]) -> str:
    parts = [str(p) for p in loc]
    if len(parts) >= 2:
        return f"[{parts[0]}] {'.'.join(parts[1:])}"
    return f"[{parts[0]}]" if parts else "the file"


def load_config(path: str | os.PathLike[str] | None = None) -> LabConfig:
    """Read the laboratory configuration (module docstring); defaults when there is no file.

    Parameters
    ----------
    path : str or Path, optional
        The file; default: :func:`config_path`'s choice.

    Raises
    ------
    ConfigurationError
        A file named but missing or unreadable, not valid TOML, or with a field of the wrong
        type, out of range or unknown (one line: the file and the field).
    """
    file, named = config_path(path)
    if file is None:
        return LabConfig()
    try:
        text = file.read_text(encoding="utf-8")
    except FileNotFoundError:
        if not named:
            return LabConfig()
        raise ConfigurationError(f"laboratory configuration {file}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise ConfigurationError(f"laboratory configuration {file}: cannot be read ({why})"
                                 ) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigurationError(f"laboratory configuration {file}: not valid TOML ({exc})"
                                 ) from None
    try:
        if "source" in data:  # the file read, set here; not a field of the file
            raise ConfigurationError(f"laboratory configuration {file}: [source]: unknown field")
        config = LabConfig.model_validate(data)
    except ValidationError as exc:
        err = exc.errors()[0]
        got = err.get("input")
        shown = "" if err["type"] == "extra_forbidden" else f"; got {got!r}"[:80]
        what = ("unknown field" if err["type"] == "extra_forbidden"
                else err["msg"][0].lower() + err["msg"][1:])
        raise ConfigurationError(f"laboratory configuration {file}: {_field(err['loc'])}: "
                                 f"{what}{shown}") from None
    database = config.records.database
    if database and "://" not in database and not Path(database).expanduser().is_absolute():
        # an SQLite file named relative to the configuration: beside it, wherever one works
        config = config.model_copy(update={"records": RecordsConfig(
            database=str(file.resolve().parent / database))})
    return config.model_copy(update={"source": str(file)})


@contextmanager
def use_config(path: str | os.PathLike[str] | None) -> Iterator[None]:
    """Make `path` the configuration file for the calls inside the block (None: no change).

    What ``--config FILE`` does for one command; the file is read (and refused) at once.

    Raises
    ------
    ConfigurationError
        As :func:`load_config`.
    """
    if path is None:
        yield
        return
    load_config(path)
    token = _chosen.set(Path(path))
    try:
        yield
    finally:
        _chosen.reset(token)
