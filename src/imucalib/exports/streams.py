"""Export a stream of a Recording (whole, a time window, or a step's valid window) as CSV or MAT.

Contents
--------
:func:`export_csv`
    Streamed in chunks (bounded memory); the header carries units, ``gyro_x_rps [rad/s]``.
:func:`export_mat`
    MATLAB v5 via :func:`scipy.io.savemat`: one column vector per column plus a ``meta`` struct.
    v5 holds at most 2 GiB per variable (:data:`MAT_V5_MAX_BYTES`); larger exports are refused
    with a clear error (export a step or a window, or use CSV).

Both accept an open :class:`~imucalib.io.reader.Recording` or a path.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from imucalib.conventions import TIME_COLUMN
from imucalib.errors import InvalidInputError, RecordingError
from imucalib.io.opening import open_recording
from imucalib.io.reader import Recording

__all__ = ["MAT_V5_MAX_BYTES", "export_csv", "export_mat"]

#: Largest variable a MAT v5 file can hold (its element sizes are 32-bit).
MAT_V5_MAX_BYTES = 2**31 - 1


@contextlib.contextmanager
def _opened(recording: Recording | str | os.PathLike[str]) -> Iterator[Recording]:
    if isinstance(recording, Recording):
        yield recording
    else:
        with open_recording(recording) as rec:
            yield rec


def _window(rec: Recording, step: int | None, t_start_s: float | None, t_end_s: float | None,
            valid_only: bool) -> tuple[float | None, float | None]:
    if step is None:
        return t_start_s, t_end_s
    if t_start_s is not None or t_end_s is not None:
        raise InvalidInputError("give either `step` or `t_start_s`/`t_end_s`, not both")
    return rec.step_window(step, valid_only=valid_only)


def export_csv(recording: Recording | str | os.PathLike[str], device: str, unit: str,
               path: str | os.PathLike[str], *, step: int | None = None,
               columns: Sequence[str] | None = None, t_start_s: float | None = None,
               t_end_s: float | None = None, valid_only: bool = True,
               chunk_samples: int = 1 << 18,
               progress: Callable[[float], None] | None = None) -> int:
    """Write a stream (or a window, or a step's valid window) to CSV, one chunk at a time.

    The first column is ``time_s [s]``; each header names the column and its unit in
    brackets. Floats are written with the shortest text that reads back to the same value;
    NaN is written as ``NaN``.

    Parameters
    ----------
    recording : Recording or str or Path
        An open Recording, or a file to open.
    device, unit : str
        The stream.
    path : str or Path
        The CSV file to write (replaced if it exists).
    step : int, optional
        Only rows inside this step's valid window (its whole span if ``valid_only=False``).
    columns : sequence of str, optional
        Columns besides ``time_s`` (default: all).
    t_start_s, t_end_s : float, optional
        Half-open time window [s] (not with `step`).
    valid_only : bool
        With `step`: the valid window (default) or the whole step.
    chunk_samples : int
        Rows held in memory at once.
    progress : callable, optional
        Called after each chunk with the fraction of the rows written (increasing; the last
        call is 1.0, also for an empty window).

    Returns
    -------
    int
        Rows written.

    Raises
    ------
    InvalidInputError
        Unknown stream, column or step, or a step without a valid window.
    RecordingError
        If the file cannot be written.
    """
    import pandas as pd

    out = Path(path)
    n_rows = 0
    with _opened(recording) as rec:
        t0, t1 = _window(rec, step, t_start_s, t_end_s, valid_only)
        chunks = rec.iter_stream(device, unit, chunk_samples, columns, t0, t1)
        info = rec.stream_info(device, unit)
        names = [c for c in (columns if columns is not None else info.columns)
                 if c != TIME_COLUMN]
        header = [f"{c} [{info.columns[c].unit}]" for c in (TIME_COLUMN, *names)]
        i0, i1 = rec.row_range(device, unit, t0, t1)
        total = max(i1 - i0, 0)
        try:
            with open(out, "w", newline="", encoding="utf-8") as fh:
                fh.write(",".join(header) + "\n")
                for chunk in chunks:
                    frame = pd.DataFrame({TIME_COLUMN: chunk.time_s,
                                          **{c: chunk.columns[c] for c in names}})
                    frame.to_csv(fh, header=False, index=False, na_rep="NaN",
                                 lineterminator="\n")
                    n_rows += len(chunk)
                    if progress is not None and 0 < n_rows < total:
                        progress(n_rows / total)
        except OSError as exc:
            raise RecordingError(f"cannot write {out}: {exc}") from exc
    if progress is not None:
        progress(1.0)
    return n_rows


def export_mat(recording: Recording | str | os.PathLike[str], device: str, unit: str,
               path: str | os.PathLike[str], *, step: int | None = None,
               columns: Sequence[str] | None = None, t_start_s: float | None = None,
               t_end_s: float | None = None, valid_only: bool = True,
               do_compression: bool = False) -> int:
    """Write a stream (or a window, or a step's valid window) to a MATLAB v5 ``.mat`` file.

    Each column (``time_s`` first) becomes a column vector named after it; a struct ``meta``
    holds ``device``, ``unit``, ``units`` (a struct of unit strings), ``source`` (the
    recording's file name), ``step`` (-1 for none) and the window ``t_start_s``/``t_end_s``
    (NaN for unbounded). Loads with ``scipy.io.loadmat`` and in MATLAB/Octave.

    Parameters
    ----------
    recording, device, unit, path, step, columns, t_start_s, t_end_s, valid_only
        As in :func:`export_csv`.
    do_compression : bool
        Compress the variables (slower, smaller).

    Returns
    -------
    int
        Rows written.

    Raises
    ------
    InvalidInputError
        Unknown stream, column or step; a column named ``meta``; or a column above the v5
        limit of 2 GiB per variable (export a step or a window, or use CSV).
    """
    from scipy.io import savemat

    with _opened(recording) as rec:
        t0, t1 = _window(rec, step, t_start_s, t_end_s, valid_only)
        info = rec.stream_info(device, unit)
        i0, i1 = rec.row_range(device, unit, t0, t1)
        names = [c for c in (columns if columns is not None else info.columns)
                 if c != TIME_COLUMN]
        if "meta" in names:
            raise InvalidInputError(f"stream {info.name} has a column named 'meta', which "
                                    "export_mat uses for the metadata struct")
        for c in (TIME_COLUMN, *names):
            if c not in info.columns:
                break  # read_stream below names the unknown column
            nbytes = (i1 - i0) * np.dtype(info.columns[c].dtype).itemsize
            if nbytes > MAT_V5_MAX_BYTES:
                raise InvalidInputError(
                    f"column {c!r} of {info.name} would be {nbytes:,} bytes ({i1 - i0:,} rows); "
                    f"MAT v5 holds at most {MAT_V5_MAX_BYTES:,} bytes per variable: export a "
                    "step or a time window, or use CSV")
        data = rec.read_stream(device, unit, names, t0, t1)
        meta: dict[str, Any] = {
            "device": device, "unit": unit, "units": dict(data.units),
            "source": rec.path.name, "step": -1 if step is None else int(step),
            "t_start_s": np.nan if t0 is None else float(t0),
            "t_end_s": np.nan if t1 is None else float(t1),
        }
        variables: dict[str, Any] = {TIME_COLUMN: data.time_s, **data.columns, "meta": meta}
        try:
            savemat(Path(path), variables, format="5", oned_as="column",
                    do_compression=do_compression)
        except OSError as exc:
            raise RecordingError(f"cannot write {path}: {exc}") from exc
    return len(data)
