"""The IMU grades a static-position plan accepts, and each grade's default warm-up.

The g-sensitivity, random-drift and Earth-rate bias plans take the unit's grade (consumer,
tactical or navigation) and, when no warm-up is given, warm the unit up for the grade's default
(docs/g-sensitivity.md, "The plan": 15/30/60 min by grade; docs/random-drift.md and
docs/earth-rate-bias.md, "The plan"). :func:`check_grade` refuses any other grade.

A plan's predicted uncertainty (docs/test-design.md) takes the noise of the unit's grade:
:func:`plan_grade` and :func:`grade_noise`, shared by every procedure's ``predict``. A noise
characterisation of the unit itself (the noise JSON ``imucalib allan`` writes, docs/noise.md)
can stand in for the grade's: :func:`characterization_noise` reads it
(docs/test-design.md, "A noise characterisation in place of the grade's").

Contents
--------
:data:`WARM_UP_S`, :func:`check_grade`, :func:`plan_grade`, :func:`grade_noise`,
:data:`NOISE_CHARACTERIZATION_FORMAT`, :func:`characterization_noise`
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from imucalib.errors import ConfigurationError, InvalidInputError

if TYPE_CHECKING:
    from imucalib.models.noise import NoiseModel
    from imucalib.plan.schema import Plan

__all__ = ["NOISE_CHARACTERIZATION_FORMAT", "WARM_UP_S", "characterization_noise", "check_grade",
           "grade_noise", "plan_grade"]

#: The ``format`` of the noise characterisation ``imucalib allan`` writes (its noise JSON).
NOISE_CHARACTERIZATION_FORMAT = "imucalib-noise-characterization"
#: The newest ``format_version`` of it this module reads.
_NOISE_FORMAT_VERSION = 1
#: The noise terms read per axis, as :class:`~imucalib.models.noise.NoiseModel` takes them.
_TERMS = {"white": "white_density", "bias_instability": "bias_instability",
          "random_walk": "random_walk"}

#: Default warm-up of each grade; its keys are the grades a plan accepts. [s]
WARM_UP_S = {"consumer": 900.0, "tactical": 1800.0, "navigation": 3600.0}


def check_grade(grade: str) -> None:
    """Raise ConfigurationError for an unknown grade."""
    if grade not in WARM_UP_S:
        raise ConfigurationError(f"`grade` must be one of {sorted(WARM_UP_S)}; got {grade!r}")


def plan_grade(plan: Plan) -> str:
    """Return the unit's grade: the plan's ``[imu]``, else its twin's IMU.

    Raises
    ------
    ConfigurationError
        The plan states no grade.
    """
    if plan.imu.grade:
        return plan.imu.grade
    if plan.twin is not None and plan.twin.imus:
        return plan.twin.imus[0].grade
    raise ConfigurationError(f"plan {plan.name!r} states no IMU grade ([imu] grade or a twin "
                             "IMU): the prediction needs the unit's noise model")


def grade_noise(plan: Plan) -> dict[str, NoiseModel]:
    """Return the noise models ``{"accel", "gyro"}`` of the plan's unit grade.

    The coefficients :func:`~imucalib.models.imu.sample_imu_model` gives a unit of the grade
    (white noise, bias instability, the gyro's rate random walk; the draw does not change them),
    white terms only when the plan's twin IMU has ``noise = "white"``.

    Raises
    ------
    ConfigurationError
        The plan states no grade, or an unknown one.
    """
    from imucalib.models.imu import sample_imu_model
    from imucalib.models.noise import NoiseModel

    model = sample_imu_model(plan_grade(plan), 0, nonlinear=False)
    white = plan.twin is not None and bool(plan.twin.imus) and plan.twin.imus[0].noise == "white"
    out = {"accel": model.accel_noise, "gyro": model.gyro_noise}
    if white:
        out = {k: NoiseModel(white_density=v.white_density) for k, v in out.items()}
    return out


def characterization_noise(path: str | os.PathLike[str]
                           ) -> tuple[dict[str, NoiseModel], str]:
    """Return the noise models ``{"accel", "gyro"}`` of a unit's noise characterisation file.

    The file is the noise JSON ``imucalib allan`` writes (``format``
    :data:`NOISE_CHARACTERIZATION_FORMAT`, docs/noise.md): per record and channel the fit of the
    overlapping Allan variance σ²(τ) = N²/τ + (2 ln 2/π)·B² + K²·τ/3 (docs/noise.md §4; IEEE Std
    952-1997 Annex C). Its longest record is read; per axis N (``white``), B
    (``bias_instability``) and K (``random_walk``), SI. A term the fit did not detect takes its
    upper bound (``upper_bound_si``: the value is below it), a conservative Type B input (JCGM
    100:2008 §4.3), else 0 where the fit gives neither (a term not fitted).

    Returns
    -------
    dict of str to NoiseModel, str
        The models, and one line naming the file and its record (for a prediction's notes).

    Raises
    ------
    InvalidInputError
        The file cannot be read, is not JSON, is another format or a newer version, or its
        longest record lacks a gyro or accelerometer channel of x, y and z (one line naming the
        file, what was expected and what was found).
    """
    from imucalib.models.noise import NoiseModel

    name = Path(path).name
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise InvalidInputError(f"noise characterisation {name}: cannot read it "
                                f"({exc.strerror or exc})") from exc
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InvalidInputError(f"noise characterisation {name}: expected the JSON `imucalib "
                                f"allan` writes; got text that is not JSON ({exc})") from exc
    if not isinstance(data, dict) or data.get("format") != NOISE_CHARACTERIZATION_FORMAT:
        found = data.get("format") if isinstance(data, dict) else type(data).__name__
        raise InvalidInputError(f"noise characterisation {name}: expected format "
                                f"{NOISE_CHARACTERIZATION_FORMAT!r} (the noise JSON of `imucalib "
                                f"allan`); got {found!r}")
    version = data.get("format_version")
    if not isinstance(version, int) or not 1 <= version <= _NOISE_FORMAT_VERSION:
        raise InvalidInputError(f"noise characterisation {name}: format_version {version!r} is "
                                f"not supported; this imucalib reads 1..{_NOISE_FORMAT_VERSION}")
    segments = [s for s in data.get("segments") or () if isinstance(s, dict)]
    if not segments:
        raise InvalidInputError(f"noise characterisation {name}: expected at least one record "
                                "('segments'); found none")
    seg = max(segments, key=lambda s: _number(s.get("t_end_s")) - _number(s.get("t_start_s")))
    coeffs: dict[str, dict[str, list[float]]] = {
        sensor: {f: [0.0, 0.0, 0.0] for f in _TERMS.values()} for sensor in ("gyro", "accel")}
    seen: set[str] = set()
    for ch in seg.get("channels") or ():
        axis = str(ch.get("channel", "")).rsplit("_", 1)[0]  # "gyro_x_rps" → "gyro_x"
        sensor, _, letter = axis.partition("_")
        if sensor not in coeffs or letter not in ("x", "y", "z"):
            continue
        terms = {t.get("name"): t for t in (ch.get("fit") or {}).get("terms") or ()}
        for term, field in _TERMS.items():
            coeffs[sensor][field]["xyz".index(letter)] = _term_value(terms.get(term))
        seen.add(axis)
    missing = [f"{sensor}_{a}" for sensor in coeffs for a in "xyz" if f"{sensor}_{a}" not in seen]
    if missing:
        raise InvalidInputError(f"noise characterisation {name}: expected gyro and accelerometer "
                                f"channels x, y, z in its longest record ({seg.get('label')!r}); "
                                f"missing {', '.join(missing)}")
    models = {sensor: NoiseModel(white_density=c["white_density"],
                                 bias_instability=c["bias_instability"],
                                 random_walk=c["random_walk"]) for sensor, c in coeffs.items()}
    span = _number(seg.get("t_end_s")) - _number(seg.get("t_start_s"))
    return models, (f"noise characterisation {name} (record {seg.get('label')!r}, "
                    f"{span:.0f} s)")


def _number(value: Any) -> float:
    """Return a JSON number as float; NaN for null or anything else."""
    return float(value) if isinstance(value, int | float) and not isinstance(value, bool) \
        else math.nan


def _term_value(term: Mapping[str, Any] | None) -> float:
    """Return a fitted term's value (SI); its upper bound when not detected; 0 when neither."""
    if term is None:
        return 0.0
    value = _number(term.get("value_si"))
    if not term.get("detected", False):
        bound = _number(term.get("upper_bound_si"))
        value = bound if math.isfinite(bound) else value
    return max(value, 0.0) if math.isfinite(value) else 0.0
