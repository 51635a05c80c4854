"""A hand-held session written as the files a user would have: imucal's CSV, raw counts, imu_tk.

:func:`write_session_csv` writes a :class:`~imucalib.sim.handheld.HandheldSession` in one of
three layouts, and returns (:class:`WrittenCsv`) how the project reads it back: the import
specification and the same as command-line options.

CSV layouts (:func:`write_session_csv`)
---------------------------------------
``"imucal"``: ``t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z``, time in s, accelerometer in m/s², gyro
in °/s (the imucal layout of :mod:`imucalib.io.csv_layouts`, read with no options).
``"counts"``: a 2-line preamble, then ``sample;gx;gy;gz;ax;ay;az`` (semicolons), a sample
counter and integer counts raw = round(value·scale + offset) clipped to [0, 2^bits − 1]
(unsigned) or [−2^(bits−1), 2^(bits−1) − 1] (``signed``) (gyro value in °/s, accelerometer in
g), as an MPU-6050 class part logged by a microcontroller; read back with the options in
:attr:`WrittenCsv.cli_args` (``--gyro-unit counts --gyro-scale …``).
``"imu_tk"``: imu_tk's two text files (Tedaldi et al. 2014), no header, blank-separated
``time x y z`` rows: the gyro's at the path given (rad/s), the accelerometer's beside it with
``_acc`` before the suffix (m/s²); read back with ``--accel-file`` and the units.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from imucalib import units
from imucalib._checks import check_positive
from imucalib.errors import InvalidInputError
from imucalib.io.import_spec import COUNTS, ImportSpec
from imucalib.sim.handheld import HandheldSession

__all__ = ["WrittenCsv", "write_session_csv"]


@dataclass(frozen=True)
class WrittenCsv:
    """A session written as a user's CSV, and how to read it back.

    Attributes
    ----------
    path : Path
    layout : str
        ``"imucal"``, ``"counts"`` or ``"imu_tk"``.
    spec : ImportSpec
        The import specification that reads it (:func:`~imucalib.io.import_spec.read_imu_table`).
    cli_args : tuple of str
        The same as command-line options (empty: none needed).
    """

    path: Path
    layout: str
    spec: ImportSpec
    cli_args: tuple[str, ...]


def write_session_csv(
    session: HandheldSession,
    path: str | os.PathLike[str],
    *,
    layout: Literal["imucal", "counts", "imu_tk"] = "imucal",
    gyro_counts_per_dps: float = 65.5,
    accel_counts_per_g: float = 16384.0,
    zero_code: int | None = None,
    bits: int = 16,
    signed: bool = False,
) -> WrittenCsv:
    """Write `session` as the CSV a user would have (module docstring, "CSV layouts").

    Parameters
    ----------
    session : HandheldSession
    path : str or Path
        The file to write.
    layout : {"imucal", "counts", "imu_tk"}
        imucal's names in SI (gyro °/s), raw integer counts, or imu_tk's two files.
    gyro_counts_per_dps, accel_counts_per_g : float
        With ``"counts"``: the sensitivities (an MPU-6050 at ±500 °/s and ±2 g: 65.5 and
        16384; at ±250 °/s a full turn by hand can clip). [1/(°/s)], [1/g]
    zero_code : int, optional
        With ``"counts"``: the code of zero (default 2^(bits−1) unsigned, 0 signed). [counts]
    bits : int
        With ``"counts"``: the word length; codes are clipped to [0, 2^bits − 1], or with
        `signed` to [−2^(bits−1), 2^(bits−1) − 1].
    signed : bool
        With ``"counts"``: two's-complement words (as most MEMS parts output).

    Returns
    -------
    WrittenCsv
        The path, the layout and the options that read it back.

    Raises
    ------
    InvalidInputError
        An unknown layout or a non-positive sensitivity.
    """
    p = Path(path)
    if layout == "imucal":
        data = np.column_stack([session.time_s, session.accel_mps2,
                                np.rad2deg(session.gyro_rps)])
        with p.open("w", encoding="utf-8", newline="\n") as fh:
            fh.write("t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n")
            np.savetxt(fh, data, fmt="%.10g", delimiter=",")
        return WrittenCsv(p, layout, ImportSpec(), ())
    if layout == "imu_tk":
        return _write_imu_tk(session, p)
    if layout != "counts":
        raise InvalidInputError(f"`layout` must be 'imucal', 'counts' or 'imu_tk'; got "
                                f"{layout!r}")
    g_scale = check_positive(gyro_counts_per_dps, "gyro_counts_per_dps")
    a_scale = check_positive(accel_counts_per_g, "accel_counts_per_g")
    half = 1 << (int(bits) - 1)
    low, top = (-half, half - 1) if signed else (0, 2 * half - 1)
    zero_code = (0 if signed else half) if zero_code is None else int(zero_code)
    gyro = np.rint(np.rad2deg(session.gyro_rps) * g_scale + zero_code)
    accel = np.rint(session.accel_mps2 / units.G0_MPS2 * a_scale + zero_code)
    counts = np.clip(np.column_stack([gyro, accel]), low, top).astype(np.int64)
    rows = np.column_stack([np.arange(len(session), dtype=np.int64), counts])
    with p.open("w", encoding="utf-8", newline="\n") as fh:
        fh.write(f"# imucalib twin, hand-held session, grade {session.grade}, seed {session.seed}"
                 f"\n# {session.sample_rate_hz:g} Hz, gyro {g_scale:g} LSB/(deg/s), accel "
                 f"{a_scale:g} LSB/g, zero {zero_code}\n")
        fh.write("sample;gx;gy;gz;ax;ay;az\n")
        np.savetxt(fh, rows, fmt="%d", delimiter=";")
    spec = ImportSpec(gyro_unit=COUNTS, accel_unit=COUNTS, gyro_scale=g_scale,
                      accel_scale=a_scale, gyro_offset=float(zero_code),
                      accel_offset=float(zero_code), time_column="sample",
                      sample_rate_hz=session.sample_rate_hz, delimiter=";", skip_rows=2)
    args = ("--skip-rows", "2", "--delimiter", ";", "--time-column", "sample",
            "--sample-rate-hz", f"{session.sample_rate_hz:g}", "--gyro-unit", COUNTS,
            "--gyro-scale", f"{g_scale:g}", "--gyro-offset", str(zero_code), "--accel-unit",
            COUNTS, "--accel-scale", f"{a_scale:g}", "--accel-offset", str(zero_code))
    return WrittenCsv(p, layout, spec, args)


def _write_imu_tk(session: HandheldSession, gyro_path: Path) -> WrittenCsv:
    """imu_tk's two files (module docstring, "CSV layouts")."""
    accel_path = gyro_path.with_name(f"{gyro_path.stem}_acc{gyro_path.suffix}")
    for path, values in ((gyro_path, session.gyro_rps), (accel_path, session.accel_mps2)):
        with path.open("w", encoding="utf-8", newline="\n") as fh:
            np.savetxt(fh, np.column_stack([session.time_s, values]), fmt="%.10g",
                       delimiter=" ")
    spec = ImportSpec(gyro_unit="rad/s", accel_unit="m/s^2", accel_file=accel_path)
    args = ("--accel-file", str(accel_path), "--gyro-unit", "rad/s", "--accel-unit", "m/s^2")
    return WrittenCsv(gyro_path, "imu_tk", spec, args)
