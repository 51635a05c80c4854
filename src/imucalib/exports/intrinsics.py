"""A calibration's intrinsics for the tools users feed: MATLAB, ROS YAML, Kalibr, OpenVINS.

Contents
--------
:func:`intrinsics_struct`
    A :class:`~imucalib.models.result.CalibrationResult` → one flat dict (the MATLAB struct).
:func:`write_mat`, :func:`write_mat73`
    That struct as a MATLAB v5 file (:func:`scipy.io.savemat`) or a v7.3 file (HDF5 with the
    MATLAB userblock and ``MATLAB_class`` attributes).
:func:`format_ros_yaml`, :func:`write_ros_yaml`
    A ROS-style parameter YAML, one namespace per triad.
:func:`kalibr_intrinsics`, :func:`format_kalibr_intrinsics`, :func:`write_kalibr_intrinsics`
    Kalibr's ``scale-misalignment`` IMU model (``M``, ``A``, ``C_gyro_i``).
:func:`openvins_intrinsics`, :func:`format_openvins_intrinsics`, :func:`write_openvins_intrinsics`
    The intrinsics of OpenVINS' ``kalibr_imu_chain.yaml`` (``Tw``, ``R_IMUtoGYRO``, ``Ta``,
    ``R_IMUtoACC``, ``Tg``).

Conventions (docs/exports.md)
-----------------------------
imucalib's forward model, sensor frame S, per triad (docs/processing-estimation.md)::

    y_g = b_g + (I + M_g)·ω + G·f,     y_a = b_a + (I + M_a)·f   (+ K2_i·u_i² + K3_i·u_i³)  (X1)

(u = (I + M_a)·f, the model of :class:`~imucalib.models.triad.TriadModel`; u_i ≈ f_i.)

OpenVINS corrects with (docs "Analytical Propagation", IMU Intrinsic Models, and its
propagator; D = T⁻¹ computed by its loader from the file's T)::

    â = R_ACCtoIMU·D_a·(a_m − b_a),     ω̂ = R_GYROtoIMU·D_w·(ω_m − b_g − T_g·â)             (X2)

and keeps only the lower triangle of D_w, D_a (its ``kalibr`` intrinsic model). So each
(I + M)⁻¹ is split as Q·L (Q a rotation, L lower triangular with a positive diagonal)::

    (I + M)⁻¹ = Q·L,   R_xxxtoIMU = Q,   R_IMUtoxxx = Qᵀ,   T = L⁻¹,   T_g = G             (X3)

which makes (X2) the exact inverse of (X1) with the IMU frame equal to S. K2, K3 ≠ 0 and the
biases have no place in (X2): a result with K2 or K3 ≠ 0 is refused (X6 below); the biases are
written as
``imucalib_bias_gyro`` / ``imucalib_bias_accel`` (OpenVINS ignores them; its biases are state).

Kalibr's ``scale-misalignment`` IMU model (its source, ``IccSensors.py``,
``IccScaledMisalignedImu``) is the forward direction, in an IMU frame i where the accelerometer's
M is lower triangular::

    a_m = M_accel·a_i + b_a,   ω_m = M_gyro·C_gyro_i·ω_i + A·C_gyro_i·a_i + b_g             (X4)

With i = C_i_s·S (a rotation of imucalib's sensor frame S), (X1) = (X4) when::

    I + M_a = M_accel·C_i_s,   (I + M_g)·C_i_sᵀ = M_gyro·C_gyro_i,   A = G·C_i_sᵀ·C_gyro_iᵀ   (X5)

two LQ splits (L lower triangular with positive diagonal times a rotation). C_i_s is written as
``imucalib_C_i_sensor`` (Kalibr's i differs from S by it; Kalibr estimates its camera–IMU
extrinsics in i).

Neither Kalibr's nor OpenVINS' model holds K2 or K3. A result with K2 or K3 ≠ 0 is refused
with what leaving them out errs by: the accelerometer's output error K2_i·f² + K3_i·f³ at a
specific force ±f along the axis, the larger of the two signs,

    e_i(f) = |K2_i|·f² + |K3_i|·f³   (the largest over the axes, at 1 g and at 2 g)        (X6)

and written without them only when asked (``drop_terms``, CLI ``--drop-terms``), the header then
stating (X6). The better way is a result without them: a field calibration lets the data choose
the terms and carries the choice in the other σ (docs/field.md, "Model terms").

Temperature models (docs/processing-estimation.md, Eq. (T1))::

    p(T, Ṫ, ℓ) = Σ_j c_j (T − T0)^j + d·Ṫ + h·ℓ                                             (T1)

MATLAB and ROS YAML carry them (:func:`temperature_models_struct`; the values hold at T0).
Kalibr's and OpenVINS' models hold constant intrinsics: for a result with temperature models
their writers need a temperature and write the parameters evaluated there (Ṫ = 0, ℓ = 0;
:func:`at_temperature`), stating it as ``imucalib_temperature_degc``; without one they refuse.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import replace
from pathlib import Path
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from imucalib import __version__
from imucalib.errors import InvalidInputError
from imucalib.models.result import CalibrationResult
from imucalib.units import G0_MPS2, MG

__all__ = [
    "at_temperature",
    "format_kalibr_intrinsics",
    "format_openvins_intrinsics",
    "format_ros_yaml",
    "intrinsics_struct",
    "kalibr_intrinsics",
    "openvins_intrinsics",
    "temperature_models_struct",
    "write_kalibr_intrinsics",
    "write_mat",
    "write_mat73",
    "write_openvins_intrinsics",
    "write_ros_yaml",
]

_F64 = NDArray[np.float64]
_SUFFIX: Final = {"accel": "a", "gyro": "g"}
#: Bytes before the HDF5 superblock of a MATLAB v7.3 file.
_USERBLOCK_BYTES: Final = 512


def _triads(cal: CalibrationResult) -> list[str]:
    return [t for t in ("accel", "gyro") if cal.has_triad(t)]


def intrinsics_struct(cal: CalibrationResult) -> dict[str, Any]:
    """Return the result as one flat struct (docs/exports.md, "MATLAB").

    Per calibrated triad t ∈ {a, g}: ``b_t`` (3,), ``M_t`` (3, 3) of Eq. (X1) (row: sensor
    axis, column: input axis); ``K2_a`` (3,), ``K3_a`` (3,) and ``G_g`` (3, 3) (zeros where
    the model has none). A per-axis result is given in the triad form (b = K·b_axis,
    M = diag(K − 1)). Then ``param_names``, ``values``, ``covariance``, ``units`` (aligned with
    ``param_names``),
    ``sensor_id``, ``procedure``, ``model``; the values hold at T0. A result with temperature
    models adds ``temperature_models`` (:func:`temperature_models_struct`), a struct with one
    field per parameter that has a model; a result without any has no such field.
    """
    out: dict[str, Any] = {}
    base = replace(cal, temperature_models=()) if cal.temperature_models else cal
    for triad in _triads(cal):
        s = _SUFFIX[triad]
        tm = base.triad_model(triad)  # type: ignore[arg-type]
        out[f"b_{s}"] = np.asarray(tm.bias, dtype=np.float64).copy()
        out[f"M_{s}"] = np.asarray(tm.scale_misalignment, dtype=np.float64).copy()
        if triad == "accel":
            out["K2_a"] = np.asarray(tm.k2, dtype=np.float64).copy()
            out["K3_a"] = np.asarray(tm.k3, dtype=np.float64).copy()
        else:
            out["G_g"] = np.asarray(tm.g_sensitivity, dtype=np.float64).copy()
    out["param_names"] = list(cal.param_names)
    out["values"] = np.asarray(cal.values, dtype=np.float64).copy()
    out["covariance"] = np.asarray(cal.covariance, dtype=np.float64).copy()
    out["units"] = [cal.units.get(n, "") for n in cal.param_names]
    out["sensor_id"] = cal.sensor_id
    out["procedure"] = cal.procedure
    out["model"] = cal.model
    if cal.temperature_models:
        out["temperature_models"] = temperature_models_struct(cal)
    return out


def temperature_models_struct(cal: CalibrationResult) -> dict[str, dict[str, Any]]:
    """Return the result's temperature models keyed by parameter name (docs/exports.md).

    Each model of Eq. (T1), p(T, Ṫ, ℓ) = Σ_j c_j (T − T0)^j + d·Ṫ + h·ℓ, becomes a struct:
    ``name``, ``reference_temperature_degc`` (T0), ``coefficients`` (c_0 … c_m, a column),
    ``rate_coefficient`` (d) and ``leg_coefficient`` (h), NaN when the model has no such term,
    ``covariance`` (q × q, in the order of ``covariance_terms``: ``c_0`` … ``c_m``, ``d``, ``h``
    for the terms present), ``temperature_range_degc`` ([T_min T_max], NaN NaN when not
    stated), ``chi2``, ``dof``, ``order_criterion``, and the held-out check ``held_out_max_abs_z``,
    ``held_out_chi2``, ``held_out_dof``, ``held_out_p_value``, ``held_out_consistent`` (1 or 0;
    all NaN without a check). The keys are the parameter names (``gyro_bias_x`` …), which are
    MATLAB identifiers; a character that is not is replaced by ``_``.
    """
    nan = float("nan")
    out: dict[str, dict[str, Any]] = {}
    for tm in cal.temperature_models:
        terms = [f"c_{j}" for j in range(len(tm.coefficients))]
        terms += [t for t, v in (("d", tm.rate_coefficient), ("h", tm.leg_coefficient))
                  if v is not None]
        rng = tm.temperature_range_degc or (nan, nan)
        ho = tm.held_out
        out[_matlab_name(tm.name)] = {
            "name": tm.name,
            "reference_temperature_degc": float(tm.reference_temperature_degc),
            "coefficients": np.array(tm.coefficients, dtype=np.float64),
            "rate_coefficient": nan if tm.rate_coefficient is None else tm.rate_coefficient,
            "leg_coefficient": nan if tm.leg_coefficient is None else tm.leg_coefficient,
            "covariance": np.array(tm.covariance, dtype=np.float64),
            "covariance_terms": terms,
            "temperature_range_degc": np.array([rng], dtype=np.float64),
            "chi2": float(tm.chi2),
            "dof": float(tm.dof),
            "order_criterion": tm.order_criterion,
            "held_out_max_abs_z": nan if ho is None else ho.max_abs_z,
            "held_out_chi2": nan if ho is None else ho.chi2,
            "held_out_dof": nan if ho is None else float(ho.dof),
            "held_out_p_value": nan if ho is None else ho.p_value,
            "held_out_consistent": nan if ho is None else float(ho.consistent),
        }
    return out


def _matlab_name(name: str) -> str:
    """Return `name` as a MATLAB identifier: a letter first, then letters, digits and ``_``."""
    text = "".join(c if (c.isascii() and c.isalnum()) or c == "_" else "_" for c in name)
    return text if text[:1].isalpha() else f"p_{text}"


def _char_matrix(strings: list[str]) -> NDArray[np.str_]:
    width = max([len(s) for s in strings] + [1])
    return np.array([s.ljust(width) for s in strings], dtype=f"<U{width}")


def _char_matrices(struct: dict[str, Any]) -> dict[str, Any]:
    """Return `struct` with every list of strings a char matrix, nested structs included."""
    return {key: _char_matrix(value) if isinstance(value, list)
            else _char_matrices(value) if isinstance(value, dict) else value
            for key, value in struct.items()}


def write_mat(cal: CalibrationResult, path: str | os.PathLike[str], *,
              name: str = "imucal") -> Path:
    """Write :func:`intrinsics_struct` as struct `name` of a MATLAB v5 file; return the path.

    String lists (``param_names``, ``units``, ``covariance_terms``) become char matrices padded
    with blanks; ``temperature_models`` (when the result has any) is a nested struct.
    """
    from scipy.io import savemat

    struct = _char_matrices(intrinsics_struct(cal))
    out = Path(path)
    savemat(out, {name: struct}, format="5", oned_as="column", long_field_names=True)
    return out


def _mat73_header() -> bytes:
    text = (f"MATLAB 7.3 MAT-file, Platform: imucalib {__version__}, Created on: "
            f"{time.strftime('%a %b %d %H:%M:%S %Y', time.gmtime())} HDF5 schema 1.00 .")
    head = text.encode("ascii")[:116].ljust(116, b" ")
    # subsystem offset (8 bytes, unused), version 0x0200, endian indicator "IM"
    return head + b"\x00" * 8 + b"\x00\x02" + b"IM"


def _h5_struct(group: Any, struct: dict[str, Any]) -> None:
    """Write `struct` into the HDF5 `group` as MATLAB v7.3 does (see :func:`write_mat73`)."""
    import h5py

    group.attrs["MATLAB_class"] = np.bytes_("struct")
    fields = np.empty(len(struct), dtype=object)  # the field order, as MATLAB writes it
    fields[:] = [np.array(list(key), dtype="S1") for key in struct]
    group.attrs.create("MATLAB_fields", data=fields, dtype=h5py.vlen_dtype(np.dtype("S1")))
    for key, value in struct.items():
        if isinstance(value, dict):
            _h5_struct(group.create_group(key), value)
        elif isinstance(value, str | list):
            rows = [value] if isinstance(value, str) else value
            width = max([len(s) for s in rows] + [1])
            codes = np.array([[ord(c) for c in s.ljust(width)] for s in rows], dtype=np.uint16)
            ds = group.create_dataset(key, data=codes.T)
            ds.attrs["MATLAB_class"] = np.bytes_("char")
            ds.attrs["MATLAB_int_decode"] = np.int32(2)
        else:
            arr = np.atleast_2d(np.asarray(value, dtype=np.float64))
            if arr.shape[0] == 1 and np.ndim(value) == 1:
                arr = arr.T  # a column vector, as v5's oned_as="column"
            ds = group.create_dataset(key, data=arr.T)
            ds.attrs["MATLAB_class"] = np.bytes_("double")


def write_mat73(cal: CalibrationResult, path: str | os.PathLike[str], *,
                name: str = "imucal") -> Path:
    """Write :func:`intrinsics_struct` as struct `name` of a MATLAB v7.3 (HDF5) file.

    The file is HDF5 with a 512-byte userblock holding the MATLAB header; the struct is a
    group (``MATLAB_class`` ``struct``, ``MATLAB_fields`` its field names), each number array
    a dataset (``double``) stored transposed (MATLAB is column-major: h5py reads
    ``f[name][field][()].T``), each string a ``char`` dataset of UTF-16 code units
    (``MATLAB_int_decode`` 2), string lists as blank-padded char matrices, a nested struct
    (``temperature_models`` and each of its models) a nested group.
    """
    import h5py

    from imucalib.errors import RecordingWriteError
    from imucalib.io._abandon import WRITE_ERRORS, abandon_copy

    out = Path(path)
    struct = intrinsics_struct(cal)
    # written under a temporary name and renamed: a write HDF5 fails (a full disk, EIO) gives
    # the copy up without touching it again and removes it (docs/reliability.md), and `out`
    # is never a half-written file
    tmp = out.with_name(f".{out.name}.partial")
    fh: h5py.File | None = None
    try:
        fh = h5py.File(tmp, "w", userblock_size=_USERBLOCK_BYTES)
        _h5_struct(fh.create_group(name), struct)
        fh.close()
    except WRITE_ERRORS as exc:
        reason = abandon_copy(tmp, f"writing {out.name}", exc, fh)
        raise RecordingWriteError(f"cannot write {out}: HDF5 failed: {reason}") from exc
    with open(tmp, "r+b") as f:
        f.write(_mat73_header())
    os.replace(tmp, out)
    return out


def _yfloat(value: float) -> str:
    """Return ``repr(value)`` as a YAML 1.1 float: ``1e-05`` (a string to PyYAML) → ``1.0e-05``."""
    text = repr(float(value))
    if "e" in text and "." not in text:
        mantissa, exponent = text.split("e")
        text = f"{mantissa}.0e{exponent}"
    return text


def _flow(values: Any) -> str:
    return "[" + ", ".join(_yfloat(v) for v in np.ravel(values)) + "]"


def format_ros_yaml(cal: CalibrationResult) -> str:
    """Return a ROS-style parameter YAML of the result (docs/exports.md, "ROS YAML").

    One namespace per calibrated triad (``accel``, ``gyro``): ``bias`` (3), ``scale_misalignment``
    (I + M of Eq. (X1), row-major, 9), ``g_sensitivity`` (gyro, row-major 9), ``k2`` and
    ``k3`` (accel, 3 each; ``k3`` only for a result with K3); then ``parameters`` (names),
    ``values``, ``covariance`` (row-major, k²) and ``units``; the values hold at T0. A result
    with temperature models adds ``temperature_models``, one mapping per parameter with a
    model of Eq. (T1) (the fields of :func:`temperature_models_struct`, ``null`` for a term or
    range the model has not, the held-out check as a mapping or ``null``). Floats are ``repr``
    with a ``.0`` put before an exponent that lacks a point (``1.0e-05``: YAML 1.1 reads
    ``1e-05`` as a string); they round-trip exactly.
    """
    s = intrinsics_struct(cal)
    unit = {"accel": "m/s^2", "gyro": "rad/s"}
    lines = [f"# imucalib {__version__} calibration intrinsics (docs/exports.md)",
             "# model: y = bias + scale_misalignment*x (+ g_sensitivity*f, gyro)"
             " (+ k2_i*u_i^2 + k3_i*u_i^3, u = scale_misalignment*x, accel);",
             "# frame: the sensor frame; x true input, y output; matrices row-major"
             " (row: sensor axis, column: input axis)",
             f"sensor_id: {_quote(cal.sensor_id)}",
             f"procedure: {_quote(cal.procedure)}",
             f"model: {_quote(cal.model)}"]
    for triad in _triads(cal):
        t = _SUFFIX[triad]
        lines += [f"{triad}:",
                  f"  bias: {_flow(s[f'b_{t}'])}  # {unit[triad]}",
                  f"  scale_misalignment: {_flow(np.eye(3) + s[f'M_{t}'])}  # 1"]
        if triad == "gyro":
            lines.append(f"  g_sensitivity: {_flow(s['G_g'])}  # rad/s/(m/s^2)")
        else:
            lines.append(f"  k2: {_flow(s['K2_a'])}  # 1/(m/s^2)")
            if "accel_K3_x" in cal.param_names:
                lines.append(f"  k3: {_flow(s['K3_a'])}  # 1/(m/s^2)^2")
    lines += ["parameters: [" + ", ".join(_quote(n) for n in cal.param_names) + "]",
              f"values: {_flow(s['values'])}",
              f"covariance: {_flow(s['covariance'])}  # row-major, k x k",
              "units: [" + ", ".join(_quote(u) for u in s["units"]) + "]"]
    lines += _ros_temperature_models(cal)
    return "\n".join(lines) + "\n"


def _ros_temperature_models(cal: CalibrationResult) -> list[str]:
    """Return the ``temperature_models`` block of :func:`format_ros_yaml` (none without)."""
    if not cal.temperature_models:
        return []
    lines = ["# temperature models, Eq. (T1): p(T, Tdot, l) = sum_j c_j*(T - T0)^j + d*Tdot + h*l",
             "# (T degC, Tdot degC/s, l = +1 heating, -1 cooling, 0 the mean of both legs);",
             "# the values above hold at T0; null = the model has no such term",
             "temperature_models:"]
    for tm in cal.temperature_models:
        terms = [f"c_{j}" for j in range(len(tm.coefficients))]
        terms += [t for t, v in (("d", tm.rate_coefficient), ("h", tm.leg_coefficient))
                  if v is not None]
        ho = tm.held_out
        lines += [f"  {_quote(tm.name)}:",
                  f"    reference_temperature_degc: {_yfloat(tm.reference_temperature_degc)}",
                  f"    coefficients: {_flow(tm.coefficients)}",
                  f"    rate_coefficient: {_scalar(tm.rate_coefficient)}",
                  f"    leg_coefficient: {_scalar(tm.leg_coefficient)}",
                  f"    covariance: {_flow(tm.covariance)}  # row-major, q x q",
                  "    covariance_terms: [" + ", ".join(_quote(t) for t in terms) + "]",
                  "    temperature_range_degc: " + ("null" if tm.temperature_range_degc is None
                                                    else _flow(tm.temperature_range_degc)),
                  f"    chi2: {_yfloat(tm.chi2)}",
                  f"    dof: {tm.dof}",
                  f"    order_criterion: {_quote(tm.order_criterion)}"]
        if ho is None:
            lines.append("    held_out: null")
        else:
            lines += ["    held_out:",
                      f"      max_abs_z: {_yfloat(ho.max_abs_z)}",
                      f"      chi2: {_yfloat(ho.chi2)}",
                      f"      dof: {ho.dof}",
                      f"      p_value: {_yfloat(ho.p_value)}",
                      f"      consistent: {'true' if ho.consistent else 'false'}"]
    return lines


def _scalar(value: float | None) -> str:
    return "null" if value is None else _yfloat(value)


def _quote(text: str) -> str:
    """Return `text` as a YAML double-quoted scalar (JSON escaping is valid YAML)."""
    import json

    return json.dumps(text, ensure_ascii=True)


def write_ros_yaml(cal: CalibrationResult, path: str | os.PathLike[str]) -> Path:
    """Write :func:`format_ros_yaml` to `path`; return the path."""
    out = Path(path)
    out.write_text(format_ros_yaml(cal), encoding="utf-8")
    return out


def _rotation_lower(d: _F64, triad: str) -> tuple[_F64, _F64]:
    """Split `d` = Q·L, Q a rotation, L lower triangular with positive diagonal (Eq. X3)."""
    from scipy.linalg import rq

    if not np.linalg.det(d) > 0.0:
        raise InvalidInputError(f"the {triad} I + M has a determinant ≤ 0; it is no "
                                "scale/misalignment OpenVINS can hold")
    upper, q = rq(d.T)  # dᵀ = upper·q  ⇒  d = qᵀ·upperᵀ
    lower = upper.T
    signs = np.sign(np.diag(lower))
    return q.T * signs, signs[:, None] * lower


def _lower_rotation(x: _F64, triad: str) -> tuple[_F64, _F64]:
    """Split `x` = L·Q, L lower triangular with positive diagonal, Q a rotation (Eq. X5)."""
    if not np.linalg.det(x) > 0.0:
        raise InvalidInputError(f"the {triad} I + M has a determinant ≤ 0; it is no "
                                "scale/misalignment Kalibr can hold")
    q, upper = np.linalg.qr(x.T)  # xᵀ = q·upper  ⇒  x = upperᵀ·qᵀ
    signs = np.sign(np.diag(upper))
    return upper.T * signs, signs[:, None] * q.T


def _no_k2(s: dict[str, Any], tool: str, drop_terms: bool = False) -> str:
    """Refuse a K2 or K3 ≠ 0 the tool's model lacks, stating what leaving it out errs by (X6).

    e_i(f) = |K2_i|·f² + |K3_i|·f³, the largest over the axes at f = 1 g and 2 g. With
    `drop_terms` the K2 and K3 in `s` are set to 0 and the statement returned (for the file's
    header); "" when there were none.
    """
    terms = [t for t in ("K2", "K3") if f"{t}_a" in s and np.any(s[f"{t}_a"] != 0.0)]
    if not terms:
        return ""
    k2, k3 = (np.abs(np.asarray(s.get(f"{t}_a", np.zeros(3)), dtype=np.float64))
              for t in ("K2", "K3"))
    err = {g: k2 * (g * G0_MPS2) ** 2 + k3 * (g * G0_MPS2) ** 3 for g in (1, 2)}
    worst = int(np.argmax(err[1]))
    what = " and ".join(terms)
    coefficients = ", ".join(
        f"{t}_{'xyz'[worst]} = {float(s[f'{t}_a'][worst]):.3g} "
        f"{'1/(m/s²)' if t == 'K2' else '1/(m/s²)²'}" for t in terms)
    formula = " + ".join({"K2": "K2·f²", "K3": "K3·f³"}[t] for t in terms)
    statement = (f"leaving the accelerometer {what} out errs by up to "
                 f"{float(err[1][worst]) / MG:.3g} mg at 1 g and {float(np.max(err[2])) / MG:.3g}"
                 f" mg at 2 g ({coefficients}, error {formula}; X6)")
    if not drop_terms:
        lacks = {"K2": "quadratic", "K3": "cubic"}
        flags = ",".join(f"-{t.lower()}" for t in terms)
        raise InvalidInputError(
            f"the result's accelerometer {what} {'is' if len(terms) == 1 else 'are'} not 0 and "
            f"{tool}'s IMU model has no {' or '.join(lacks[t] for t in terms)} scale factor: "
            f"{statement}; pass --drop-terms (drop_terms=True) to write it without, or "
            f"calibrate again without {what} (the field calibration: --set terms={flags}, "
            "or let the data choose; docs/exports.md)")
    for t in terms:
        s[f"{t}_a"] = np.zeros(3)
    return statement


def at_temperature(cal: CalibrationResult, temperature_degc: float | None, tool: str
                   ) -> tuple[CalibrationResult, float | None]:
    """Return the result with its values at `temperature_degc` for a tool without T models.

    Kalibr's and OpenVINS' IMU models hold constant intrinsics. A result with temperature
    models (Eq. (T1)) is evaluated at `temperature_degc` with Ṫ = 0 and ℓ = 0 (the mean of both
    legs; :meth:`~imucalib.models.result.CalibrationResult.values_at`) and returned without
    its models, with that temperature. A result without models is returned unchanged, with
    None (its values hold at every temperature; `temperature_degc` is not needed).

    Raises
    ------
    InvalidInputError
        A result with temperature models and no `temperature_degc` (the message names the
        parameters and the CLI option ``--temperature``), a temperature that is not a finite
        number, or one outside the models' fitted range
        (:attr:`~imucalib.models.result.CalibrationResult.temperature_range_degc`).
    """
    if not cal.temperature_models:
        return cal, None
    names = ", ".join(tm.name for tm in cal.temperature_models)
    if temperature_degc is None:
        raise InvalidInputError(
            f"the result has temperature models (Eq. (T1)) for {names}; {tool}'s IMU model "
            "holds constant intrinsics, so they cannot be written without a temperature: pass "
            "the temperature to evaluate them at (temperature_degc=…; CLI: --temperature DEGC), "
            "or export mat, mat73 or ros-yaml, which carry the models")
    if isinstance(temperature_degc, bool) or not isinstance(
            temperature_degc, int | float | np.integer | np.floating) \
            or not math.isfinite(float(temperature_degc)):
        raise InvalidInputError(f"the temperature must be a finite number of °C; got "
                                f"{temperature_degc!r}")
    t = float(temperature_degc)
    rng = cal.temperature_range_degc
    if rng is not None and not rng[0] <= t <= rng[1]:
        raise InvalidInputError(
            f"the temperature {t!r} °C is outside the range the temperature models were fitted "
            f"over, [{rng[0]!r}, {rng[1]!r}] °C; the models are not valid there")
    values, _ = cal.values_at(t, 0.0, 0.0)
    return replace(cal, values=values[0], temperature_models=()), t


def kalibr_intrinsics(cal: CalibrationResult, *, temperature_degc: float | None = None,
                      drop_terms: bool = False) -> dict[str, _F64]:
    """Return Kalibr's ``M_accel``, ``M_gyro``, ``A``, ``C_gyro_i`` and ``C_i_sensor`` (Eq. X5).

    Needs both triads in the result. A result with temperature models is evaluated at
    `temperature_degc` (:func:`at_temperature`, Eq. (T1)).

    Raises
    ------
    InvalidInputError
        A triad missing, K2 or K3 ≠ 0 (not in Kalibr's model) unless `drop_terms` (then written
        without it, :func:`_no_k2`), an I + M with determinant ≤ 0, or a temperature
        :func:`at_temperature` refuses (none given for a result with models).
    """
    cal, _ = at_temperature(cal, temperature_degc, "Kalibr")
    s = intrinsics_struct(cal)
    _no_k2(s, "Kalibr", drop_terms)
    if "M_a" not in s or "M_g" not in s:
        raise InvalidInputError("Kalibr's IMU model needs both the gyro and the accelerometer "
                                "calibrated")
    m_accel, c_i_s = _lower_rotation(np.eye(3) + s["M_a"], "accel")
    m_gyro, c_gyro_i = _lower_rotation((np.eye(3) + s["M_g"]) @ c_i_s.T, "gyro")
    a = np.asarray(s["G_g"] @ c_i_s.T @ c_gyro_i.T, dtype=np.float64)
    return {"M_accel": m_accel, "M_gyro": m_gyro, "A": a, "C_gyro_i": c_gyro_i,
            "C_i_sensor": c_i_s}


def format_kalibr_intrinsics(cal: CalibrationResult, *, temperature_degc: float | None = None,
                             drop_terms: bool = False) -> str:
    """Return the intrinsics in the layout of Kalibr's ``scale-misalignment`` IMU result YAML.

    A result with temperature models needs `temperature_degc` (:func:`at_temperature`); the
    file then states it as ``imucalib_temperature_degc``. A K2 or K3 left out (`drop_terms`) is
    stated in the header with the error it leaves.
    """
    cal, t = at_temperature(cal, temperature_degc, "Kalibr")
    k = kalibr_intrinsics(cal, drop_terms=drop_terms)
    s = intrinsics_struct(cal)
    dropped = _no_k2(dict(s), "Kalibr", drop_terms)

    def block(indent: str, mat: _F64) -> list[str]:
        return [f"{indent}- {_flow(row)}" for row in mat]

    lines = [f"# imucalib {__version__}: IMU intrinsics in Kalibr's scale-misalignment model",
             "# (a_m = M a_i + b_a; w_m = M C_gyro_i w_i + A C_gyro_i a_i + b_g; docs/exports.md)",
             *_dropped_lines("", dropped),
             "model: scale-misalignment",
             "accelerometers:",
             "  M:", *block("    ", k["M_accel"]),
             "gyroscopes:",
             "  M:", *block("    ", k["M_gyro"]),
             "  A:", *block("    ", k["A"]),
             "  C_gyro_i:", *block("    ", k["C_gyro_i"]),
             "# the frame i = imucalib_C_i_sensor * (imucalib's sensor frame)",
             "imucalib_C_i_sensor:", *block("  ", k["C_i_sensor"]),
             f"imucalib_bias_accel: {_flow(s['b_a'])}  # m/s^2, in the accelerometer's output",
             f"imucalib_bias_gyro: {_flow(s['b_g'])}  # rad/s, in the gyro's output"]
    lines += _temperature_lines("", t)
    return "\n".join(lines) + "\n"


def _dropped_lines(indent: str, statement: str) -> list[str]:
    """Return the header lines of a K2 and/or K3 left out (--drop-terms), none when nothing was."""
    if not statement:
        return []
    words, lines, line = statement.split(), [], ""
    for w in words:
        if len(line) + len(w) + 1 > 76:
            lines.append(line)
            line = w
        else:
            line = f"{line} {w}".strip()
    lines.append(line)
    what = statement.split("leaving the accelerometer ", 1)[1].split(" out ", 1)[0]
    return [f"{indent}# {what.upper()} LEFT OUT (--drop-terms):",
            *(f"{indent}#   {x}" for x in lines)]


def _temperature_lines(indent: str, temperature_degc: float | None) -> list[str]:
    """Return the lines stating the temperature the values hold at (none without models)."""
    if temperature_degc is None:
        return []
    return [f"{indent}# the result's temperature models (Eq. (T1)) evaluated at this temperature",
            f"{indent}# (rate 0, the mean of the heating and cooling legs), in degC",
            f"{indent}imucalib_temperature_degc: {_yfloat(temperature_degc)}"]


def write_kalibr_intrinsics(cal: CalibrationResult, path: str | os.PathLike[str], *,
                            temperature_degc: float | None = None,
                            drop_terms: bool = False) -> Path:
    """Write :func:`format_kalibr_intrinsics` to `path`; return the path."""
    out = Path(path)
    out.write_text(format_kalibr_intrinsics(cal, temperature_degc=temperature_degc,
                                            drop_terms=drop_terms), encoding="utf-8")
    return out


def openvins_intrinsics(cal: CalibrationResult, *, temperature_degc: float | None = None,
                        drop_terms: bool = False) -> dict[str, _F64]:
    """Return OpenVINS' ``Tw``, ``R_IMUtoGYRO``, ``Ta``, ``R_IMUtoACC``, ``Tg`` (Eq. X3).

    A triad the result does not calibrate gets identity (``Tg`` zero). A result with
    temperature models is evaluated at `temperature_degc` (:func:`at_temperature`, Eq. (T1)).

    Raises
    ------
    InvalidInputError
        K2 or K3 ≠ 0 (not in OpenVINS' model) unless `drop_terms` (then written without it,
        :func:`_no_k2`), an I + M with determinant ≤ 0, or a temperature
        :func:`at_temperature` refuses (none given for a result with models).
    """
    cal, _ = at_temperature(cal, temperature_degc, "OpenVINS")
    s = intrinsics_struct(cal)
    _no_k2(s, "OpenVINS", drop_terms)
    out: dict[str, _F64] = {}
    for triad, t_key, r_key in (("gyro", "Tw", "R_IMUtoGYRO"), ("accel", "Ta", "R_IMUtoACC")):
        t = _SUFFIX[triad]
        if f"M_{t}" not in s:
            out[t_key], out[r_key] = np.eye(3), np.eye(3)
            continue
        q, lower = _rotation_lower(np.linalg.inv(np.eye(3) + s[f"M_{t}"]), triad)
        out[t_key] = np.asarray(np.linalg.inv(lower), dtype=np.float64)
        out[r_key] = q.T
    out["Tg"] = np.asarray(s.get("G_g", np.zeros((3, 3))), dtype=np.float64)
    return out


def format_openvins_intrinsics(cal: CalibrationResult, *, temperature_degc: float | None = None,
                               drop_terms: bool = False) -> str:
    """Return the ``imu0`` intrinsics block of OpenVINS' ``kalibr_imu_chain.yaml`` (Eq. X3).

    A result with temperature models needs `temperature_degc` (:func:`at_temperature`); the
    block then states it as ``imucalib_temperature_degc``. The header comment names the
    ``estimator_config.yaml`` keys OpenVINS reads with it (docs/exports.md).
    """
    cal, t = at_temperature(cal, temperature_degc, "OpenVINS")
    mats = openvins_intrinsics(cal, drop_terms=drop_terms)
    s = intrinsics_struct(cal)
    dropped = _no_k2(dict(s), "OpenVINS", drop_terms)
    lines = [f"# imucalib {__version__}: IMU intrinsics for OpenVINS (kalibr IMU model: lower-",
             "# triangular D = T^-1; docs/exports.md). Merge the noise keys of the "
             "openvins-yaml export into imu0.",
             "# OpenVINS reads this file as the relative_config_imu of its estimator_config.yaml",
             "# and takes the intrinsic model from imu0/model below. In estimator_config.yaml set",
             "# calib_imu_intrinsics and calib_imu_g_sensitivity to false to apply these values",
             "# as they are (OpenVINS applies Tw, Ta, R_IMUtoGYRO, R_IMUtoACC and Tg either way),",
             "# or to true to refine them online starting from these values.",
             *_dropped_lines("", dropped),
             "imu0:",
             '  model: "kalibr"']
    for key in ("Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC", "Tg"):
        lines.append(f"  {key}:")
        lines += [f"    - {_flow(row)}" for row in mats[key]]
    for triad in _triads(cal):
        unit = "rad/s" if triad == "gyro" else "m/s^2"
        lines.append(f"  imucalib_bias_{triad}: {_flow(s[f'b_{_SUFFIX[triad]}'])}  # {unit}, "
                     "b of (X2); OpenVINS estimates its own")
    lines += _temperature_lines("  ", t)
    return "\n".join(lines) + "\n"


def write_openvins_intrinsics(cal: CalibrationResult, path: str | os.PathLike[str], *,
                              temperature_degc: float | None = None,
                              drop_terms: bool = False) -> Path:
    """Write :func:`format_openvins_intrinsics` to `path`; return the path."""
    out = Path(path)
    out.write_text(format_openvins_intrinsics(cal, temperature_degc=temperature_degc,
                                              drop_terms=drop_terms), encoding="utf-8")
    return out
