"""A calibration as C99 for firmware: a generated parameter header and a fixed runtime library.

Contents
--------
:func:`write_c_runtime`
    A :class:`~imucalib.models.result.CalibrationResult` → ``<name>_params.h`` (generated) and
    ``imucalib_runtime.h`` / ``imucalib_runtime.c`` (copied, package data of
    ``imucalib.exports``) in one folder.
:data:`C_RUNTIME_FILES`, :data:`MAX_TEMPERATURE_ORDER`, :data:`LAYOUT_VERSION`

Model (docs/c-runtime.md)
-------------------------
The runtime computes, per sample and with no allocation, what
:func:`~imucalib.models.correct.correct_imu` computes::

    p(T, Ṫ, ℓ) = Σ_{j=0..m} c_j (T − T0)^j + d·Ṫ + h·ℓ                                      (C1)
    y = b + h((I + M)·x) (+ G·f, gyro),  h_i(u) = u + K2_i·u² + K3_i·u³  (triad model)    (C2)
    u_i = 2 r_i / (1 + √(1 + 4 K2_i r_i)),  r = y − b (− G·f),  x = (I + M)⁻¹·u             (C3)
    K3_i ≠ 0: u_i ← u_i − (h_i(u_i) − r_i) / h_i′(u_i), from the root of (C3)               (C3′)
    x_i = y_i / K_i − b_i                          (per-axis model, y_i = K_i·(x_i + b_i))  (C4)

(C1) is Eq. (T1) of docs/processing-estimation.md; (C3) is the exact root of the quadratic
h(u) = u + K2·u² on the branch through 0, the root :func:`~imucalib.models.triad.correct_triad`
starts its Newton iteration from (and keeps when K3 = 0; Koq = asymmetry = 0 being the only
case a result file can hold). With K3 ≠ 0, (C3′) takes Newton steps from it (at most
``IMUCAL_K3_MAX_ITER``, until a step is ≤ 4 ε·|u|) and accepts the root only on the branch
through 0 (h′ > 0 between 0 and it), as :func:`~imucalib.models.correct.correct_imu` does; K3 = 0
runs exactly the code of (C3). The accelerometer is corrected first and its corrected specific
force feeds the gyro's G, as in ``correct_imu``.

Each parameter has a slot (``IMUCAL_BIAS`` … in ``imucalib_runtime.h``); a slot the result does
not carry holds 0 (so ``I + M`` = I, no G, no K2, no K3). K3 is the last slot of a triad's block
(:data:`LAYOUT_VERSION` 2; the offsets of version 1 are unchanged). Parameters are written in
double (``%r``, exact) and in float (rounded to nearest). Refused, with an
:class:`~imucalib.errors.InvalidInputError` naming what: a parameter the runtime has no slot for,
a temperature model of order above :data:`MAX_TEMPERATURE_ORDER`, a `name` that is not a C
identifier.
"""

from __future__ import annotations

import hashlib
import os
import re
from importlib import resources
from pathlib import Path
from typing import Any, Final

import numpy as np

from imucalib import __version__
from imucalib.conventions import AXES
from imucalib.errors import InvalidInputError
from imucalib.models.result import CalibrationResult

__all__ = ["C_RUNTIME_FILES", "LAYOUT_VERSION", "MAX_TEMPERATURE_ORDER", "write_c_runtime"]

#: The fixed library's files, copied next to the generated header.
C_RUNTIME_FILES: Final = ("imucalib_runtime.h", "imucalib_runtime.c")
#: The body of imucalib_runtime.c, written once for both precisions (package data only): it is
#: inlined where the .c includes it, so the folder written stands alone.
_IMPL: Final = "imucalib_runtime_impl.h"
#: Polynomial terms per slot in the runtime (``IMUCAL_MAX_TERMS``); the highest order is one less.
_MAX_TERMS: Final = 8
#: The highest order m of Eq. (C1) the runtime evaluates.
MAX_TEMPERATURE_ORDER: Final = _MAX_TERMS - 1
_TRIADS: Final = ("gyro", "accel")
#: The slot layout's version (``IMUCAL_LAYOUT_VERSION``): 2 appended K3 (offset 30) to each
#: triad's block of version 1 (30 slots a triad); the generated header checks it.
LAYOUT_VERSION: Final = 2
_TRIAD_SLOTS: Final = 33
#: Offset of each symbol's first slot in a triad (``IMUCAL_BIAS`` … of imucalib_runtime.h).
_OFFSETS: Final = {"bias": 0, "M": 3, "G": 12, "K2": 21, "K": 24, "b": 27, "K3": 30}
_IDENTIFIER: Final = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def _slot_names() -> list[str]:
    """Return the parameter name of every slot, in slot order (66 names, :data:`_OFFSETS`)."""
    names = []
    for triad in _TRIADS:
        names += [f"{triad}_bias_{a}" for a in AXES]
        names += [f"{triad}_M_{i}{j}" for i in AXES for j in AXES]
        names += [f"{triad}_G_{i}{j}" for i in AXES for j in AXES]
        names += [f"{triad}_K2_{a}" for a in AXES]
        names += [f"{triad}_K_{a}" for a in AXES]
        names += [f"{triad}_b_{a}" for a in AXES]
        names += [f"{triad}_K3_{a}" for a in AXES]
    return names


_SLOTS: Final = _slot_names()


def _c_double(value: float) -> str:
    text = repr(float(value))
    return text if any(ch in text for ch in ".en") else text + ".0"


def _c_float(value: float) -> str:
    text = str(np.float32(value))
    return (text if any(ch in text for ch in ".en") else text + ".0") + "f"


def _c_string(text: str) -> str:
    """Return a C string literal's body: printable ASCII kept, the rest as 3-digit octal escapes."""
    out = []
    for byte in text.encode("utf-8"):
        ch = chr(byte)
        if 0x20 <= byte < 0x7F and ch not in '"\\?*/':
            out.append(ch)
        else:
            out.append(f"\\{byte:03o}")
    return "".join(out)


def _c_comment(text: str) -> str:
    """Return text safe inside a C comment: printable ASCII kept, other characters ``?``."""
    kept = "".join(ch if 0x20 <= ord(ch) < 0x7F else "?" for ch in text)
    return kept.replace("*/", "*_/")


def _tables(result: CalibrationResult) -> dict[str, Any]:
    """n_terms, coef, rate and leg per slot (module docstring), after the support checks."""
    unknown = [n for n in result.param_names if n not in _SLOTS]
    if unknown:
        raise InvalidInputError(f"the C runtime has no slot for the parameter(s) {unknown} of "
                                f"the result for {result.sensor_id!r}")
    coef = [[0.0] * _MAX_TERMS for _ in _SLOTS]
    n_terms = [1] * len(_SLOTS)
    rate = [0.0] * len(_SLOTS)
    leg = [0.0] * len(_SLOTS)
    for name, value in zip(result.param_names, result.values, strict=True):
        coef[_SLOTS.index(name)][0] = float(value)
    for tm in result.temperature_models:
        if tm.order > MAX_TEMPERATURE_ORDER:
            raise InvalidInputError(
                f"the C runtime evaluates temperature polynomials up to order "
                f"{MAX_TEMPERATURE_ORDER}; the model of {tm.name!r} has order {tm.order}")
        s = _SLOTS.index(tm.name)
        coef[s][:len(tm.coefficients)] = [float(c) for c in tm.coefficients]
        n_terms[s] = len(tm.coefficients)
        rate[s] = float(tm.rate_coefficient or 0.0)
        leg[s] = float(tm.leg_coefficient or 0.0)
    return {"n_terms": n_terms, "coef": coef, "rate": rate, "leg": leg}


def _initializer(result: CalibrationResult, tables: dict[str, Any], real: str) -> str:
    """Return the brace initializer of an ``imucal_params_d`` (real "d") or ``imucal_params_f``."""
    num = _c_double if real == "d" else _c_float
    model = "IMUCAL_MODEL_PER_AXIS" if result.model == "per-axis" else "IMUCAL_MODEL_TRIAD"
    has = ", ".join(str(int(result.has_triad(t))) for t in _TRIADS)
    t0 = result.reference_temperature_degc or 0.0
    lines = ["{", f"    {model},", f"    {{{has}}},  /* has_triad: gyro, accel */",
             f"    {int(bool(result.temperature_models))},  /* has_temperature */",
             f"    {num(t0)},  /* t0_degc */", "    {  /* n_terms */"]
    lines += [f"        {n},  /* {name} */" for n, name in zip(tables["n_terms"], _SLOTS,
                                                             strict=True)]
    lines += ["    },", "    {  /* coef: c_0 (value at T0) ... c_7 */"]
    lines += ["        {" + ", ".join(num(c) for c in row) + f"}},  /* {name} */"
              for row, name in zip(tables["coef"], _SLOTS, strict=True)]
    for key, what in (("rate", "rate: d [unit per degC/s]"), ("leg", "leg: h [unit]")):
        lines += ["    },", f"    {{  /* {what} */"]
        lines += [f"        {num(v)},  /* {name} */" for v, name in zip(tables[key], _SLOTS,
                                                                       strict=True)]
    lines += ["    }", "}"]
    return "\n".join(lines)


def _params_header(result: CalibrationResult, name: str) -> str:
    """Return the text of ``<name>_params.h``."""
    tables = _tables(result)
    sha = hashlib.sha256(result.to_json().encode("utf-8")).hexdigest()
    sensor = _c_string(result.sensor_id)
    guard = f"{name.upper()}_PARAMS_H"
    units = ", ".join(f"{k}: {v}" for k, v in sorted(result.input_units.items()))
    rng = result.temperature_range_degc
    fitted = "none" if rng is None else f"{rng[0]!r} .. {rng[1]!r} degC"
    t0 = "none" if result.reference_temperature_degc is None else \
        f"{result.reference_temperature_degc!r} degC"
    return f"""/*
 * {name}_params.h - generated by imucalib {__version__}; do not edit.
 *
 * Sensor: "{_c_comment(result.sensor_id)}"
 * Procedure: {_c_comment(result.procedure)}; model: {result.model}
 * Result format version: {result.format_version}
 * Input units: {_c_comment(units)}
 * Temperature models: {len(result.temperature_models)}, T0 {t0}, fitted range {fitted}
 * Library: imucalib_runtime.h / .c (docs/c-runtime.md), slot layout version {LAYOUT_VERSION}
 * SHA-256 of the result JSON (CalibrationResult.to_json(), UTF-8):
 * {sha}
 */
#ifndef {guard}
#define {guard}

#include "imucalib_runtime.h"

#if !defined(IMUCAL_LAYOUT_VERSION) || IMUCAL_LAYOUT_VERSION != {LAYOUT_VERSION}
#error "{name}_params.h needs the imucalib_runtime.h of slot layout version {LAYOUT_VERSION}"
#endif

#define {name.upper()}_FORMAT_VERSION {result.format_version}
#define {name.upper()}_RESULT_SHA256 "{sha}"

static const char {name}_sensor_id[] = "{sensor}";
static const char {name}_result_sha256[] = "{sha}";
static const int {name}_format_version = {result.format_version};

/* Parameters per slot (imucalib_runtime.h), SI, double precision (exact). */
static const imucal_params_d {name}_calibration_d = {_initializer(result, tables, "d")};

/* The same, rounded to float. */
static const imucal_params_f {name}_calibration_f = {_initializer(result, tables, "f")};

/* Referencing every constant keeps -Wunused-const-variable quiet where some go unused. */
static inline const imucal_params_d *{name}_get_d(void)
{{
    (void){name}_sensor_id;
    (void){name}_result_sha256;
    (void){name}_format_version;
    (void)&{name}_calibration_f;
    return &{name}_calibration_d;
}}

static inline const imucal_params_f *{name}_get_f(void)
{{
    (void)&{name}_calibration_d;
    return &{name}_calibration_f;
}}

#endif /* {guard} */
"""


def write_c_runtime(result: CalibrationResult, folder: str | os.PathLike[str], *,
                    name: str = "imucal") -> list[Path]:
    """Write a calibration as a C99 parameter header plus the runtime library.

    Parameters
    ----------
    result : CalibrationResult
        The calibration (triad or per-axis model, with or without temperature models).
    folder : str or os.PathLike
        Where to write (created if missing).
    name : str
        Prefix of the generated file and of its identifiers (``<name>_params.h``,
        ``<name>_calibration_d`` …); a C identifier.

    Returns
    -------
    list of Path
        ``<name>_params.h``, ``imucalib_runtime.h``, ``imucalib_runtime.c``.

    Raises
    ------
    InvalidInputError
        `name` not a C identifier, a parameter the runtime has no slot for, or a temperature
        model of order above :data:`MAX_TEMPERATURE_ORDER` (module docstring).

    Notes
    -----
    ``imucal_correct_d`` / ``imucal_correct_f`` evaluate Eqs. (C1)–(C4) and (C3′) of the module
    docstring (docs/c-runtime.md) per sample.
    """
    if not isinstance(name, str) or not _IDENTIFIER.match(name):
        raise InvalidInputError(f"`name` must be a C identifier ([A-Za-z_][A-Za-z0-9_]*); got "
                                f"{name!r}")
    header = _params_header(result, name)
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    params = out / f"{name}_params.h"
    params.write_text(header, encoding="utf-8")
    written = [params]
    library = resources.files("imucalib.exports").joinpath("c")
    body = library.joinpath(_IMPL).read_text(encoding="utf-8")
    for file_name in C_RUNTIME_FILES:
        path = out / file_name
        text = library.joinpath(file_name).read_text(encoding="utf-8")
        # the library's body is kept once in the package and written out for each precision
        path.write_text(text.replace(f'#include "{_IMPL}"\n', body), encoding="utf-8")
        written.append(path)
    return written
