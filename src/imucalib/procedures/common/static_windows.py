"""Static window means of all six IMU channels with their reference inputs.

Used by g-sensitivity, Earth-rate bias and random drift (docs/g-sensitivity.md, "Processing").

One step's valid window of one unit at a time (memory bounded by the longest step):

1. the unit's six channels, the counter and the saturation flags; a window with a saturated
   sample is refused (:class:`~imucalib.errors.SaturationError`), one with fewer than 10
   samples or lost samples beyond 1 % is missing (:class:`~imucalib.errors.MissingSegmentError`);
2. the mean of each channel over the window, and the mean table angles of the table feedback;
3. the reference inputs from the table angles, the fixture pose (tag ``pose=<axis>``, the
   remount of a single-axis table, :func:`~imucalib.plan.fixture_poses.rot_pm_for_pose`) and
   the site (:func:`~imucalib.procedures.common.reference.static_inputs_b`):
   ω_b = R_pmᵀ·rot_tpᵀ·Ω_t, f_b = R_pmᵀ·rot_tpᵀ·[0, 0, g];
4. the standard error of each mean, N/√T, with N² the white-noise density of the channel from
   the scatter of its 1 s block means pooled over every window of the unit (as P3 does,
   docs/p3.md): N² = Σ (K_i − 1)·s_i²·τ / Σ (K_i − 1).

Contents
--------
:class:`StaticWindow`, :class:`StaticSite`, :func:`extract_static_windows`, :func:`read_site`,
:func:`require_recorded`, :func:`json_safe`
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from imucalib.conventions import IMU_COLUMNS
from imucalib.errors import InvalidInputError, MissingSegmentError, RecordingError, SaturationError
from imucalib.io.reader import Recording, StepRecord
from imucalib.io.streams import DEVICE_IMU, DEVICE_TABLE
from imucalib.plan.fixture_poses import FIXTURE_AXES, rot_pm_for_pose
from imucalib.procedures.common.noise import block_variance
from imucalib.procedures.common.reference import site_vectors, static_inputs_b
from imucalib.procedures.common.window_checks import pooled_white_se

__all__ = ["StaticSite", "StaticWindow", "extract_static_windows", "json_safe", "read_site",
           "require_recorded"]

_F64 = NDArray[np.float64]


@dataclass(frozen=True)
class StaticSite:
    """The site of a recording: latitude, table heading, g and Earth rate in the table frame.

    Attributes
    ----------
    latitude_deg, heading_deg : float
        [°]
    gravity_mps2 : float
        Local g (the recording's, or normal gravity at the latitude). [m/s²]
    earth_rate_t_rps : ndarray, shape (3,)
        Earth rate in the table frame. [rad/s]
    axis_names : tuple of str
        The table axes, outer first.
    """

    latitude_deg: float
    heading_deg: float
    gravity_mps2: float
    earth_rate_t_rps: _F64
    axis_names: tuple[str, ...]


@dataclass(frozen=True)
class StaticWindow:
    """One static window of one unit, reduced (module docstring).

    Attributes
    ----------
    step_index, label, role : int, str, str
        The recorded step.
    tags : tuple of str
        The step's tags (``pose=``, ``azimuth=``, ``rep=``).
    pose : str
        The fixture pose (``"+z"`` when the step has no ``pose=`` tag).
    angles_rad : ndarray
        Mean table angles, outer first. [rad]
    mean : ndarray, shape (6,)
        Mean gyro (rad/s) then accelerometer (m/s²) outputs.
    se : ndarray, shape (6,)
        Their standard errors N/√T.
    omega_ref_b_rps, force_ref_b_mps2 : ndarray, shape (3,)
        Reference Earth rate and specific force in the body frame.
    duration_s, time_s : float
        Span averaged and its middle (station time). [s]
    block_dof : int
        K − 1, K the number of noise blocks.
    block_var : ndarray, shape (6,)
        s²·τ of the block means, an estimate of N² per channel.
    """

    step_index: int
    label: str
    role: str
    tags: tuple[str, ...]
    pose: str
    angles_rad: _F64
    mean: _F64
    se: _F64
    omega_ref_b_rps: _F64
    force_ref_b_mps2: _F64
    duration_s: float
    time_s: float
    block_dof: int
    block_var: _F64

    def tag_value(self, key: str) -> str | None:
        """Return the value of the first ``key=value`` tag, or None."""
        for tag in self.tags:
            if tag.startswith(f"{key}="):
                return tag[len(key) + 1:]
        return None


def read_site(rec: Recording, gravity_mps2: float | None = None) -> StaticSite:
    """Return the recording's site and table axes.

    Raises
    ------
    RecordingError
        No table stream or no recorded latitude.
    """
    tables = [s for s in rec.streams if s.device == DEVICE_TABLE]
    if not tables:
        raise RecordingError(f"{rec.path} has no table stream: the reference inputs need the "
                             "table's angles")
    names = tuple(c[len("angle_"):-len("_rad")] for c in tables[0].columns
                  if c.startswith("angle_") and c.endswith("_rad"))
    meta = rec.metadata
    lat = float(meta.get("latitude_deg", math.nan))
    if not math.isfinite(lat):
        raise RecordingError(f"{rec.path} does not record the latitude (latitude_deg): the "
                             "Earth-rate reference needs it")
    heading = float(meta.get("heading_deg", 0.0))
    g, earth = site_vectors(lat, heading, gravity_mps2)
    return StaticSite(lat, heading, g, earth, names)


def _table_unit(rec: Recording) -> str:
    return next(s.unit for s in rec.streams if s.device == DEVICE_TABLE)


def _reduce(unit: str, step: StepRecord, values: _F64, counter: NDArray[np.int64],
            saturated: int, t: _F64, angles: _F64, site: StaticSite,
            noise_block_s: float) -> StaticWindow:
    where = f"unit {unit}, step {step.index} ({step.label})"
    if values.shape[0] < 10:
        raise MissingSegmentError(f"{where}: only {values.shape[0]} samples in its valid window "
                                  "(at least 10 expected)")
    if not np.all(np.isfinite(values)):
        raise InvalidInputError(f"{where}: the window holds NaN or infinite samples")
    if saturated:
        raise SaturationError(f"{where}: {saturated} of {values.shape[0]} samples flagged "
                              "saturated; a clipped mean would bias the estimate")
    steps = np.diff(counter)
    if np.any(steps <= 0):
        raise InvalidInputError(f"{where}: the sample counter repeats or goes backwards")
    lost = int(np.sum(steps - 1))
    if lost > 0.01 * (values.shape[0] + lost):
        raise MissingSegmentError(f"{where}: {lost} of {values.shape[0] + lost} samples lost to "
                                  "dropouts (at most 1 % accepted)")
    period = float(t[-1] - t[0]) / float(counter[-1] - counter[0])
    pose = step.tag_value("pose") or "+z"
    if pose not in FIXTURE_AXES:
        raise RecordingError(f"{where}: tag pose={pose!r} is not one of {FIXTURE_AXES}")
    omega_p, force_p = static_inputs_b(site.axis_names, angles, site.gravity_mps2,
                                       site.earth_rate_t_rps)
    rot_pm = rot_pm_for_pose(pose, 0.0)
    dof, var = block_variance(values, period, noise_block_s)
    return StaticWindow(
        step_index=step.index, label=step.label, role=step.role, tags=tuple(step.tags),
        pose=pose, angles_rad=angles, mean=values.mean(axis=0), se=np.full(6, math.nan),
        omega_ref_b_rps=rot_pm.T @ omega_p, force_ref_b_mps2=rot_pm.T @ force_p,
        duration_s=float(t[-1] - t[0]), time_s=float(0.5 * (t[0] + t[-1])),
        block_dof=dof, block_var=np.asarray(var, dtype=np.float64))


def _pooled(windows: list[StaticWindow], unit: str) -> list[StaticWindow]:
    se = pooled_white_se([(w.block_dof, w.block_var) for w in windows],
                         [w.duration_s for w in windows], unit=unit, what="window")
    return [dataclasses.replace(w, se=e) for w, e in zip(windows, se, strict=True)]


def extract_static_windows(rec: Recording, unit: str | None, roles: Sequence[str], *,
                           gravity_mps2: float | None = None, noise_block_s: float = 1.0
                           ) -> tuple[str, StaticSite, list[StaticWindow]]:
    """Reduce every done step with one of `roles` for one unit (module docstring).

    Returns
    -------
    (unit, site, windows)
        The unit (the only IMU when `unit` is None), the site, the windows in step order.

    Raises
    ------
    RecordingError
        No IMU stream `unit` (or several and none chosen), no table stream, no latitude, no
        step with one of `roles`.
    MissingSegmentError, SaturationError, InvalidInputError
        A window too short, with dropouts, saturated or with bad samples.
    """
    imus = [s.unit for s in rec.streams if s.device == DEVICE_IMU]
    if unit is None:
        if len(imus) != 1:
            raise RecordingError(f"{rec.path} has IMU streams {imus}: name the unit to analyse")
        unit = imus[0]
    if unit not in imus:
        raise RecordingError(f"{rec.path} has no IMU stream {unit!r}; it has {imus}")
    chosen = [s for s in rec.steps if s.role in roles and s.concerns(unit)]
    if not chosen:
        raise RecordingError(f"{rec.path}: no step has a role among {', '.join(roles)}; is it a "
                             "recording of this procedure?")
    site = read_site(rec, gravity_mps2)
    usable = [s for s in chosen if s.status == "done" and s.has_valid_window]
    spans = [(s.valid_start_s, s.valid_end_s) for s in usable]
    imu_rows = rec.iter_windows(DEVICE_IMU, unit, spans, [*IMU_COLUMNS, "counter", "saturated"])
    angle_cols = [f"angle_{n}_rad" for n in site.axis_names]
    fb_rows = rec.iter_windows(DEVICE_TABLE, _table_unit(rec), spans, angle_cols)
    windows = []
    for step, data, fb in zip(usable, imu_rows, fb_rows, strict=True):
        values = np.column_stack([np.asarray(data.columns[c], dtype=np.float64)
                                  for c in IMU_COLUMNS])
        angles = np.array([float(np.mean(fb.columns[c])) if len(fb) else math.nan
                           for c in angle_cols])
        if not np.all(np.isfinite(angles)):
            raise MissingSegmentError(f"unit {unit}, step {step.index} ({step.label}): no table "
                                      "feedback in its valid window")
        windows.append(_reduce(unit, step, values,
                               np.asarray(data.columns["counter"], dtype=np.int64),
                               int(np.count_nonzero(np.asarray(data.columns["saturated"]))),
                               np.asarray(data.time_s, dtype=np.float64), angles, site,
                               noise_block_s))
    return unit, site, _pooled(windows, unit)


def json_safe(value: object) -> object:
    """Return `value` with numpy arrays and scalars turned into lists and floats (for to_dict)."""
    return json.loads(json.dumps(value, default=lambda o: np.asarray(o).tolist()))


def require_recorded(rec: Recording, roles: Sequence[str]) -> None:
    """Raise MissingSegmentError naming every step of `roles` not done with a valid window."""
    missing = [f"step {s.index} ({s.label}): {s.status}" for s in rec.steps
               if s.role in roles and not (s.status == "done" and s.has_valid_window)]
    if missing:
        raise MissingSegmentError(f"every planned position must be recorded; missing: "
                                  f"{'; '.join(missing)}")
