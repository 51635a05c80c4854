"""What a calibration result document is: its format name and version, models, parameter names.

Shared by :mod:`imucalib.models.result` (the result, which re-exports every name here) and
:mod:`imucalib.models._result_reader` (the strict reader of its JSON), so that neither imports
the other for them. The parameter names are documented in :mod:`imucalib.models.result`.
"""

from __future__ import annotations

from typing import Final

from imucalib.conventions import AXES

__all__ = ["MODELS", "RESULT_DOCUMENT_VERSION", "RESULT_FORMAT", "RESULT_FORMAT_VERSION", "RTOL",
           "triad_parameter_names", "triad_parameter_unit"]

RESULT_FORMAT: Final = "imucalib-calibration-result"
#: Version 2 adds ``fit_quality`` (χ²/ν, expected range, misfit flag per fitted triad); version 3
#: adds ``temperature_models`` (one per temperature-dependent parameter). Files of versions 1 and
#: 2 are read with none of what they lack.
RESULT_FORMAT_VERSION: Final = 3
#: The version of the one result file of every procedure (:mod:`imucalib.models.result_document`),
#: whose ``calibration`` holds a calibration result of versions 1–3.
RESULT_DOCUMENT_VERSION: Final = 4
MODELS: Final = ("triad", "per-axis")
#: Relative tolerance of a result's consistency checks: a temperature model's c_0 against the
#: parameter's value, and (in the reader) symmetry and ``std`` against √diag(covariance).
RTOL: Final = 1e-9


def triad_parameter_names(triad: str, model: str, *, g_sensitivity: bool = False,
                          k2: bool = False, k3: bool = False) -> tuple[str, ...]:
    """Return the parameter names of one triad under `model` (:mod:`imucalib.models.result`).

    A triad model's names: bias, M, then the optional G, K2 and K3 terms in that order (the
    order of the result contract and of the C runtime's slots); `g_sensitivity`, `k2` and `k3`
    are ignored for the per-axis model.
    """
    if model == "per-axis":
        return (*(f"{triad}_K_{a}" for a in AXES), *(f"{triad}_b_{a}" for a in AXES))
    names = [*(f"{triad}_bias_{a}" for a in AXES),
             *(f"{triad}_M_{i}{j}" for i in AXES for j in AXES)]
    if g_sensitivity:
        names += [f"{triad}_G_{i}{j}" for i in AXES for j in AXES]
    if k2:
        names += [f"{triad}_K2_{a}" for a in AXES]
    if k3:
        names += [f"{triad}_K3_{a}" for a in AXES]
    return tuple(names)


def triad_parameter_unit(name: str) -> str:
    """Return the SI unit of a parameter name (``gyro_bias_x`` → ``rad/s``)."""
    triad, _, rest = name.partition("_")
    symbol = rest.split("_")[0]
    si = "m/s^2" if triad == "accel" else "rad/s"
    return {"bias": si, "b": si, "G": "rad/s/(m/s^2)", "K2": "1/(m/s^2)",
            "K3": "1/(m/s^2)^2"}.get(symbol, "1")
