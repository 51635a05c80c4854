"""The covariance of the turns' means under coloured noise (docs/rate-transfer.md, (RT-4c)).

The white σ_j = N/√T_j of (RT-4) treat the turns' means as independent. A gyro's flicker
(bias instability B) and rate random walk K are shared by turns that follow each other within
minutes: weighting by the white σ alone understated the biases' σ 2.9–5.3× for the default plan
and a tactical gyro (docs/rate-transfer.md, "Coloured noise"). As P1 does (docs/p1.md, "Noise
model of the window means"), the means of gyro k's turns get the covariance of Eq. (TD.2)
(docs/test-design.md),

    (RT-4c)  C_jl = Cov(ȳ_j, ȳ_l) = (T_j·T_l)⁻¹ ∫_j ∫_l R_k(t − s) ds dt,

:func:`~imucalib.estimation.compute_window_mean_covariance`, for the noise model with

- the white density N_k fitted to the turns (RT-4: the pooled scatter of 1 s block means);
- the flicker B_k and random walk K_k of the unit's declared grade, a Type B input (JCGM
  100:2008 §4.3): a turn lasts seconds to minutes, its Allan fit's longest cluster far short of
  the :data:`~imucalib.procedures.common.noise.FLICKER_CORNERS_MIN` flicker corners that would
  determine the floor (:func:`~imucalib.procedures.common.noise.with_declared_floor`, the rule
  P1 applies); and the turn reduction (RT-4) fits the white density only, so even turns long
  enough for the floor take the declared terms, and the note says which case it is.

The declared noise is a noise characterisation the recording's plan or IMU specification
carries (``[imu.noise]``, docs/p1.md), else that of the grade the recording states: the
stored plan's (its ``[imu]`` grade or its twin IMU's, white only for a twin with ``noise =
"white"``), else the metadata's IMU specification. A recording that states none keeps the
white σ (RT-4), and the note says the σ then hold for white noise only.

Each turn's span of whole revolutions lies inside its step's valid window; its start is taken
as the window's centre less half the span (an error under half a revolution, small against
the flicker's correlation times). The random walk starts at the run's first step.

Contents
--------
:class:`TurnNoise`, :func:`declared_gyro_noise`, :func:`turn_noise`
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from imucalib.estimation.noise_covariance import compute_window_mean_covariance
from imucalib.io.reader import Recording
from imucalib.models.noise import NoiseModel
from imucalib.procedures.common.noise import (
    FLICKER_CORNERS_MIN,
    flicker_corner_s,
    longest_cluster_s,
    with_declared_floor,
)
from imucalib.procedures.common.rate_windows import RateWindow

__all__ = ["TurnNoise", "declared_gyro_noise", "turn_noise"]

_F64 = NDArray[np.float64]
_INDEX = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class TurnNoise:
    """The noise model of the turns' means and their covariance per gyro axis (RT-4c).

    Attributes
    ----------
    model : NoiseModel
        The fitted white density with the declared flicker and random walk (module docstring).
    covariance : dict of str to ndarray (n_k, n_k)
        Per body axis tested, the covariance of gyro k's means of its turns, in the order of
        the turns of that axis. [(rad/s)²]
    note : str
        What the model holds and why.
    coloured : bool
        Whether flicker or random walk entered the covariance.
    """

    model: NoiseModel
    covariance: dict[str, _F64]
    note: str
    coloured: bool


def declared_gyro_noise(rec: Recording) -> tuple[NoiseModel | None, str]:
    """Return the gyro noise the recording declares for its unit, and its source.

    :func:`~imucalib.procedures.common.grade.recording_declared_noise` (the one lookup P1's
    floor uses too) with the IMU specification the metadata states: ``"grade G"`` or
    ``"characterisation FILE (sha256 …)"``; (None, "") when it declares none (module
    docstring).
    """
    from pydantic import ValidationError

    from imucalib.io.context import RecordingContext
    from imucalib.plan.schema import ImuSpecConfig
    from imucalib.procedures.common.grade import recording_declared_noise

    table = RecordingContext.of(rec.metadata).imu_table
    try:
        spec = ImuSpecConfig.model_validate(table) if table else None
    except ValidationError:
        spec = None  # a specification the metadata states badly declares nothing
    found = recording_declared_noise(rec, spec)
    return (None, "") if found is None else (found[0]["gyro"], found[1])


def _starts(rec: Recording, windows: Sequence[RateWindow]) -> tuple[_F64, float]:
    """Return each turn's span start (module docstring) and the run's start. [s]"""
    steps = {s.index: s for s in rec.steps}
    out = []
    for w in windows:
        s = steps[w.step_index]
        mid = 0.5 * (s.valid_start_s + s.valid_end_s)
        out.append(max(mid - 0.5 * w.duration_s, s.valid_start_s))
    starts = np.asarray(out, dtype=np.float64)
    first = min((s.t_start_s for s in rec.steps if math.isfinite(s.t_start_s)),
                default=float(starts.min()))
    return starts, float(min(first, float(starts.min())))


def turn_noise(rec: Recording, windows: Sequence[RateWindow], white_density_rps: _F64,
               sample_rate_hz: float) -> TurnNoise:
    """Return the turns' noise model and the covariance of each axis' means (module docstring).

    Parameters
    ----------
    rec : Recording
        The run (its steps' windows and the grade it states).
    windows : sequence of RateWindow
        The unit's turns, as reduced (RT-2)–(RT-4).
    white_density_rps : ndarray, shape (3,)
        N per gyro axis, pooled over the turns (RT-4). [rad/s/√Hz]
    sample_rate_hz : float
        The unit's sample rate (the Allan fit's longest cluster of a turn). [Hz]
    """
    fitted = NoiseModel(white_density=np.asarray(white_density_rps, dtype=np.float64))
    declared, source = declared_gyro_noise(rec)
    model, note, coloured = fitted, "", False
    if declared is not None:
        tau_max = longest_cluster_s(max(w.duration_s for w in windows), sample_rate_hz)
        floored, floor_note = with_declared_floor({"gyro": fitted}, {"gyro": declared}, tau_max,
                                                  source=source)
        model = floored["gyro"]
        coloured = bool(np.any(np.asarray(model.bias_instability) > 0)
                        or np.any(np.asarray(model.random_walk) > 0))
        if floor_note is not None:
            tau_c = float(np.max(flicker_corner_s(declared)))
            note = (f"turn means' covariance (RT-4c, Eq. (TD.2)): white density fitted to the "
                    f"turns (RT-4), flicker and random walk of the {source} (Type B, "
                    f"JCGM 100:2008 §4.3): the longest turn's Allan cluster ({tau_max:.3g} s) "
                    f"is shorter than {FLICKER_CORNERS_MIN:g} flicker corners (τ_c {tau_c:.3g}"
                    " s), so the turns cannot determine the flicker floor")
        elif coloured or np.any(flicker_corner_s(declared) > 0):
            # turns long enough for the floor, yet (RT-4) fits no flicker: the declared terms
            model = NoiseModel(white_density=fitted.white_density,
                               bias_instability=declared.bias_instability,
                               random_walk=declared.random_walk)
            coloured = True
            note = (f"turn means' covariance (RT-4c, Eq. (TD.2)): white density fitted (RT-4), "
                    f"the {source} bias instability and random walk (Type B): the turn "
                    f"reduction fits no flicker, though the longest turn's Allan cluster "
                    f"({tau_max:.3g} s) reaches {FLICKER_CORNERS_MIN:g} flicker corners")
        else:
            note = (f"turn means' covariance (RT-4c): white only, as the {source} the "
                    "recording states declares (its twin's noise)")
    else:
        note = ("the recording states no IMU grade: the turns' means weighted by their white σ "
                "(RT-4) only; under flicker and random walk the biases' σ are understated "
                "(docs/rate-transfer.md, \"Coloured noise\")")
    starts, t0 = _starts(rec, windows)
    cov: dict[str, _F64] = {}
    for axis in sorted({w.axis for w in windows}):
        idx = [i for i, w in enumerate(windows) if w.axis == axis]
        c = compute_window_mean_covariance(model, starts[idx],
                                           [windows[i].duration_s for i in idx],
                                           reference_time_s=t0)
        cov[axis] = np.asarray(c[_INDEX[axis]], dtype=np.float64)
    return TurnNoise(model=model, covariance=cov, note=note, coloured=coloured)
