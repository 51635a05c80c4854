"""What every request of the web server reaches: the records, the supervisor, the settings.

:class:`WebContext` is stored on ``app.state.web`` by :func:`imucalib.web.app.create_app`;
:func:`context_of` finds it from a request or a WebSocket.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from imucalib.errors import CalibrationError

if TYPE_CHECKING:
    from fastapi.templating import Jinja2Templates
    from starlette.requests import HTTPConnection

    from imucalib.records.api import Records

__all__ = ["SupervisorUnavailableError", "WebContext", "context_of"]


class SupervisorUnavailableError(CalibrationError):
    """The run supervisor could not be started (the server still shows the station)."""


@dataclass
class WebContext:
    """The server's state: records database, run supervisor, folders, station, cookie policy.

    Attributes
    ----------
    records : Records
    runs_dir : Path
        Where the supervisor keeps its runs (and uploaded plans).
    plans_dir : Path or None
        The plan folder offered on /runs/new (TOML files); None: upload only.
    stations_dir : Path or None
        The station files offered besides ``sim``; None: the twin only.
    station : str
        This station's name (its lock in the records database).
    secure_cookies : bool
        Served over TLS: cookies are ``Secure``.
    session_hours : float
        How long a login lasts. [h]
    templates : Jinja2Templates
    supervisor : object or None
        A :class:`~imucalib.web.supervisor.RunSupervisor` (or a test's stand-in); made on first
        use when None.
    records_url : str or None
        The records database's URL the server was given (None: the default one); the
        supervisor's workers record their runs there.
    abort_escalate_s : float or None
        The supervisor's bound on an abort before it ends the worker (None: its default). [s]
    """

    records: Records
    runs_dir: Path
    plans_dir: Path | None
    stations_dir: Path | None
    station: str
    secure_cookies: bool
    session_hours: float
    templates: Jinja2Templates
    supervisor: Any = None
    records_url: str | None = None
    abort_escalate_s: float | None = None
    owns_supervisor: bool = False
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def runs(self) -> Any:
        """Return the run supervisor, starting it on first use.

        Raises
        ------
        SupervisorUnavailableError
            It cannot be imported or started (the message says why).
        """
        with self._lock:
            if self.supervisor is None:
                try:
                    from imucalib.web.supervisor import RunSupervisor
                except ImportError as exc:
                    raise SupervisorUnavailableError(
                        f"the run supervisor is not available in this installation: {exc}"
                    ) from exc
                # the runs are recorded in this server's database, not the worker's default
                from imucalib.web.abort_watch import ABORT_ESCALATE_S

                bound = (ABORT_ESCALATE_S if self.abort_escalate_s is None
                         else self.abort_escalate_s)
                self.supervisor = RunSupervisor(self.runs_dir, db=self.records_url,
                                                abort_escalate_s=bound)
                self.owns_supervisor = True
            return self.supervisor

    def close(self) -> None:
        """Stop the supervisor (when this server made it) and release the database."""
        if self.owns_supervisor and self.supervisor is not None:
            self.supervisor.close()
        self.records.close()


def context_of(connection: HTTPConnection) -> WebContext:
    """Return the :class:`WebContext` of the app serving `connection`."""
    web: WebContext = connection.app.state.web
    return web
