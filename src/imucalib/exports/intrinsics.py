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

    y_g = b_g + (I + M_g)·ω + G·f,     y_a = b_a + (I + M_a)·f   (+ K2_i·f_i²)             (X1)

OpenVINS corrects with (docs "Analytical Propagation", IMU Intrinsic Models, and its
propagator; D = T⁻¹ computed by its loader from the file's T)::

    â = R_ACCtoIMU·D_a·(a_m − b_a),     ω̂ = R_GYROtoIMU·D_w·(ω_m − b_g − T_g·â)             (X2)

and keeps only the lower triangle of D_w, D_a (its ``kalibr`` intrinsic model). So each
(I + M)⁻¹ is split as Q·L (Q a rotation, L lower triangular with a positive diagonal)::

    (I + M)⁻¹ = Q·L,   R_xxxtoIMU = Q,   R_IMUtoxxx = Qᵀ,   T = L⁻¹,   T_g = G             (X3)

which makes (X2) the exact inverse of (X1) with the IMU frame equal to S. K2 ≠ 0 and the
biases have no place in (X2): a result with K2 ≠ 0 is refused; the biases are written as
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
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from imucalib import __version__
from imucalib.errors import InvalidInputError
from imucalib.models.result import CalibrationResult

__all__ = [
    "format_kalibr_intrinsics",
    "format_openvins_intrinsics",
    "format_ros_yaml",
    "intrinsics_struct",
    "kalibr_intrinsics",
    "openvins_intrinsics",
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
    axis, column: input axis); ``K2_a`` (3,) and ``G_g`` (3, 3) (zeros where the model has
    none). A per-axis result is given in the triad form (b = K·b_axis, M = diag(K − 1)). Then
    ``param_names``, ``values``, ``covariance``, ``units`` (aligned with ``param_names``),
    ``sensor_id``, ``procedure``, ``model``. Temperature models are not part of it: the values
    are the parameters' reference values.
    """
    out: dict[str, Any] = {}
    for triad in _triads(cal):
        s = _SUFFIX[triad]
        tm = cal.triad_model(triad)  # type: ignore[arg-type]
        out[f"b_{s}"] = np.asarray(tm.bias, dtype=np.float64).copy()
        out[f"M_{s}"] = np.asarray(tm.scale_misalignment, dtype=np.float64).copy()
        if triad == "accel":
            out["K2_a"] = np.asarray(tm.k2, dtype=np.float64).copy()
        else:
            out["G_g"] = np.asarray(tm.g_sensitivity, dtype=np.float64).copy()
    out["param_names"] = list(cal.param_names)
    out["values"] = np.asarray(cal.values, dtype=np.float64).copy()
    out["covariance"] = np.asarray(cal.covariance, dtype=np.float64).copy()
    out["units"] = [cal.units.get(n, "") for n in cal.param_names]
    out["sensor_id"] = cal.sensor_id
    out["procedure"] = cal.procedure
    out["model"] = cal.model
    return out


def _char_matrix(strings: list[str]) -> NDArray[np.str_]:
    width = max([len(s) for s in strings] + [1])
    return np.array([s.ljust(width) for s in strings], dtype=f"<U{width}")


def write_mat(cal: CalibrationResult, path: str | os.PathLike[str], *,
              name: str = "imucal") -> Path:
    """Write :func:`intrinsics_struct` as struct `name` of a MATLAB v5 file; return the path.

    String lists (``param_names``, ``units``) become char matrices padded with blanks.
    """
    from scipy.io import savemat

    struct = intrinsics_struct(cal)
    for key in ("param_names", "units"):
        struct[key] = _char_matrix(struct[key])
    out = Path(path)
    savemat(out, {name: struct}, format="5", oned_as="column", long_field_names=True)
    return out


def _mat73_header() -> bytes:
    text = (f"MATLAB 7.3 MAT-file, Platform: imucalib {__version__}, Created on: "
            f"{time.strftime('%a %b %d %H:%M:%S %Y', time.gmtime())} HDF5 schema 1.00 .")
    head = text.encode("ascii")[:116].ljust(116, b" ")
    # subsystem offset (8 bytes, unused), version 0x0200, endian indicator "IM"
    return head + b"\x00" * 8 + b"\x00\x02" + b"IM"


def write_mat73(cal: CalibrationResult, path: str | os.PathLike[str], *,
                name: str = "imucal") -> Path:
    """Write :func:`intrinsics_struct` as struct `name` of a MATLAB v7.3 (HDF5) file.

    The file is HDF5 with a 512-byte userblock holding the MATLAB header; the struct is a
    group (``MATLAB_class`` ``struct``, ``MATLAB_fields`` its field names), each number array
    a dataset (``double``) stored transposed (MATLAB is column-major: h5py reads
    ``f[name][field][()].T``), each string a ``char`` dataset of UTF-16 code units
    (``MATLAB_int_decode`` 2), string lists as blank-padded char matrices.
    """
    import h5py

    out = Path(path)
    struct = intrinsics_struct(cal)
    with h5py.File(out, "w", userblock_size=_USERBLOCK_BYTES) as fh:
        group = fh.create_group(name)
        group.attrs["MATLAB_class"] = np.bytes_("struct")
        fields = np.empty(len(struct), dtype=object)  # the field order, as MATLAB writes it
        fields[:] = [np.array(list(key), dtype="S1") for key in struct]
        group.attrs.create("MATLAB_fields", data=fields, dtype=h5py.vlen_dtype(np.dtype("S1")))
        for key, value in struct.items():
            if isinstance(value, str | list):
                rows = [value] if isinstance(value, str) else value
                width = max([len(s) for s in rows] + [1])
                codes = np.array([[ord(c) for c in s.ljust(width)] for s in rows],
                                 dtype=np.uint16)
                ds = group.create_dataset(key, data=codes.T)
                ds.attrs["MATLAB_class"] = np.bytes_("char")
                ds.attrs["MATLAB_int_decode"] = np.int32(2)
            else:
                arr = np.atleast_2d(np.asarray(value, dtype=np.float64))
                if arr.shape[0] == 1 and np.ndim(value) == 1:
                    arr = arr.T  # a column vector, as v5's oned_as="column"
                ds = group.create_dataset(key, data=arr.T)
                ds.attrs["MATLAB_class"] = np.bytes_("double")
    with open(out, "r+b") as fh:
        fh.write(_mat73_header())
    return out


def _flow(values: Any) -> str:
    return "[" + ", ".join(repr(float(v)) for v in np.ravel(values)) + "]"


def format_ros_yaml(cal: CalibrationResult) -> str:
    """Return a ROS-style parameter YAML of the result (docs/exports.md, "ROS YAML").

    One namespace per calibrated triad (``accel``, ``gyro``): ``bias`` (3), ``scale_misalignment``
    (I + M of Eq. (X1), row-major, 9), ``g_sensitivity`` (gyro, row-major 9) and ``k2``
    (accel, 3); then ``parameters`` (names), ``values``, ``covariance`` (row-major, k²) and
    ``units``. Floats are ``repr`` (round-trip exact).
    """
    s = intrinsics_struct(cal)
    unit = {"accel": "m/s^2", "gyro": "rad/s"}
    lines = [f"# imucalib {__version__} calibration intrinsics (docs/exports.md)",
             "# model: y = bias + scale_misalignment*x (+ g_sensitivity*f, gyro)"
             " (+ k2_i*x_i^2, accel);",
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
    lines += ["parameters: [" + ", ".join(_quote(n) for n in cal.param_names) + "]",
              f"values: {_flow(s['values'])}",
              f"covariance: {_flow(s['covariance'])}  # row-major, k x k",
              "units: [" + ", ".join(_quote(u) for u in s["units"]) + "]"]
    return "\n".join(lines) + "\n"


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


def _no_k2(s: dict[str, Any], tool: str) -> None:
    if "K2_a" in s and np.any(s["K2_a"] != 0.0):
        raise InvalidInputError(f"the result's accelerometer K2 is not 0; {tool}'s IMU model "
                                "has no quadratic scale factor (docs/exports.md)")


def kalibr_intrinsics(cal: CalibrationResult) -> dict[str, _F64]:
    """Return Kalibr's ``M_accel``, ``M_gyro``, ``A``, ``C_gyro_i`` and ``C_i_sensor`` (Eq. X5).

    Needs both triads in the result.

    Raises
    ------
    InvalidInputError
        A triad missing, K2 ≠ 0 (not in Kalibr's model), or an I + M with determinant ≤ 0.
    """
    s = intrinsics_struct(cal)
    _no_k2(s, "Kalibr")
    if "M_a" not in s or "M_g" not in s:
        raise InvalidInputError("Kalibr's IMU model needs both the gyro and the accelerometer "
                                "calibrated")
    m_accel, c_i_s = _lower_rotation(np.eye(3) + s["M_a"], "accel")
    m_gyro, c_gyro_i = _lower_rotation((np.eye(3) + s["M_g"]) @ c_i_s.T, "gyro")
    a = np.asarray(s["G_g"] @ c_i_s.T @ c_gyro_i.T, dtype=np.float64)
    return {"M_accel": m_accel, "M_gyro": m_gyro, "A": a, "C_gyro_i": c_gyro_i,
            "C_i_sensor": c_i_s}


def format_kalibr_intrinsics(cal: CalibrationResult) -> str:
    """Return the intrinsics in the layout of Kalibr's ``scale-misalignment`` IMU result YAML."""
    k = kalibr_intrinsics(cal)
    s = intrinsics_struct(cal)

    def block(indent: str, mat: _F64) -> list[str]:
        return [f"{indent}- {_flow(row)}" for row in mat]

    lines = [f"# imucalib {__version__}: IMU intrinsics in Kalibr's scale-misalignment model",
             "# (a_m = M a_i + b_a; w_m = M C_gyro_i w_i + A C_gyro_i a_i + b_g; docs/exports.md)",
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
    return "\n".join(lines) + "\n"


def write_kalibr_intrinsics(cal: CalibrationResult, path: str | os.PathLike[str]) -> Path:
    """Write :func:`format_kalibr_intrinsics` to `path`; return the path."""
    out = Path(path)
    out.write_text(format_kalibr_intrinsics(cal), encoding="utf-8")
    return out


def openvins_intrinsics(cal: CalibrationResult) -> dict[str, _F64]:
    """Return OpenVINS' ``Tw``, ``R_IMUtoGYRO``, ``Ta``, ``R_IMUtoACC``, ``Tg`` (Eq. X3).

    A triad the result does not calibrate gets identity (``Tg`` zero).

    Raises
    ------
    InvalidInputError
        K2 ≠ 0 (not in OpenVINS' model), or an I + M with determinant ≤ 0.
    """
    s = intrinsics_struct(cal)
    _no_k2(s, "OpenVINS")
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


def format_openvins_intrinsics(cal: CalibrationResult) -> str:
    """Return the ``imu0`` intrinsics block of OpenVINS' ``kalibr_imu_chain.yaml`` (Eq. X3)."""
    mats = openvins_intrinsics(cal)
    s = intrinsics_struct(cal)
    lines = [f"# imucalib {__version__}: IMU intrinsics for OpenVINS (kalibr IMU model: lower-",
             "# triangular D = T^-1; docs/exports.md). Merge the noise keys of the "
             "openvins-yaml export into imu0.",
             "imu0:",
             '  model: "kalibr"']
    for key in ("Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC", "Tg"):
        lines.append(f"  {key}:")
        lines += [f"    - {_flow(row)}" for row in mats[key]]
    for triad in _triads(cal):
        unit = "rad/s" if triad == "gyro" else "m/s^2"
        lines.append(f"  imucalib_bias_{triad}: {_flow(s[f'b_{_SUFFIX[triad]}'])}  # {unit}, "
                     "b of (X2); OpenVINS estimates its own")
    return "\n".join(lines) + "\n"


def write_openvins_intrinsics(cal: CalibrationResult, path: str | os.PathLike[str]) -> Path:
    """Write :func:`format_openvins_intrinsics` to `path`; return the path."""
    out = Path(path)
    out.write_text(format_openvins_intrinsics(cal), encoding="utf-8")
    return out
