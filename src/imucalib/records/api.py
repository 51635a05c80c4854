"""The records: append and query units, stations, equipment, runs, results, reviews, users.

Contents
--------
:class:`Records`
    One object per database; each method is one transaction (docs/records.md).
:func:`open_records`
    Resolve the URL, bring the schema up to date, return a :class:`Records`.

Every write appends rows to the hash chains (:mod:`imucalib.records.chain`); nothing is ever
updated or deleted. An amendment is a new result, version n + 1, whose ``replaces`` names the
result it supersedes; "current" means not replaced.

What a user reads back (history, drift, due units and equipment, runs) is built by
:mod:`imucalib.records.queries`, which also states the due rules (R.4) and (R.5).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from datetime import UTC, date, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final, TypeVar

from sqlalchemy import Engine, func, select, true
from sqlalchemy.exc import DBAPIError, IntegrityError, OperationalError, StatementError
from sqlalchemy.orm import Session

from imucalib.errors import CalibrationError, InvalidInputError, RecordsError
from imucalib.io.hashing import file_sha256
from imucalib.records import chain, queries
from imucalib.records.access_api import AccessRecords
from imucalib.records.canonical import canonical_json
from imucalib.records.engine import BEGIN_OPTION, make_engine, resolve_url, safe_url, upgrade
from imucalib.records.queries import dangling, to_utc
from imucalib.records.schema import (
    CHAINED,
    Equipment,
    Result,
    ResultParameter,
    Review,
    Run,
    RunEquipment,
    Station,
    Unit,
    User,
)
from imucalib.records.views import (
    ChainHead,
    DriftPoint,
    DueUnit,
    EquipmentView,
    HistoryEntry,
    ParameterRow,
    Problem,
    ReleaseStatus,
    RunView,
    UserView,
    VerifyReport,
)

if TYPE_CHECKING:  # the result models (numpy) are imported where a result is recorded
    from imucalib.models.procedure_result import ProcedureResult
    from imucalib.models.result import CalibrationResult

__all__ = ["DEFAULT_INTERVAL_DAYS", "Records", "open_records"]

#: Recalibration interval of a unit without its own. [d]
DEFAULT_INTERVAL_DAYS: Final = 365
#: Attempts of a transaction that met a busy database or a deadlock.
ATTEMPTS: Final = 8
#: What reading a row of unexpected type or shape raises (a stored value that is not of its
#: column's type, a dangling reference): reported as a database problem, not a crash.
DATA_ERRORS: Final = (ValueError, TypeError, KeyError, IndexError, AttributeError,
                      AssertionError, ArithmeticError, RecursionError, StatementError)
_T = TypeVar("_T")


def _data_problem(url: str, exc: BaseException) -> RecordsError:
    what = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    return RecordsError(f"the records database {url} has a problem: {what[:300]}; run "
                        "`imucalib records verify` to find the rows")


def _software_version() -> str:
    from imucalib import __version__

    return __version__


def _json_text(value: Mapping[str, Any] | None, name: str) -> str:
    try:
        return canonical_json(dict(value or {}))
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"`{name}` must be JSON-able; got {value!r} ({exc})") from exc


def parameter_rows(result: ProcedureResult | CalibrationResult) -> list[ParameterRow]:
    """Return a result's parameters as the records keep them: σ as reported.

    A procedure's result gives its ``parameter_rows()`` (the result contract,
    :class:`~imucalib.models.procedure_result.ProcedureResult`); a CalibrationResult its
    parameters with the standard uncertainties as reported, Birge-scaled by √(χ²/ν) for a group
    whose fit is a misfit (its noise-only σ stay in the stored document's covariance). A row
    whose value or standard uncertainty is not a finite number (a quantity a procedure reports
    as not estimated: P3's nominal radii, say) is left out of the parameter rows; the result's
    stored document keeps it.
    """
    from imucalib.models.procedure_result import calibration_rows
    from imucalib.models.result import CalibrationResult

    rows = (calibration_rows(result) if isinstance(result, CalibrationResult)
            else result.parameter_rows())
    return [ParameterRow(r.name, float(r.value), float(r.std), r.unit) for r in rows
            if math.isfinite(r.value) and math.isfinite(r.std)]


class Records(AccessRecords):
    """The calibration records of one database (use :func:`open_records`).

    The web page's methods (passwords, sessions, the audit trail, the station lock) come from
    :class:`~imucalib.records.access_api.AccessRecords`.

    Parameters
    ----------
    engine : Engine
        From :func:`imucalib.records.engine.make_engine`, schema already at head.
    """

    def __init__(self, engine: Engine, signing: Path | None = None) -> None:
        from imucalib.records.signing import signing_folder

        self.engine = engine
        self.url = safe_url(engine.url.render_as_string(hide_password=False))
        #: The key folder: station key, station.pub, anchor log (docs/records.md, "Signing").
        self.signing_folder = (signing if signing is not None else
                               signing_folder(engine.url.render_as_string(hide_password=False)))
        self._key: Any = None
        self._values_checked = False

    def close(self) -> None:
        """Release the connections."""
        self.engine.dispose()

    def __enter__(self) -> Records:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    # --- transactions -----------------------------------------------------------------------
    def _run(self, work: Callable[[Session], _T], *, write: bool,
             anchor_key: Any = None, checked: bool = True) -> _T:
        """Run `work` in one transaction, retried when the database is busy.

        A write on SQLite begins with ``BEGIN IMMEDIATE``; a read sees one snapshot (SQLite's
        WAL read transaction, PostgreSQL's REPEATABLE READ), so :meth:`verify` never sees a
        result without the parameters committed with it. With `checked`, a database holding a
        value not of its column's type is refused first (one line that asks for
        ``records verify``; :func:`~imucalib.records.verify.first_bad_value`).
        """
        sqlite = self.engine.dialect.name == "sqlite"
        for attempt in range(ATTEMPTS):
            try:
                appended: dict[str, tuple[int, str]] = {}
                key = anchor_key
                with self.engine.connect() as conn:
                    if write and sqlite:
                        conn.execution_options(**{BEGIN_OPTION: "BEGIN IMMEDIATE"})
                    elif not write and not sqlite:  # one snapshot for all a query reads
                        conn.execution_options(isolation_level="REPEATABLE READ")
                    with conn.begin(), Session(bind=conn, expire_on_commit=False) as session:
                        if checked:
                            self._check_values(session)
                        if write and anchor_key is None:
                            self._sign_with(session)
                            key = self._key
                        out = work(session)
                        session.flush()
                        appended = dict(session.info.get("appended", {}))
                if appended and key is not None:
                    self._anchor(appended, key)
                return out
            except CalibrationError:
                raise
            except OperationalError as exc:
                text = str(exc.orig).lower()
                transient = ("locked" in text or "busy" in text or "deadlock" in text
                             or "could not serialize" in text)
                if not transient or attempt == ATTEMPTS - 1:
                    raise RecordsError(f"records database {self.url}: {exc.orig}") from exc
                time.sleep(0.05 * 2 ** attempt)
            except IntegrityError as exc:
                raise RecordsError(f"records database {self.url} refused the write: "
                                   f"{exc.orig}") from exc
            except DBAPIError as exc:
                raise RecordsError(f"records database {self.url}: {exc.orig}") from exc
            except DATA_ERRORS as exc:
                raise _data_problem(self.url, exc) from exc
        raise AssertionError("unreachable")  # pragma: no cover

    def _check_values(self, session: Session) -> None:
        """Refuse a database holding a value not of its column's type (once per object)."""
        from imucalib.records.verify import first_bad_value

        if self._values_checked:
            return
        bad = first_bad_value(session)
        if not bad:
            self._values_checked = True
        else:
            raise RecordsError(f"the records database {self.url} has a problem: {bad}; run "
                               "`imucalib records verify`")

    # --- signing ----------------------------------------------------------------------------
    def _sign_with(self, session: Session) -> None:
        """Give `session` the station key to sign with (registering it in a new database)."""
        from imucalib.records.keys import ensure_signer

        key, key_id = ensure_signer(session, self.signing_folder, self._key)
        self._key = key
        session.info["signer"] = (key, key_id)

    def _anchor(self, heads: dict[str, tuple[int, str]], key: Any) -> None:
        """Append the new chain heads to the anchor log, Eq. (R.10), signed by `key`."""
        from imucalib.records.anchor_log import append_heads
        from imucalib.records.signing import LOG_FILE

        append_heads(self.signing_folder / LOG_FILE, key, heads)

    def trusted_keys(self) -> list[str]:
        """Return the public keys verify trusts: the key file's, else ``station.pub``'s."""
        from imucalib.records.signing import KEY_FILE, PUB_FILE, load_key, read_public

        key = load_key(self.signing_folder / KEY_FILE)
        if key is not None:
            return [key.public_hex]
        pub = read_public(self.signing_folder / PUB_FILE)
        return [pub] if pub else []

    def rekey(self, reason: str, *, lost: bool = False) -> int:
        """Register a new station key and make it the key file; return its id.

        The new key is endorsed by the current key file's key (R.8); with `lost` the current
        key file is gone and the new key is registered without endorsement (docs/records.md,
        "A lost key"). The old key file is kept as ``station.key.<fingerprint>.retired``.

        Raises
        ------
        RecordsError
            No key file without `lost`; a key file with `lost`; an empty reason.
        """
        from imucalib.records.keys import register_new_key
        from imucalib.records.signing import KEY_FILE, create_key, load_key, write_public

        if not reason.strip():
            raise RecordsError("a new key needs a reason (why the key is replaced); got an "
                               "empty one")
        path = self.signing_folder / KEY_FILE
        old = load_key(path)
        if old is None and not lost:
            raise RecordsError(f"there is no key file {path} to endorse a new key with: if the "
                               "key was lost, pass --lost-key (docs/records.md, \"A lost key\")")
        if old is not None and lost:
            raise RecordsError(f"--lost-key, but the key file {path} is there: rekey without "
                               "--lost-key (the old key endorses the new one)")
        staged = path.with_name(KEY_FILE + ".new")
        staged.unlink(missing_ok=True)
        new = create_key(staged, publish=False)
        try:
            new_id = self._run(lambda s: register_new_key(s, old, new, reason.strip()),
                               write=True, anchor_key=new)
        except BaseException:
            staged.unlink(missing_ok=True)
            raise
        try:
            if old is not None:
                path.replace(path.with_name(f"{KEY_FILE}.{old.fingerprint}.retired"))
            staged.replace(path)
        except OSError as exc:
            raise RecordsError(f"key {new_id} is registered but its file {staged} could not "
                               f"become {path}: move it there by hand ({exc})") from exc
        from imucalib.records.signing import StationKey

        self._key = StationKey(path, new.private, new.public_hex)
        write_public(self._key)
        return new_id

    # --- units, stations, equipment ---------------------------------------------------------
    @staticmethod
    def _new_unit(session: Session, serial: str, model: str, maker: str,
                  specification: Mapping[str, Any] | None,
                  recal_interval_days: int | None) -> Unit:
        if not serial:
            raise InvalidInputError("`serial` must be a non-empty string; got ''")
        if recal_interval_days is not None and recal_interval_days <= 0:
            raise InvalidInputError("`recal_interval_days` must be > 0; got "
                                    f"{recal_interval_days}")
        return chain.append(session, Unit(
            serial=serial, model=model, maker=maker,
            specification_json=_json_text(specification, "specification"),
            recal_interval_days=recal_interval_days))

    def add_unit(self, serial: str, model: str = "", maker: str = "",
                 specification: Mapping[str, Any] | None = None,
                 recal_interval_days: int | None = None) -> int:
        """Add a unit and return its id.

        Raises
        ------
        RecordsError
            A unit with that serial is already recorded.
        """
        def work(session: Session) -> int:
            chain.lock(session, Unit)
            if session.scalars(select(Unit.id).where(Unit.serial == serial)).first():
                raise RecordsError(f"a unit with serial {serial!r} is already recorded")
            return self._new_unit(session, serial, model, maker, specification,
                                  recal_interval_days).id
        return self._run(work, write=True)

    def get_or_create_unit(self, serial: str, model: str = "", maker: str = "",
                           specification: Mapping[str, Any] | None = None,
                           recal_interval_days: int | None = None) -> int:
        """Return the id of the unit `serial`, adding it (with the other fields) if new."""
        return self._run(lambda s: self._get_or_create(s, serial, model, maker, specification,
                                                       recal_interval_days), write=True)

    def _get_or_create(self, session: Session, serial: str, model: str = "", maker: str = "",
                       specification: Mapping[str, Any] | None = None,
                       recal_interval_days: int | None = None) -> int:
        chain.lock(session, Unit)
        found = session.scalars(select(Unit.id).where(Unit.serial == serial)).first()
        if found is not None:
            return int(found)
        return self._new_unit(session, serial, model, maker, specification,
                              recal_interval_days).id

    def add_station(self, name: str, location: str = "") -> int:
        """Add a station and return its id (RecordsError if the name is taken)."""
        def work(session: Session) -> int:
            chain.lock(session, Station)
            if session.scalars(select(Station.id).where(Station.name == name)).first():
                raise RecordsError(f"a station named {name!r} is already recorded")
            return chain.append(session, Station(name=name, location=location)).id
        return self._run(work, write=True)

    @staticmethod
    def _station_id(session: Session, station: int | str | None) -> int | None:
        if station is None:
            return None
        where = Station.id == station if isinstance(station, int) else Station.name == station
        found = session.scalars(select(Station.id).where(where)).first()
        if found is None:
            raise RecordsError(f"no station {station!r} in the records")
        return int(found)

    def add_equipment(self, station: int | str | None, kind: str, model: str = "",
                      serial: str = "", certificate: str = "",
                      calibrated_on: date | None = None, due_on: date | None = None) -> int:
        """Add a piece of equipment with its certificate and return its id."""
        def work(session: Session) -> int:
            return chain.append(session, Equipment(
                station_id=self._station_id(session, station), kind=kind, model=model,
                serial=serial, certificate=certificate, calibrated_on=calibrated_on,
                due_on=due_on)).id
        return self._run(work, write=True)

    def recertify_equipment(self, equipment_id: int, certificate: str, calibrated_on: date,
                            due_on: date) -> int:
        """Record a new certificate of a piece of equipment; return the new row's id.

        The old row stays; the new one ``replaces`` it and is what :meth:`due_equipment` reads.
        """
        def work(session: Session) -> int:
            old = session.get(Equipment, equipment_id)
            if old is None:
                raise RecordsError(f"no equipment with id {equipment_id} in the records")
            chain.lock(session, Equipment)
            newer = session.scalars(select(Equipment.id)
                                    .where(Equipment.replaces_id == equipment_id)).first()
            if newer is not None:
                raise RecordsError(f"equipment {equipment_id} was already replaced by {newer}; "
                                   f"recertify {newer}")
            return chain.append(session, Equipment(
                station_id=old.station_id, kind=old.kind, model=old.model, serial=old.serial,
                certificate=certificate, calibrated_on=calibrated_on, due_on=due_on,
                replaces_id=equipment_id)).id
        return self._run(work, write=True)

    # --- runs, results, reviews -------------------------------------------------------------
    def record_run(self, *, plan_name: str = "", plan_hash: str = "", procedure: str = "",
                   recording: str | os.PathLike[str] | None = None,
                   recording_sha256: str | None = None,
                   environment: Mapping[str, Any] | None = None, operator: str = "",
                   software_version: str | None = None, station: int | str | None = None,
                   equipment: Sequence[int] = (), started_utc: datetime | None = None,
                   ended_utc: datetime | None = None) -> int:
        """Record a run and return its id.

        Parameters
        ----------
        recording : path, optional
            The Recording file; stored as an absolute path. Its SHA-256 is computed when
            `recording_sha256` is not given.
        environment : mapping, optional
            JSON-able conditions (temperature, humidity, …).
        software_version : str, optional
            Default: this imucalib's version.
        equipment : sequence of int
            Ids of the equipment used.

        Raises
        ------
        RecordsError
            A recording that cannot be read when its SHA-256 must be computed; an unknown
            station or equipment id.
        """
        path = "" if recording is None else str(Path(recording).expanduser().resolve())
        sha = recording_sha256 or ""
        if path and not sha:
            try:
                sha = file_sha256(path)
            except OSError as exc:
                raise RecordsError(f"cannot hash the recording {path}: {exc}") from exc
        env_text = _json_text(environment, "environment")
        ids = sorted({int(i) for i in equipment})

        def work(session: Session) -> int:
            from imucalib.records.users import check_operator

            station_id = self._station_id(session, station)
            for eq in ids:
                if session.get(Equipment, eq) is None:
                    raise RecordsError(f"no equipment with id {eq} in the records")
            run = chain.append(session, Run(
                plan_name=plan_name, plan_hash=plan_hash, procedure=procedure,
                recording_path=path, recording_sha256=sha, environment_json=env_text,
                operator=check_operator(session, operator),
                software_version=software_version or _software_version(),
                station_id=station_id, started_utc=to_utc(started_utc),
                ended_utc=to_utc(ended_utc)), equipment=ids)
            session.add_all(RunEquipment(run_id=run.id, equipment_id=eq) for eq in ids)
            return run.id
        return self._run(work, write=True)

    @staticmethod
    def _append_result(session: Session, *, run_id: int, serial: str, result: Any,
                       passed: bool | None, verification: Mapping[str, Any] | None,
                       version: int, replaces: int | None, reason: str,
                       unit_id: int | None = None) -> int:
        if session.get(Run, run_id) is None:
            raise RecordsError(f"no run with id {run_id} in the records")
        from imucalib.models.result import CalibrationResult
        from imucalib.models.result_document import result_document

        rows = parameter_rows(result)
        if isinstance(result, CalibrationResult):
            document, model = result.to_dict(), result.model
        else:  # the result document (format version 4, imucalib.models.result_document)
            cal = result.calibration
            document, model = result_document(result), "" if cal is None else cal.model
        row = Result(run_id=run_id, unit_id=unit_id, procedure=str(result.procedure),
                     model=model, passed=passed,
                     verification_json=_json_text(verification, "verification"),
                     document_json=_json_text(document, "the result document"), version=version,
                     replaces_id=replaces, amendment_reason=reason)
        params = [ResultParameter(name=r.name, value=r.value, std=r.std, unit=r.unit)
                  for r in rows]
        if len({p.name for p in params}) != len(params):
            raise InvalidInputError(f"parameter names of result for {serial!r} must be unique")
        chain.append(session, row, parameters=chain.parameter_content(params))
        for p in params:
            p.result_id = row.id
        session.add_all(params)
        return row.id

    def record_result(self, run_id: int, result: Any, passed: bool | None = None,
                      verification: Mapping[str, Any] | None = None, *,
                      serial: str | None = None) -> int:
        """Record a unit's result of a run (version 1) and return its id.

        Parameters
        ----------
        run_id : int
        result : ProcedureResult or CalibrationResult
            One unit's result (the result contract); its document is stored (a
            procedure's result as the version-4 result document).
        passed : bool or None
            The decision: passed, failed, or not decided.
        verification : mapping, optional
            The verification outcome (JSON-able).
        serial : str, optional
            The unit; default the result's (``unit``, a CalibrationResult's ``sensor_id``). A
            new serial adds the unit.
        """
        from imucalib.models.result import CalibrationResult

        serial = serial or (result.sensor_id if isinstance(result, CalibrationResult)
                            else str(result.unit))
        if not serial:
            raise InvalidInputError("the result names no unit: give `serial` or a result with "
                                    "`sensor_id`")

        def work(session: Session) -> int:
            unit_id = self._get_or_create(session, serial)
            return self._append_result(session, run_id=run_id, serial=serial, result=result,
                                       passed=passed, verification=verification, version=1,
                                       replaces=None, reason="", unit_id=unit_id)
        return self._run(work, write=True)

    def amend(self, result_id: int, result: Any, reason: str, passed: bool | None = None,
              verification: Mapping[str, Any] | None = None) -> int:
        """Record a new version of result `result_id` and return its id; the old one stays.

        `passed` None keeps the decision of the result amended (a FAIL stays a FAIL unless
        the new result decides otherwise).

        Raises
        ------
        RecordsError
            An unknown result, one that was already amended (amend its successor), or an
            empty `reason`.
        """
        if not reason.strip():
            raise RecordsError("an amendment needs a reason; got an empty one")

        def work(session: Session) -> int:
            chain.lock(session, Result)
            old = session.get(Result, result_id)
            if old is None:
                raise RecordsError(f"no result with id {result_id} in the records")
            newer = session.scalars(select(Result.id)
                                    .where(Result.replaces_id == result_id)).first()
            if newer is not None:
                raise RecordsError(f"result {result_id} was already amended by result {newer}; "
                                   f"amend {newer}")
            unit = session.get(Unit, old.unit_id)
            if unit is None:
                raise dangling("results", old.id, "unit", old.unit_id)
            decided = old.passed if passed is None else passed   # the decision stays
            return self._append_result(session, run_id=old.run_id, serial=unit.serial,
                                       result=result, passed=decided, verification=verification,
                                       version=old.version + 1, replaces=result_id,
                                       reason=reason, unit_id=old.unit_id)
        return self._run(work, write=True)

    def record_analysis(self, run_id: int, result: Any, passed: bool | None = None,
                        verification: Mapping[str, Any] | None = None, *,
                        serial: str | None = None, reason: str = "") -> tuple[int, int | None]:
        """Record a unit's result of a run: version 1, or the next version of its current one.

        The first analysis of a unit in run `run_id` is version 1 (as :meth:`record_result`);
        a further analysis by the same procedure in the same run (a re-analysis of the same
        recording) is the next version of the unit's current result of that procedure there:
        it ``replaces`` it, with `reason` (who and why) as its ``amendment_reason``. One
        transaction, so two analyses at once cannot both become version 1.

        Returns
        -------
        (int, int or None)
            The new result's id, and the id of the result it replaces (None for version 1).

        Raises
        ------
        RecordsError
            An unknown run, or a re-analysis with an empty `reason`.
        """
        from imucalib.models.result import CalibrationResult

        serial = serial or (result.sensor_id if isinstance(result, CalibrationResult)
                            else str(result.unit))
        if not serial:
            raise InvalidInputError("the result names no unit: give `serial` or a result with "
                                    "`sensor_id`")

        def work(session: Session) -> tuple[int, int | None]:
            if session.get(Run, run_id) is None:
                raise RecordsError(f"no run with id {run_id} in the records")
            unit_id = self._get_or_create(session, serial)
            chain.lock(session, Result)
            mine = session.scalars(select(Result).where(
                Result.run_id == run_id, Result.unit_id == unit_id,
                Result.procedure == str(result.procedure)).order_by(Result.seq)).all()
            replaced = set(session.scalars(select(Result.replaces_id).where(
                Result.replaces_id.in_([r.id for r in mine]))))
            current = [r for r in mine if r.id not in replaced]
            if not current:
                return self._append_result(session, run_id=run_id, serial=serial,
                                           result=result, passed=passed,
                                           verification=verification, version=1,
                                           replaces=None, reason="", unit_id=unit_id), None
            old = current[-1]
            if not reason.strip():
                raise RecordsError(f"run {run_id} already holds result {old.id} of unit "
                                   f"{serial!r}; a re-analysis needs a reason; got an empty one")
            return self._append_result(session, run_id=run_id, serial=serial, result=result,
                                       passed=passed, verification=verification,
                                       version=old.version + 1, replaces=old.id,
                                       reason=reason, unit_id=unit_id), old.id
        return self._run(work, write=True)

    def review(self, result_id: int, who: str, approved: bool, comment: str = "",
               when: datetime | None = None) -> int:
        """Record a review (approval or rejection) of a result and return its id.

        The review control (docs/records.md, "Users and roles"; rules (U.1), (U.3) of
        :mod:`imucalib.records.users`): only the current version of a result is reviewed, a
        rejection needs a `comment`, and, once the database has users, `who` must be an active
        user with role reviewer or admin who is not the operator of the result's run.

        Raises
        ------
        RecordsError
            An unknown or amended result, or a reviewer the control refuses (named, with why).
        InvalidInputError
            An empty `who`, or a rejection without a comment.
        """
        from imucalib.records import users

        who = who.strip()
        if not who:
            raise InvalidInputError("`who` must name the reviewer; got ''")

        def work(session: Session) -> int:
            name = users.check_review(session, result_id, who, bool(approved), comment)
            return chain.append(session, Review(
                result_id=result_id, reviewer=name, approved=bool(approved), comment=comment,
                reviewed_utc=to_utc(when) or datetime.now(UTC))).id
        return self._run(work, write=True)

    def reviews_unverified(self) -> str:
        """Return why reviews cannot be shown as authorisation ("" when the records verify).

        A review is shown (``records show``, a certificate) only after the records verify:
        every hash, signature and anchor (recordings aside). Else a review could be a forged
        row; the reason names the first problem and asks for ``records verify``.
        """
        problems = self.verify_report(recordings=False).problems
        if not problems:
            return ""
        return (f"the records do not verify ({len(problems)} problem(s), first: {problems[0]});"
                " a review is not shown as authorisation until `imucalib records verify` is "
                "clean")

    def release_status(self, result_id: int) -> ReleaseStatus:
        """Return whether a result is released, and by whom, when, with what decision.

        Released: the latest review of the result's current version approves it, made by a
        user who was then an active reviewer or admin and is not the run's operator (rule
        (U.4) of :mod:`imucalib.records.users`). An amended result is not released (its
        ``current_id`` names the version that may be).

        Raises
        ------
        RecordsError
            An unknown result.
        """
        from imucalib.records import users

        return self._run(lambda s: users.release_status(s, result_id), write=False)

    # --- users ------------------------------------------------------------------------------
    def add_user(self, name: str, initials: str = "", role: str = "operator", *,
                 by: str | None = None) -> int:
        """Add a user (role operator, engineer, reviewer or admin) and return its id.

        Parameters
        ----------
        by : str, optional
            Who is adding (recorded as ``added_by``). Needed once the database has users: an
            active user, and an admin once an active admin exists (rule (U.2) of
            :mod:`imucalib.records.users`).

        Raises
        ------
        RecordsError
            A name already used (ignoring case), or an actor the rule refuses.
        InvalidInputError
            An empty name or an unknown role.
        """
        from imucalib.records import users

        return self._run(lambda s: users.add_user(s, name, initials, role, by), write=True)

    def disable_user(self, name: str, reason: str, *, by: str | None = None) -> int:
        """Disable a user (a new ``user_events`` row; the user stays); return the event's id.

        A disabled user can no longer act; what they did stays valid. The last active user and
        the last active admin cannot be disabled. `by` as in :meth:`add_user`.
        """
        from imucalib.records import users

        return self._run(lambda s: users.change_user(s, name, "disable", reason, by),
                         write=True)

    def enable_user(self, name: str, reason: str, *, by: str | None = None) -> int:
        """Enable a disabled user again (a new ``user_events`` row); return the event's id."""
        from imucalib.records import users

        return self._run(lambda s: users.change_user(s, name, "enable", reason, by),
                         write=True)

    def users(self) -> list[UserView]:
        """Return every user (active or not), in the order they were added."""
        from imucalib.records import users

        return self._run(users.users_of, write=False)

    def user(self, name: str) -> UserView:
        """Return the user called `name` (RecordsError if there is none)."""
        from imucalib.records import users

        def work(session: Session) -> UserView:
            row = session.scalars(select(User).where(User.name == name)).first()
            if row is None:
                known = ", ".join(u.name for u in users.users_of(session)) or "none"
                raise RecordsError(f"no user named {name!r} in the records; users: {known}")
            return users.user_view(session, row)
        return self._run(work, write=False)

    # --- queries (the read side: imucalib.records.queries) ----------------------------------
    def units(self) -> list[str]:
        """Return every recorded serial number, in the order they were added."""
        return self._run(lambda s: list(s.scalars(select(Unit.serial).order_by(Unit.seq))),
                         write=False)

    def result_document(self, result_id: int) -> dict[str, Any]:
        """Return the stored document of a result.

        A procedure's result document (format version 4,
        :func:`~imucalib.models.result_document.result_document`) or a CalibrationResult's
        ``to_dict()``; ``CalibrationResult.from_dict`` rebuilds the calibration from either
        (when the result has one).
        """
        return self._run(lambda s: queries.result_document(s, result_id), write=False)

    def history(self, serial: str) -> list[HistoryEntry]:
        """Return every result of unit `serial` in recording order, amended ones included.

        An amended result has ``replaced_by`` set; its amendment has ``replaces`` and
        ``amendment_reason``.

        Raises
        ------
        RecordsError
            An unknown serial (the message lists known ones).
        """
        return self._run(lambda s: queries.unit_history(s, serial), write=False)

    def result(self, result_id: int) -> HistoryEntry:
        """Return one result as a history entry (RecordsError if unknown)."""
        def work(session: Session) -> HistoryEntry:
            row = session.get(Result, result_id)
            if row is None:
                raise RecordsError(f"no result with id {result_id} in the records")
            return queries.history_entries(session, [row])[0]
        return self._run(work, write=False)

    def drift(self, serial: str, parameter: str) -> list[DriftPoint]:
        """Return `parameter` of unit `serial` across its current results, oldest first.

        Raises
        ------
        RecordsError
            An unknown serial, or a parameter none of its results carries.
        """
        return queries.drift_points(serial, parameter, self.history(serial))

    def due_units(self, as_of: date | None = None,
                  interval_days: int = DEFAULT_INTERVAL_DAYS) -> list[DueUnit]:
        """Return the units due for recalibration on `as_of` (default today), Eq. (R.4)."""
        day = as_of or datetime.now(UTC).date()
        return [u for u in self.unit_status(interval_days)
                if u.due_on is None or u.due_on <= day]

    def unit_status(self, interval_days: int = DEFAULT_INTERVAL_DAYS) -> list[DueUnit]:
        """Return every unit with its last good calibration and when it is due, Eq. (R.4).

        A unit never calibrated (or only by failed results) has ``last_calibrated`` and
        ``due_on`` None; amended results count by their current version.
        """
        if interval_days <= 0:
            raise InvalidInputError(f"`interval_days` must be > 0; got {interval_days}")
        return self._run(lambda s: queries.unit_status(s, interval_days), write=False)

    def equipment(self, *, current_only: bool = True) -> list[EquipmentView]:
        """Return the equipment (by default only current certificates), in recording order."""
        return self._run(lambda s: queries.equipment_views(s, current_only=current_only),
                         write=False)

    def due_equipment(self, as_of: date | None = None) -> list[EquipmentView]:
        """Return the current equipment whose certificate is due on `as_of`, Eq. (R.5)."""
        day = as_of or datetime.now(UTC).date()
        return [e for e in self.equipment() if e.due_on is None or e.due_on <= day]

    def runs_of_plan(self, plan: str) -> list[RunView]:
        """Return every run whose plan hash or plan name is `plan`, oldest first."""
        return self._run(lambda s: queries.runs_of_plan(s, plan), write=False)

    def run(self, run_id: int) -> RunView:
        """Return one run (RecordsError if unknown)."""
        def work(session: Session) -> RunView:
            row = session.get(Run, run_id)
            if row is None:
                raise RecordsError(f"no run with id {run_id} in the records")
            return queries.run_view(session, row)
        return self._run(work, write=False)

    def run_of_recording(self, sha256: str,
                         path: str | os.PathLike[str] | None = None) -> RunView | None:
        """Return the run that recorded a recording, known by its SHA-256 (None: none did).

        This is how ``calibrate`` finds the run a recording belongs to (docs/records.md, "One
        calibration, one run"): the bytes decide, not the file's name or folder. Among several
        runs of the same bytes (records made before calibrations were attached to their run)
        the one at the same absolute `path` is taken, else the first recorded.
        """
        if not sha256:
            return None
        want = "" if path is None else str(Path(path).expanduser().resolve())
        return self._run(lambda s: queries.run_of_recording(s, sha256, want), write=False)

    def read_snapshot(self, work: Callable[[Session], _T]) -> _T:
        """Return ``work(session)`` run on one consistent snapshot of the database, read-only.

        For a reader that gathers from many tables at once (the web page's lab overview,
        :mod:`imucalib.web.lab_state`): every query of `work` sees the same committed state
        (SQLite's WAL read transaction, PostgreSQL's REPEATABLE READ), as :meth:`verify` does.

        Raises
        ------
        RecordsError
            `work` added, changed or deleted a row (nothing of it is committed).
        """
        def guarded(session: Session) -> _T:
            out = work(session)
            if session.new or session.dirty or session.deleted:   # rolled back by _run
                raise RecordsError("a read of the records tried to change them; nothing was "
                                   "written")
            return out
        return self._run(guarded, write=False)

    # --- tamper evidence --------------------------------------------------------------------
    def heads(self) -> list[ChainHead]:
        """Return the head of every chain (keep them elsewhere; :meth:`verify` checks them)."""
        def work(session: Session) -> list[ChainHead]:
            out = []
            for model in CHAINED:       # the largest integer seq: a damaged row is skipped
                head = session.execute(select(model.seq, model.row_hash)
                                       .where(func.typeof(model.seq) == "integer"
                                              if sqlite else true())
                                       .order_by(model.seq.desc()).limit(1)).first()
                out.append(ChainHead(model.__tablename__,  # type: ignore[attr-defined]
                                     int(head[0]) if head else 0,
                                     str(head[1]) if head else ""))
            return out
        sqlite = self.engine.dialect.name == "sqlite"
        return self._run(work, write=False, checked=False)   # a damaged database: backed up

    def verify(self, *, recordings: bool = True,
               anchors: Iterable[ChainHead] = ()) -> list[Problem]:
        """Re-hash every row and recording; return every mismatch (empty: all is intact).

        :meth:`verify_report`'s problems (with the anchor log and the trusted key of the key
        folder).
        """
        return list(self.verify_report(recordings=recordings, anchors=anchors).problems)

    def verify_report(self, *, recordings: bool = True, anchors: Iterable[ChainHead] = (),
                      anchor_log: Path | None = None,
                      trusted_keys: Iterable[str] | None = None) -> VerifyReport:
        """Check every row's hash and signature, the anchor log, every recording.

        Parameters
        ----------
        recordings : bool
            Also re-hash each run's recording file.
        anchors : iterable of ChainHead
            Heads kept from an earlier :meth:`heads`; each must still be in its chain with the
            same hash (this catches a deleted last row).
        anchor_log : Path, optional
            Default: ``anchors.jsonl`` in the key folder.
        trusted_keys : iterable of str, optional
            Public keys (hex) to trust; default :meth:`trusted_keys`.
        """
        from imucalib.records.anchor_log import read_log
        from imucalib.records.signing import LOG_FILE
        from imucalib.records.verify import verify_report

        anchor_list = list(anchors)
        log = anchor_log if anchor_log is not None else self.signing_folder / LOG_FILE
        roots = list(self.trusted_keys() if trusted_keys is None else trusted_keys)
        present = log.exists()     # read before the snapshot: a later line names later rows
        lines = read_log(log) if present else ([], [])
        return self._run(lambda s: verify_report(s, recordings=recordings,
                                                 anchors=anchor_list, anchor_log=log,
                                                 trusted_keys=roots, log=lines,
                                                 log_present=present), write=False,
                         checked=False)


def open_records(url: str | None = None) -> Records:
    """Open (creating or upgrading as needed) the records database and return it.

    Parameters
    ----------
    url : str, optional
        A SQLAlchemy URL (``sqlite:///path.db``, ``postgresql+psycopg://user@host/db``) or an
        SQLite file path; default ``$IMUCALIB_DB``, else ``records.db`` in the user's data
        directory (docs/records.md, "Where the database is").

    Raises
    ------
    RecordsError
        An unusable URL, an unreachable database, or a schema newer than this software.
    """
    engine = make_engine(resolve_url(url))
    try:
        upgrade(engine)
    except BaseException:
        engine.dispose()
        raise
    return Records(engine)
