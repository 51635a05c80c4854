"""``/runs/new``: choose a plan, the station and the units; validate; start (docs/web.md).

The plan comes from the plan folder (``--plans-dir``) or an upload, and is validated by the
project's plan validation (:mod:`imucalib.web.plan_check`), its problems shown per step and
field. The run is started by the supervisor — the same runner as ``imucalib run``, in a worker
process — with a copy of the plan kept in the runs folder. Starting needs the station's lock;
it is audited (``start``). A station whose equipment is overdue for calibration is refused in
one line, unless an engineer gives the reason to use it (:mod:`imucalib.web.due_override`): the
reason goes to the run, to an ``override_due`` audit row of its own and to the ``start`` row.
"""

from __future__ import annotations

from datetime import UTC, date, datetime
from pathlib import Path
from typing import Annotated, Any, Final

from fastapi import APIRouter, Depends, File, Form, Request, UploadFile
from fastapi.responses import RedirectResponse
from starlette.concurrency import run_in_threadpool
from starlette.responses import Response

from imucalib.errors import CalibrationError
from imucalib.records.access import LoginSession
from imucalib.web.audit import record
from imucalib.web.auth import article, can, require
from imucalib.web.context import context_of
from imucalib.web.due_override import due_station_name, overdue_equipment, overdue_line
from imucalib.web.lock import require_lock
from imucalib.web.plan_check import FieldError, check_plan, check_serials
from imucalib.web.render import WebError, render

__all__ = ["router"]

#: The largest plan file accepted. [bytes]
MAX_PLAN_BYTES: Final = 1_000_000
router = APIRouter()


def _tomls(folder: Path | None) -> list[str]:
    if folder is None or not folder.is_dir():
        return []
    return sorted(p.name for p in folder.glob("*.toml") if p.is_file())


def _form(request: Request, *, status: int = 200, errors: list[FieldError] | None = None,
          chosen: str = "", station: str = "sim", serials: str = "",
          override_due: str = "") -> Response:
    web = context_of(request)
    return render(request, "run_new.html", status=status, plans=_tomls(web.plans_dir),
                  stations=["sim", *_tomls(web.stations_dir)], errors=errors or [],
                  chosen=chosen, chosen_station=station, serials=serials,
                  override_due=override_due)


@router.get("/runs/new")
async def new_run_page(request: Request,
                       login: Annotated[LoginSession, Depends(require("run"))]) -> Response:
    """Show the form."""
    return _form(request)


def _in_folder(folder: Path | None, name: str, what: str) -> Path:
    if folder is None or not name or name != Path(name).name or not name.endswith(".toml"):
        raise WebError(422, f"{what} must be one of the listed files; got {name!r}")
    path = folder / name
    if not path.is_file():
        raise WebError(422, f"{what} {name!r} is not in {folder}")
    return path


@router.post("/runs/new")
async def start_run(request: Request,
                    login: Annotated[LoginSession, Depends(require("run"))],
                    plan_file: Annotated[str, Form()] = "",
                    station: Annotated[str, Form()] = "sim",
                    serials: Annotated[str, Form()] = "",
                    override_due: Annotated[str, Form()] = "",
                    plan_upload: Annotated[UploadFile | None, File()] = None) -> Response:
    """Validate the plan, the station and the serials; start the run; go to its page.

    `override_due` is the reason to start on equipment overdue for calibration (engineers only,
    :mod:`imucalib.web.due_override`).
    """
    web = context_of(request)
    override = override_due.strip()[:500]
    if override and not can(login, "override_due"):
        raise WebError(403, f"{login.user.name} is {article(login.user.role)}: only an "
                            "engineer may start a run on equipment overdue for calibration")
    await require_lock(request, login)
    if plan_upload is not None and plan_upload.filename:
        raw = await plan_upload.read(MAX_PLAN_BYTES + 1)
        source = Path(plan_upload.filename).name
    elif plan_file:
        raw = _in_folder(web.plans_dir, plan_file, "the plan").read_bytes()[:MAX_PLAN_BYTES + 1]
        source = plan_file
    else:
        return _form(request, status=422, errors=[FieldError(None, "plan", "choose a plan "
                     "from the folder or upload one; got neither")], station=station,
                     serials=serials)
    problems: list[FieldError] = []
    if len(raw) > MAX_PLAN_BYTES:
        problems.append(FieldError(None, "plan", f"a plan file is at most {MAX_PLAN_BYTES} "
                                                 f"bytes; got more ({source})"))
        text = ""
    else:
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError:
            text = ""
            problems.append(FieldError(None, "plan", f"a plan is UTF-8 TOML text; {source} "
                                                     "is not UTF-8"))
    station_spec = "sim"
    if station != "sim":
        station_spec = str(_in_folder(web.stations_dir, station, "the station"))
    plan = None
    if not problems:
        plan, found = await run_in_threadpool(check_plan, text, source, station)
        problems += found
    units, found = check_serials(serials)
    problems += found
    overdue: list[Any] = []
    if not problems and plan is not None:
        name = due_station_name(station_spec)
        equipment = await run_in_threadpool(web.records.equipment)
        overdue = overdue_equipment(equipment, name, date.today())
        if overdue and not override:
            problems.append(FieldError(None, "override_due", overdue_line(
                name, overdue, may_override=can(login, "override_due"))))
    if problems or plan is None:
        return _form(request, status=422, errors=problems, chosen=plan_file, station=station,
                     serials=serials, override_due=override)
    # an override without overdue equipment overrides nothing: it is neither passed nor audited
    extra: dict[str, Any] = {"override_due": override} if overdue else {}
    kept = web.runs_dir / "plans" / f"{datetime.now(UTC):%Y%m%dT%H%M%S%fZ}-{Path(source).name}"
    try:
        kept.parent.mkdir(parents=True, exist_ok=True)
        kept.write_text(text, encoding="utf-8")
        supervisor = web.runs()
        run_id = await run_in_threadpool(lambda: supervisor.start(
            kept, station=station_spec, serials=units, operator=login.user.name, **extra))
    except (CalibrationError, OSError) as exc:
        raise WebError(409, f"the run could not start: {exc}") from exc
    from imucalib.plan.io import plan_hash

    details: dict[str, Any] = {"plan": plan.name, "plan_hash": plan_hash(plan),
                               "station": station, "serials": units, "source": source}
    if overdue:
        details["override_due"] = override
        details["overdue_equipment"] = [e.equipment_id for e in overdue]
        # the override is an action of its own: its row names the engineer and the equipment
        await record(request, login, "override_due", run_ref=str(run_id), details={
            "reason": override, "overdue_equipment": details["overdue_equipment"]})
    await record(request, login, "start", run_ref=str(run_id), details=details)
    return RedirectResponse(f"/runs/{run_id}", status_code=303)
