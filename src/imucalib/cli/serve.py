"""``imucalib serve``: the station's operator web page (docs/web.md).

Binds 127.0.0.1:8000 by default. Another address (a lab network) needs TLS (``--certfile`` and
``--keyfile``), or ``--insecure-http`` said explicitly, which prints one warning line: the
passwords and session cookies would cross the network in clear. The server (FastAPI, uvicorn) is
imported only when the command runs, so ``imucalib --help`` stays quick.
"""

from __future__ import annotations

import ipaddress
import socket
from pathlib import Path
from typing import Annotated

import typer

from imucalib.cli._app import app, err_console, fail
from imucalib.errors import CalibrationError, InvalidInputError

__all__ = ["check_bind", "is_loopback", "serve"]


def is_loopback(host: str) -> bool:
    """Return whether `host` names only this machine (``localhost``, 127.0.0.0/8, ``::1``)."""
    if host.strip().lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def check_bind(host: str, certfile: Path | None, keyfile: Path | None,
               insecure_http: bool) -> str:
    """Refuse an address and TLS combination the security model forbids; return a warning.

    Returns
    -------
    str
        The warning to print ("" when none).

    Raises
    ------
    InvalidInputError
        Only one of the certificate and key; a file that is not there; another host than
        loopback without TLS or ``--insecure-http``.
    """
    if (certfile is None) != (keyfile is None):
        raise InvalidInputError("TLS needs both --certfile and --keyfile; got only "
                                f"{'--certfile' if certfile else '--keyfile'}")
    for name, path in (("--certfile", certfile), ("--keyfile", keyfile)):
        if path is not None and not path.is_file():
            raise InvalidInputError(f"{name} must name a PEM file; {path} is not a file")
    if certfile is not None or is_loopback(host):
        return ""
    if not insecure_http:
        raise InvalidInputError(f"--host {host} is not this machine only: serving it needs TLS "
                                "(--certfile FILE --keyfile FILE) or an explicit "
                                "--insecure-http (docs/web.md, \"Security\")")
    return (f"warning: serving {host} over plain HTTP (--insecure-http): passwords and "
            "session cookies cross the network unencrypted")


def _default_runs_dir() -> Path:
    import platformdirs

    return Path(platformdirs.user_data_dir("imucalib")) / "runs"


def _can_listen(host: str, port: int) -> None:
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind((host.strip("[]"), port))
        except OSError as exc:
            raise InvalidInputError(f"cannot listen on {host}:{port}: expected a free port on "
                                    f"an address of this machine, got {exc.strerror or exc}"
                                    ) from exc


@app.command()
def serve(
    host: Annotated[str, typer.Option(help="Address to listen on (another than 127.0.0.1 "
                                           "needs TLS or --insecure-http).")] = "127.0.0.1",
    port: Annotated[int, typer.Option(min=1, max=65535, help="Port.")] = 8000,
    records: Annotated[str | None, typer.Option(
        "--records", "--db", help="Records database URL or SQLite file (default: "
                                  "$IMUCALIB_DB, else records.db in the user's data "
                                  "directory).")] = None,
    runs_dir: Annotated[Path | None, typer.Option(
        help="Folder of the supervised runs (default: runs in the user's data "
             "directory).")] = None,
    plans_dir: Annotated[Path | None, typer.Option(
        help="Plan files (*.toml) offered on the new-run page.")] = None,
    stations_dir: Annotated[Path | None, typer.Option(
        help="Station files (*.toml) offered besides the twin.")] = None,
    station: Annotated[str | None, typer.Option(
        help="This station's name (its lock; default: the host name).")] = None,
    certfile: Annotated[Path | None, typer.Option(help="TLS certificate (PEM).")] = None,
    keyfile: Annotated[Path | None, typer.Option(help="TLS private key (PEM).")] = None,
    insecure_http: Annotated[bool, typer.Option(
        "--insecure-http", help="Serve another host than this machine without TLS "
                                "(warned).")] = False,
    session_hours: Annotated[float, typer.Option(
        min=0.05, max=24 * 7, help="How long a login lasts [h].")] = 8.0,
    abort_escalate_s: Annotated[float, typer.Option(
        min=1.0, max=3600.0, help="How long an abort may take before the worker is ended "
                                  "(a hung device call) [s].")] = 10.0,
) -> None:
    """Serve the station's operator web page: run, watch, answer prompts, abort (docs/web.md)."""
    try:
        warning = check_bind(host, certfile, keyfile, insecure_http)
        for name, folder in (("--plans-dir", plans_dir), ("--stations-dir", stations_dir)):
            if folder is not None and not folder.is_dir():
                raise InvalidInputError(f"{name} must name a folder; {folder} is not one")
        _can_listen(host, port)
        folder = (runs_dir or _default_runs_dir()).expanduser()
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InvalidInputError(f"--runs-dir must be a folder that can be created; "
                                    f"{folder}: {exc.strerror or exc}") from exc
        from imucalib.web.app import create_app

        web_app = create_app(records, folder, plans_dir=plans_dir, stations_dir=stations_dir,
                             station=station or socket.gethostname(),
                             secure_cookies=certfile is not None, session_hours=session_hours,
                             abort_escalate_s=abort_escalate_s)
    except CalibrationError as exc:
        raise fail(exc) from exc
    if warning:
        err_console.print(warning, style="yellow", highlight=False, soft_wrap=True)
    import uvicorn

    scheme = "https" if certfile else "http"
    shown = f"[{host}]" if ":" in host else host
    err_console.print(f"serving station {web_app.state.web.station} at {scheme}://{shown}:{port}"
                      f" (records {web_app.state.web.records.url}); Ctrl-C stops it",
                      highlight=False, soft_wrap=True)
    uvicorn.run(web_app, host=host.strip("[]"), port=port, ws="websockets-sansio",
                ssl_certfile=str(certfile) if certfile else None,
                ssl_keyfile=str(keyfile) if keyfile else None, log_level="warning",
                access_log=False)
