"""Every procedure's analysis options are one dataclass (procedures/<name>/options.py) true to its
analysis: the keys ``analyze`` accepts, each with the default the analysis really uses when the
key is not given (read from the analysis's own dataclass or signature, never retyped here)."""

from __future__ import annotations

import dataclasses
import inspect
import typing
from collections.abc import Callable
from typing import Any

import pytest

from imucalib.errors import RecordingError
from imucalib.procedures import registry
from imucalib.procedures.common.options import option_names, option_specs


def _fields(cls: type) -> dict[str, Any]:
    """{field: default} of the dataclass `cls` (a default factory called)."""
    out = {}
    for f in dataclasses.fields(cls):
        if f.default is not dataclasses.MISSING:
            out[f.name] = f.default
        elif f.default_factory is not dataclasses.MISSING:
            out[f.name] = f.default_factory()
    return out


def _keywords(func: Callable[..., Any]) -> dict[str, Any]:
    """{keyword: default} of `func`'s keywords that have one."""
    return {p.name: p.default for p in inspect.signature(func).parameters.values()
            if p.default is not p.empty}


def _p1() -> dict[str, Any]:
    from imucalib.procedures.p1.analysis import P1Options

    return _fields(P1Options)


def _p2() -> dict[str, Any]:
    from imucalib.procedures.p2.analysis import P2Options
    from imucalib.procedures.p2.batch import analyze_p2

    return {**_fields(P2Options), **_keywords(analyze_p2)}


def _p3() -> dict[str, Any]:
    from imucalib.procedures.p3.analysis import P3Options
    from imucalib.procedures.p3.observations import P3Processing

    return {**_fields(P3Processing), **_fields(P3Options)}


def _rate_transfer() -> dict[str, Any]:
    from imucalib.procedures.rate_transfer.observations import RateProcessing

    return _fields(RateProcessing)


def _installation() -> dict[str, Any]:
    from imucalib.procedures.common.rate_windows import RateProcessing
    from imucalib.procedures.installation.analysis import analyze_installation

    return {**_fields(RateProcessing), **_keywords(analyze_installation)}


def _g_sensitivity() -> dict[str, Any]:
    from imucalib.procedures.g_sensitivity.analysis import GSensitivityOptions

    return _fields(GSensitivityOptions)


def _random_drift() -> dict[str, Any]:
    from imucalib.procedures.common.drift_model import GSensitivityOptions

    return _fields(GSensitivityOptions)


def _earth_rate_bias() -> dict[str, Any]:
    from imucalib.procedures.earth_rate_bias.analysis import analyze_earth_rate_bias

    return _keywords(analyze_earth_rate_bias)


def _tumble() -> dict[str, Any]:
    from imucalib.procedures.tumble.analysis import TumbleOptions

    return _fields(TumbleOptions)


def _field() -> dict[str, Any]:
    from imucalib.io.import_spec import read_imu_table
    from imucalib.procedures.field.analysis import FieldOptions

    return {**_fields(FieldOptions), "import_spec": _keywords(read_imu_table)["spec"]}


def _allan() -> dict[str, Any]:
    from imucalib.io.import_spec import read_imu_table

    return {"import_spec": _keywords(read_imu_table)["spec"]}  # a log read by its layout


#: Per built-in: where its analysis keeps the default of each key {key: real default}.
REAL_DEFAULTS: dict[str, Callable[[], dict[str, Any]]] = {
    "p1": _p1, "allan": _allan, "p2": _p2, "p3": _p3, "rate-transfer": _rate_transfer,
    "installation": _installation, "g-sensitivity": _g_sensitivity,
    "earth-rate-bias": _earth_rate_bias, "random-drift": _random_drift, "tumble": _tumble,
    "field": _field,
}


def _norm(value: Any) -> Any:
    if isinstance(value, list | tuple):
        return tuple(_norm(v) for v in value)
    return value


def test_every_builtin_has_its_table():
    assert set(REAL_DEFAULTS) == set(registry.BUILTIN)


@pytest.mark.parametrize("name", list(registry.BUILTIN))
def test_the_options_dataclass_is_what_analyze_accepts(name):
    proc = registry.get(name)
    cls = proc.analysis_options_type
    assert dataclasses.is_dataclass(cls) and cls.__dataclass_params__.frozen
    assert proc.analysis_options == option_names(cls)
    for spec in option_specs(cls):
        assert spec.info.help and spec.info.help[0].isupper(), spec.name
        assert spec.info.help.rstrip().endswith("."), spec.name
        assert spec.cli or spec.info.python_only, spec.name


@pytest.mark.parametrize("name", list(registry.BUILTIN))
def test_each_default_is_the_analysiss_own(name):
    real = REAL_DEFAULTS[name]()
    for spec in option_specs(registry.get(name).analysis_options_type):
        assert spec.name in real, f"{name}: {spec.name} has no default in the analysis"
        want = real[spec.name]
        if spec.default is None and isinstance(want, dict) and not want:
            continue  # an empty mapping, which a frozen dataclass cannot hold: None stands for it
        assert _norm(spec.default) == _norm(want), f"{name}: {spec.name}"


def test_choices_are_the_analysiss_own():
    from imucalib.procedures.p1.procedure import MODELS
    from imucalib.procedures.p2.analysis import P2Options
    from imucalib.procedures.tumble.fourier import COEFFICIENTS

    def choices(name: str, key: str) -> tuple[str, ...] | None:
        spec = {s.name: s for s in option_specs(registry.get(name).analysis_options_type)}[key]
        return spec.choices

    assert choices("tumble", "coefficients") == COEFFICIENTS
    assert choices("p1", "model") == MODELS
    p2_hints = typing.get_type_hints(P2Options)
    for key in ("lever_arm", "criterion", "hysteresis"):
        assert choices("p2", key) == typing.get_args(p2_hints[key]), key


@pytest.mark.parametrize("name", list(registry.BUILTIN))
def test_the_defaults_are_accepted_by_analyze(name, tmp_path):
    proc = registry.get(name)
    given = {s.name: s.default for s in option_specs(proc.analysis_options_type)
             if s.default is not None}
    missing = tmp_path / "x.h5"
    # every key is taken: the analysis gets as far as opening the recording
    with pytest.raises(RecordingError, match="no such recording"):
        proc.analyze(str(missing), options=given)
