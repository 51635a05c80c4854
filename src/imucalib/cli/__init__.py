"""The ``imucalib`` command line: argument handling and rendering only, no maths.

Each module registers its commands on the one Typer app of :mod:`imucalib.cli._app`; the app
imports a command's module when that command is asked for (:mod:`imucalib.cli._commands`), so
importing this package imports none of them.

Commands
--------
``simulate SCENARIO --out FILE``   run a twin scenario (built-in name or TOML file) into a Recording
``scenarios``                      list the built-in scenarios
``inspect FILE``                   summarise a Recording: streams, units, steps, rates, gaps
``recover FILE``                   copy out what a crashed writer left in an open Recording
``compact FILE --compression NAME`` rewrite a closed Recording with another compression (gzip,
                                   which every HDF5 tool reads; blosc-lz4, blosc-zstd, lzf, none)
``export FILE --stream DEV/UNIT``  write a stream (or one step of it) as CSV or MAT
``export RESULT --format FMT``     a result for firmware (c-runtime) or other tools (mat, ros-yaml…)
``import DATA --steps FILE``       a CSV and its step file as a Recording (docs/import.md)
``segments DATA``                  the static and rotating intervals of data without steps
``procedures [NAME]``              list the procedures (built-in and installed: the
                                   ``imucalib.procedures`` entry points, docs/plugins.md);
                                   with NAME, its plan and analysis options with units, defaults
``plan new NAME --out FILE``       a procedure's default plan; ``plan new NAME --help`` lists
                                   its options, grouped, each a flag
``plan validate|show|schema``      check a plan, print its expanded steps, export its JSON Schema
``plan optimize p1|p2 --out FILE`` the plan meeting σ targets in the least station time
``run PLAN [--station sim|FILE]``  execute a plan on the twin or on equipment (``--resume FILE``)
``calibrate [PROCEDURE] DATA``     estimate, verify and decide; write the result JSON. DATA is a
                                   Recording, a CSV with ``--steps``, or (``calibrate field``) a
                                   hand-held log; ``--set NAME=VALUE`` sets any analysis option,
                                   ``calibrate PROCEDURE --help`` lists them
``allan DATA``                     noise terms of a bare static log (CSV, ROS CSV or .h5)
``apply RESULT DATA --out CSV``    correct a recording's IMU stream or a CSV file
``combine RESULT… --out FILE``     fuse several tests' triad parameters into one result file
``schema result``                  the JSON Schema of the result file (format version 4)
``station check STATION.toml``     connect to real equipment, identify, read status; move nothing
``records list|show|history|…``    the calibration records database (docs/records.md)
``users add|list|disable|enable``  the people who act on the records and their roles
``users set-password NAME``        a user's password for the web page (argon2 hash, records)
``serve``                          the station's operator web page (docs/web.md)
``report RESULT|RECORDING``        the calibration report (certificate) as PDF or HTML; an
                                   array's units and summary; ``--run N`` from the records
"""

from __future__ import annotations

import logging
import os
import sys
import warnings
from typing import Any

from imucalib.cli._app import EXCEPTHOOK, app, err_console, fail
from imucalib.errors import CalibrationError

__all__ = ["app", "main"]


def main() -> None:
    """Entry point of the ``imucalib`` console script.

    Every command renders imucalib's own errors as one line with exit code 2. This is the last
    net under them: an unexpected exception is printed as one ``internal error`` line (the
    traceback only with ``IMUCALIB_DEBUG=1``), also with exit code 2. When HDF5 failed to write
    a Recording (a disk filled behind the free-space checks), the process ends with
    :func:`os._exit` so that the HDF5 library cannot crash while it shuts down. No Python
    warning reaches the terminal as one: a warning a library raises is one ``note:`` line
    (:func:`_warning_note`), or an error under ``python -W error``.
    """
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    warnings.showwarning = _warning_note
    sys.unraisablehook = _unraisable
    sys.excepthook = _printed_error
    EXCEPTHOOK[:] = [_printed_error]  # put back by the app's root callback (Typer replaces it)
    code = 0
    try:
        app()
    except SystemExit as exc:  # typer.Exit and usage errors arrive as their exit codes here
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    except KeyboardInterrupt:
        err_console.print("[red]interrupted[/]", highlight=False)
        code = 130
    except CalibrationError as exc:
        code = fail(exc).exit_code
    except Exception as exc:
        if os.environ.get("IMUCALIB_DEBUG"):
            sys.excepthook = sys.__excepthook__  # the quiet hook would swallow the traceback
            raise
        err_console.print(f"[bold red]internal error:[/] {type(exc).__name__}: {exc} (a bug in "
                          "imucalib; IMUCALIB_DEBUG=1 shows the traceback)", highlight=False,
                          soft_wrap=True)
        code = 2
    _exit(code)


_UNRAISABLE: list[str] = []


def _warning_note(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                  file: Any = None, line: str | None = None) -> None:
    """Print a warning as one ``note:`` line, without Python's file, line and source."""
    err_console.print(f"note: {message}", highlight=False, soft_wrap=True, markup=False)


def _unraisable(unraisable: sys.UnraisableHookArgs) -> None:
    """Keep errors raised while Python frees objects (HDF5 failing to write) off the terminal.

    Python would print them with a traceback; they follow an error already reported (a disk
    that filled up), so they are logged at debug level and the process ends with
    :func:`os._exit` (HDF5's own shutdown could crash on the same failed file).
    """
    _UNRAISABLE.append(f"{type(unraisable.exc_value).__name__}: {unraisable.exc_value}")
    logging.getLogger("imucalib.cli").debug("ignored while freeing %r: %s", unraisable.object,
                                            _UNRAISABLE[-1])


def _printed_error(exc_type: type[BaseException], exc: BaseException, tb: object) -> None:
    """Keep exceptions printed from C code (h5py freeing an object) off the terminal.

    Cython prints an exception raised while an HDF5 object is freed through ``sys.excepthook``
    before it reports it as unraisable; everything :func:`main` itself meets is caught there.
    """
    _UNRAISABLE.append(f"{exc_type.__name__}: {exc}")
    logging.getLogger("imucalib.cli").debug("printed from C code: %s", _UNRAISABLE[-1])


def _exit(code: int) -> None:
    """Leave with `code`; skip interpreter teardown after HDF5 failed to write a file.

    A command that wrote no HDF5 file never imported :mod:`imucalib.io._abandon` (nor h5py),
    so there is nothing of it to ask about (and importing it here would cost every command).
    """
    gave_up = sys.modules.get("imucalib.io._abandon")
    abandoned = gave_up is not None and gave_up.abandoned_files()
    if abandoned or _UNRAISABLE:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)
