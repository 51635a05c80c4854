"""The IMU grades a static-position plan accepts, and each grade's default warm-up.

The g-sensitivity, random-drift and Earth-rate bias plans take the unit's grade (consumer,
tactical or navigation) and, when no warm-up is given, warm the unit up for the grade's default
(docs/g-sensitivity.md, "The plan": 15/30/60 min by grade; docs/random-drift.md and
docs/earth-rate-bias.md, "The plan"). :func:`check_grade` refuses any other grade.

A plan's predicted uncertainty (docs/test-design.md) takes the noise of the unit's grade:
:func:`plan_grade` and :func:`grade_noise`, shared by every procedure's ``predict``. A noise
characterisation of the unit itself (the noise JSON ``imucalib allan`` writes, docs/noise.md)
can stand in for the grade's: :func:`characterization_noise` reads it
(docs/test-design.md, "A noise characterisation in place of the grade's"),
:func:`characterization_config` turns it into the plan's ``[imu.noise]`` table
(:class:`~imucalib.plan.schema.ImuNoiseConfig`), and :func:`declared_noise` returns the noise a
plan declares — its ``[imu.noise]``, else its grade's — with its source.

Contents
--------
:data:`WARM_UP_S`, :func:`check_grade`, :func:`plan_grade`, :func:`grade_noise`,
:func:`declared_noise`, :func:`spec_noise`, :data:`NOISE_CHARACTERIZATION_FORMAT`,
:func:`characterization_noise`, :func:`characterization_config`
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from imucalib.errors import ConfigurationError, InvalidInputError

if TYPE_CHECKING:
    from imucalib.io.reader import Recording
    from imucalib.models.noise import NoiseModel
    from imucalib.plan.schema import ImuNoiseConfig, ImuSpecConfig, Plan

__all__ = ["NOISE_CHARACTERIZATION_FORMAT", "WARM_UP_S", "characterization_config",
           "characterization_noise", "check_grade", "declared_noise", "grade_noise",
           "plan_grade", "recording_declared_noise", "spec_noise"]

#: The ``format`` of the noise characterisation ``imucalib allan`` writes (its noise JSON).
NOISE_CHARACTERIZATION_FORMAT = "imucalib-noise-characterization"
#: The newest ``format_version`` of it this module reads.
_NOISE_FORMAT_VERSION = 1
#: The noise terms read per axis, as :class:`~imucalib.models.noise.NoiseModel` takes them.
_TERMS = {"white": "white_density", "bias_instability": "bias_instability",
          "random_walk": "random_walk"}
#: The fields of :class:`~imucalib.plan.schema.ImuNoiseConfig` per triad and NoiseModel term.
_CONFIG_FIELDS = {
    "gyro": {"white_density": "gyro_white_rps_rthz",
             "bias_instability": "gyro_bias_instability_rps",
             "random_walk": "gyro_random_walk_rps_rts"},
    "accel": {"white_density": "accel_white_mps2_rthz",
              "bias_instability": "accel_bias_instability_mps2",
              "random_walk": "accel_random_walk_mps2_rts"},
}
#: Hex digits of the SHA-256 a source line shows.
_HASH_SHOWN = 12

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


def declared_noise(plan: Plan) -> tuple[dict[str, NoiseModel], str]:
    """Return the noise ``{"accel", "gyro"}`` the plan declares for its unit, and its source.

    The plan's ``[imu.noise]`` (a noise characterisation of the unit, :func:`spec_noise`) when
    it has one, else its grade's (:func:`grade_noise`). The source names it for a result's or a
    prediction's notes: ``"characterisation FILE (sha256 0123456789ab…)"`` or
    ``"grade tactical"`` (docs/test-design.md, "A noise characterisation in place of the
    grade's").

    Raises
    ------
    ConfigurationError
        The plan has no ``[imu.noise]`` and states no grade.
    """
    stated = spec_noise(plan.imu)
    if stated is not None:
        return stated
    return grade_noise(plan), f"grade {plan_grade(plan)}"


def spec_noise(spec: ImuSpecConfig | None) -> tuple[dict[str, NoiseModel], str] | None:
    """Return the noise an IMU specification declares (its ``noise``) and its source; None if none.

    The models are the table's N, B and K per axis (:class:`~imucalib.plan.schema.ImuNoiseConfig`,
    SI); the source is ``"characterisation FILE (sha256 0123456789ab…)"``.
    """
    from imucalib.models.noise import NoiseModel

    if spec is None or spec.noise is None:
        return None
    cfg = spec.noise
    models = {triad: NoiseModel(white_density=list(getattr(cfg, fields["white_density"])),
                                bias_instability=list(getattr(cfg, fields["bias_instability"])),
                                random_walk=list(getattr(cfg, fields["random_walk"])))
              for triad, fields in _CONFIG_FIELDS.items()}
    return models, (f"characterisation {cfg.source} "
                    f"(sha256 {cfg.source_sha256[:_HASH_SHOWN]}…)")


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

    coeffs, name, label, span, _ = _read_characterization(path)
    models = {sensor: NoiseModel(white_density=c["white_density"],
                                 bias_instability=c["bias_instability"],
                                 random_walk=c["random_walk"]) for sensor, c in coeffs.items()}
    return models, f"noise characterisation {name} (record {label!r}, {span:.0f} s)"


def characterization_config(path: str | os.PathLike[str]) -> ImuNoiseConfig:
    """Return a noise characterisation file as a plan's ``[imu.noise]`` table.

    The values are :func:`characterization_noise`'s (N, B, K per axis of the gyro and the
    accelerometer, SI, the longest record's), with the file's name, the record's label and
    length, and the SHA-256 of the file's bytes: the plan then carries the unit's noise and
    needs the file no more (:class:`~imucalib.plan.schema.ImuNoiseConfig`).

    Raises
    ------
    InvalidInputError
        As :func:`characterization_noise`; also a coefficient the plan's bounds refuse.
    """
    from pydantic import ValidationError

    from imucalib.plan.schema import ImuNoiseConfig

    coeffs, name, label, span, digest = _read_characterization(path)
    values: dict[str, Any] = {
        field: tuple(coeffs[triad][term])
        for triad, fields in _CONFIG_FIELDS.items() for term, field in fields.items()}
    try:
        return ImuNoiseConfig(source=name, source_sha256=digest, record=label[:200],
                              record_duration_s=span if math.isfinite(span) else 0.0, **values)
    except ValidationError as exc:
        err = exc.errors()[0]
        where = ".".join(str(p) for p in err["loc"])
        raise InvalidInputError(f"noise characterisation {name}: {where} {err['msg']}; got "
                                f"{err.get('input')!r}") from None


def _read_characterization(path: str | os.PathLike[str]
                           ) -> tuple[dict[str, dict[str, list[float]]], str, str, float, str]:
    """Read a noise JSON: per triad and term the three axes' values, name, label, span, sha256.

    Raises
    ------
    InvalidInputError
        As :func:`characterization_noise`.
    """
    name = Path(path).name
    try:
        raw = Path(path).read_bytes()
        data = json.loads(raw.decode("utf-8"))
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
        if not isinstance(ch, dict):
            continue
        axis = str(ch.get("channel", "")).rsplit("_", 1)[0]  # "gyro_x_rps" → "gyro_x"
        sensor, _, letter = axis.partition("_")
        if sensor not in coeffs or letter not in ("x", "y", "z"):
            continue
        fit = ch.get("fit")
        listed = fit.get("terms") if isinstance(fit, dict) else None
        terms = {t.get("name"): t for t in listed or () if isinstance(t, dict)}
        for term, field in _TERMS.items():
            coeffs[sensor][field]["xyz".index(letter)] = _term_value(terms.get(term))
        seen.add(axis)
    missing = [f"{sensor}_{a}" for sensor in coeffs for a in "xyz" if f"{sensor}_{a}" not in seen]
    if missing:
        raise InvalidInputError(f"noise characterisation {name}: expected gyro and accelerometer "
                                f"channels x, y, z in its longest record ({seg.get('label')!r}); "
                                f"missing {', '.join(missing)}")
    span = _number(seg.get("t_end_s")) - _number(seg.get("t_start_s"))
    return coeffs, name, str(seg.get("label", "")), span, hashlib.sha256(raw).hexdigest()


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


def recording_declared_noise(rec: Recording, imu_spec: ImuSpecConfig | None
                             ) -> tuple[dict[str, NoiseModel], str] | None:
    """Return the noise a recording declares for its unit, with its source; None if none.

    In order: the stated IMU specification's ``noise`` (a noise characterisation,
    :func:`~imucalib.procedures.common.grade.spec_noise`); the stored plan's declared noise
    (:func:`~imucalib.procedures.common.grade.declared_noise`: its ``[imu.noise]``, else its
    grade's, white only for a plan whose twin says so) when the plan's grade is the stated one
    (or none is stated); the stated grade's. The source is ``"characterisation FILE (sha256
    …)"`` or ``"grade G"`` (docs/test-design.md, "A noise characterisation in place of the
    grade's").
    """
    from imucalib.models.imu import sample_imu_model
    from imucalib.plan import parse_plan

    stated = spec_noise(imu_spec)
    if stated is not None:
        return stated
    grade: str = imu_spec.grade if imu_spec is not None else ""
    text = rec.metadata.get("plan_toml")
    if text:
        try:
            plan = parse_plan(str(text))
            if not grade or plan_grade(plan) == grade:
                return declared_noise(plan)
        except ConfigurationError:
            pass
    if not grade:
        return None
    model = sample_imu_model(grade, 0, nonlinear=False)
    return {"accel": model.accel_noise, "gyro": model.gyro_noise}, f"grade {grade}"
