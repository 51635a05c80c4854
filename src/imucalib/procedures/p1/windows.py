"""What P1's fit takes: one reduced window, and every window of one IMU with its site facts.

:class:`WindowObservation` (a static position or a rate point reduced to means, standard errors,
reference inputs and processing facts) and :class:`P1Observations` (the windows of one IMU, the
site, the processing and what the recording states of its calibration) are the contract between
the reduction (:mod:`.observations`, which makes them from a Recording) and the fit
(:mod:`.fit`, :mod:`.analysis`, which use them; a Monte-Carlo test or a bench may make them
directly). docs/p1.md describes both.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from imucalib.io.context import RecordingContext
from imucalib.models.noise import NoiseModel
from imucalib.plan.schema import AcceptanceConfig, EquipmentConfig, ImuSpecConfig

__all__ = ["P1Observations", "WindowObservation"]

_F64 = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class WindowObservation:
    """One valid window reduced to means: a static position or a rate point.

    Attributes
    ----------
    step_index, plan_step : int
        Row in the Recording's steps and index in the plan (the row when the recording does
        not say: ``commanded["plan_step"]``).
    kind : {"static", "rate"}
    role : {"calibration", "verification"}
        What the fit does with the window (from the step role: held-out roles verify).
    repetition : int
        The ``rep<k>`` or ``repetition=<k>`` tag (1 when absent).
    tags : tuple of str
        The step's tags, with ``"six-position"`` or ``"gyro-bias"`` added when its role is
        ``p1.accel-position`` or ``p1.gyro-bias`` (the fit selects by these tags).
    label : str
    gyro_mean_rps, accel_mps2 : ndarray, shape (3,)
        Window means (whole revolutions for a rate point). [rad/s], [m/s²]
    gyro_se_rps, accel_se_mps2 : ndarray, shape (3,)
        Their standard errors (correlated noise accounted for). [rad/s], [m/s²]
    gyro_std_rps, accel_std_mps2 : ndarray, shape (3,)
        Scatter of the filtered samples about what the model predicts within the window: the
        mean for a static window; the mean and the once-per-revolution harmonic of the table
        angle for a rate point (g-sensitivity, horizontal Earth rate). [rad/s], [m/s²]
    rate_b_rps, force_b_mps2 : ndarray, shape (3,)
        Reference inputs in b (module docstring). [rad/s], [m/s²]
    angles_rad : ndarray, shape (k,)
        Mean measured table angles (the spinning axis: at the window start). [rad]
    table_rate_rps : float
        Mean measured rate of the spinning axis (0 for a static window). [rad/s]
    axis : int or None
        The spinning table axis of a rate point.
    n_samples, n_outliers : int
        Samples in the window, and samples flagged as outliers (all channels together).
    outliers_per_channel : tuple of int
        Flagged samples per channel (gyro x, y, z, accel x, y, z); empty when not tested.
    outlier_times_s : tuple of float
        Times of the first :data:`~.window_reduction.OUTLIER_TIMES_KEPT` rows with a flagged
        sample, to say where. [s]
    n_revolutions : int
    alignment_error_s : float
        Bound on the IMU-to-table synchronisation error. [s]
    duration_s, t_start_s : float
        Length and start of the averaged span (whole revolutions for a rate point). [s]
    allan_fit : ndarray, shape (3, 6), or None
        Per channel (gyro x, y, z, accel x, y, z) the fitted N̂, Ĉ_B, K̂ of the window's Allan
        variance (:func:`~imucalib.processing.statistics.compute_window_statistics`).
    step_role : str
        The step's role (:mod:`.roles`), e.g. ``"p1.accel-position"``.
    """

    step_index: int
    plan_step: int
    kind: str
    role: str
    repetition: int
    tags: tuple[str, ...]
    label: str
    gyro_mean_rps: _F64
    accel_mean_mps2: _F64
    gyro_se_rps: _F64
    accel_se_mps2: _F64
    gyro_std_rps: _F64
    accel_std_mps2: _F64
    rate_b_rps: _F64
    force_b_mps2: _F64
    angles_rad: _F64
    table_rate_rps: float
    axis: int | None
    n_samples: int
    n_outliers: int
    n_revolutions: int
    alignment_error_s: float
    duration_s: float
    t_start_s: float = 0.0
    allan_fit: _F64 | None = None
    step_role: str = ""
    outliers_per_channel: tuple[int, ...] = ()
    outlier_times_s: tuple[float, ...] = ()


@dataclass(frozen=True, eq=False)
class P1Observations:
    """Every usable window of one IMU in a P1 Recording, with the site and processing facts.

    ``context`` is what the recording says about its calibration
    (:class:`~imucalib.io.context.RecordingContext`: the keys a run writes, an older
    recording's stored plan, what an import's step file gives, docs/import.md). ``equipment``,
    ``imu_spec`` and ``acceptance`` are the equipment accuracies, the IMU specification and the
    decision rule it states, as the plan's models; None when it states nothing (the analysis
    then takes them from its options or the models' defaults).
    """

    sensor_id: str
    windows: tuple[WindowObservation, ...]
    gravity_mps2: float
    earth_rate_t_rps: _F64
    latitude_deg: float
    heading_deg: float
    sample_rate_hz: float
    cutoff_hz: float | None
    notes: tuple[str, ...] = ()
    skipped: tuple[str, ...] = field(default_factory=tuple)
    noise: dict[str, NoiseModel] = field(default_factory=dict)
    equipment: EquipmentConfig | None = None
    imu_spec: ImuSpecConfig | None = None
    acceptance: AcceptanceConfig | None = None
    context: RecordingContext = field(default_factory=RecordingContext)

    def select(self, *, kind: str | None = None, role: str | None = None,
               repetition: int | None = None, tag: str | None = None
               ) -> list[WindowObservation]:
        """Return the windows matching every given criterion."""
        return [w for w in self.windows
                if (kind is None or w.kind == kind) and (role is None or w.role == role)
                and (repetition is None or w.repetition == repetition)
                and (tag is None or tag in w.tags)]

    @property
    def repetitions(self) -> tuple[int, ...]:
        """The repetition numbers present."""
        return tuple(sorted({w.repetition for w in self.windows}))
