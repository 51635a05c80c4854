"""Read IMU data from CSV: the exports of :mod:`imucalib.io.export` and plain vendor files.

Contents
--------
:func:`read_imu_csv`
    A CSV file → a DataFrame indexed by ``time_s`` with canonical column names and the units in
    ``df.attrs["units"]``.

Accepted headers
----------------
- ``name [unit]`` (what :func:`~imucalib.io.export.export_csv` writes): the unit is taken from
  the brackets and checked with :func:`imucalib.units.parse_unit`;
- a bare canonical name (``gyro_x_rps``, ``accel_y_mps2``, ``time_s``): the unit its suffix
  names;
- a ``column_map`` renames vendor columns once, at ingest (``{"GyrX": "gyro_x_rps"}``), with
  ``units`` giving their units when the header does not (values are converted to SI).
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from imucalib.conventions import TIME_COLUMN
from imucalib.errors import InvalidInputError, UnitError
from imucalib.units import parse_unit

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["read_imu_csv"]

_HEADER = re.compile(r"^\s*([A-Za-z][A-Za-z0-9_]*)\s*(?:\[(.+)\])?\s*$")
_SI_SUFFIXES = {"_rps": "rad/s", "_mps2": "m/s^2", "_s": "s"}
_SUFFIX_UNITS = {"_rps": "rad/s", "_mps2": "m/s^2", "_s": "s", "_degc": "degC", "_dps": "deg/s",
                 "_g": "g"}


def _unit_of(name: str) -> str:
    for suffix, unit in _SUFFIX_UNITS.items():
        if name.endswith(suffix):
            return unit
    return "1"


def read_imu_csv(path: str | os.PathLike[str], *, column_map: Mapping[str, str] | None = None,
                 units: Mapping[str, str] | None = None, to_si: bool = True) -> pd.DataFrame:
    """Read a CSV file of IMU samples.

    Parameters
    ----------
    path : str or Path
        The file; its first line is the header.
    column_map : mapping, optional
        Vendor column name → canonical name.
    units : mapping, optional
        Canonical column name → unit, for columns whose header gives none.
    to_si : bool
        Convert every column with a known SI factor to SI (``deg/s`` → rad/s, ``g`` → m/s²);
        the canonical name must then carry the SI suffix.

    Returns
    -------
    pandas.DataFrame
        Indexed by ``time_s`` [s]; ``df.attrs["units"]`` maps each column to its unit.

    Raises
    ------
    InvalidInputError
        No ``time_s`` column, a non-numeric value, non-finite or decreasing time.
    UnitError
        An unknown unit in a header.
    """
    import pandas as pd

    p = Path(path)
    try:
        raw = pd.read_csv(p, na_values=["NaN"], keep_default_na=False)
    except (OSError, ValueError, pd.errors.ParserError) as exc:
        raise InvalidInputError(f"cannot read CSV {p}: {exc}") from exc
    names: dict[str, str] = {}
    col_units: dict[str, str] = {}
    for header in raw.columns:
        m = _HEADER.match(str(header))
        if m is None:
            raise InvalidInputError(f"{p}: header {header!r} is not `name` or `name [unit]`")
        name = (column_map or {}).get(m.group(1), m.group(1))
        names[str(header)] = name
        col_units[name] = m.group(2) or (units or {}).get(name) or _unit_of(name)
    df = raw.rename(columns=names)
    if TIME_COLUMN not in df.columns:
        raise InvalidInputError(f"{p}: no {TIME_COLUMN!r} column; columns are {list(df.columns)}"
                                " (use `column_map` to name the time column)")
    for col in df.columns:
        if not pd.api.types.is_numeric_dtype(df[col]):
            bad = pd.to_numeric(df[col], errors="coerce").isna() & df[col].notna()
            row = int(np.argmax(bad.to_numpy()))
            raise InvalidInputError(
                f"{p}: column {col!r} holds a non-numeric value {df[col].iloc[row]!r} at data "
                f"row {row + 1} (numbers expected; a missing value is written NaN)")
        unit = col_units[col]
        if unit in ("1", "counts", "degC", "bool"):
            continue
        try:
            factor = parse_unit(unit)
        except UnitError as exc:
            raise UnitError(f"{p}: column {col!r}: {exc}") from exc
        if to_si and factor != 1.0:
            si_unit = next((u for suffix, u in _SI_SUFFIXES.items() if col.endswith(suffix)),
                           None)
            if si_unit is None:
                raise InvalidInputError(
                    f"{p}: column {col!r} is in {unit!r}; to convert it to SI give it a "
                    f"canonical SI name (ending in {list(_SI_SUFFIXES)}) with `column_map`")
            df[col] = df[col].to_numpy(dtype=np.float64) * factor
            col_units[col] = si_unit
    t = df[TIME_COLUMN].to_numpy(dtype=np.float64)
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0):
        raise InvalidInputError(f"{p}: {TIME_COLUMN} must be finite and non-decreasing")
    df = df.set_index(TIME_COLUMN)
    df.attrs["units"] = {c: col_units[c] for c in df.columns}
    return df
