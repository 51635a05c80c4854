"""The deterministic error model of one sensor triad (three gyros or three accelerometers).

Contents
--------
:data:`TriadKind`
    ``"gyro"`` or ``"accel"``.
:data:`PARAMETER_NAMES`
    The names of the model's parameters, in their canonical order.
:class:`TriadModel`
    Bias, scale factor and misalignment, per-axis nonlinearity (K2, K3, Koq, asymmetry), gyro
    g- and g²-sensitivity, accelerometer size-effect lever arms, and the temperature dependence
    of any of them (:class:`~imucalib.models.temperature.TemperatureDependence`).
:func:`apply_triad`
    True input → measured output (what the twin's sensors produce).
:func:`correct_triad`
    Measured output → true input (the exact inverse of :func:`apply_triad`).

Model
-----
For sensor i (row i) of the triad, with A = I + M::

    u_i = A_i · x_i
    y_i = b_i + u_i + K2_i·u_i² + K3_i·u_i³ + Koq_i·u_i|u_i| + (asym_i/2)·|u_i|
          + G_i · f + G2_i · q(f)                                        (gyro only)

x_i is the true input seen by sensor i. For a gyro x_i = ω_ib (the same for the three sensors),
f is the specific force and q(f) = (f_x², f_y², f_z², f_x f_y, f_x f_z, f_y f_z). For an
accelerometer at position r_i (row i of the lever arms) x_i = f + ω̇ × r_i + ω × (ω × r_i), the
size effect of docs/equations.md §7.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import partial
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array, check_positive
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models.temperature import TemperatureDependence, evaluate_parameter

__all__ = ["PARAMETER_NAMES", "PARAMETER_SHAPES", "TriadKind", "TriadModel", "apply_triad",
           "correct_triad"]

TriadKind = Literal["gyro", "accel"]

_SHAPES: dict[str, tuple[int, ...]] = {
    "bias": (3,), "scale_misalignment": (3, 3), "k2": (3,), "k3": (3,), "koq": (3,),
    "scale_asymmetry": (3,), "g_sensitivity": (3, 3), "g2_sensitivity": (3, 6),
    "lever_arms_b_m": (3, 3),
}
#: Parameter names of :class:`TriadModel`, in canonical order.
PARAMETER_NAMES: tuple[str, ...] = tuple(_SHAPES)
#: The shape of each parameter of :class:`TriadModel`.
PARAMETER_SHAPES: dict[str, tuple[int, ...]] = dict(_SHAPES)

_PER_AXIS_NONLINEAR = ("k2", "k3", "koq", "scale_asymmetry")
_NOT_FOR = {"accel": ("g_sensitivity", "g2_sensitivity"), "gyro": ("lever_arms_b_m",)}
_BLOCK_ROWS = 8192  # rows per block of the Newton iteration (keeps its arrays in cache)
_EYE3 = np.eye(3)
_EYE3.setflags(write=False)


@dataclass(frozen=True, eq=False)
class TriadModel:
    """Deterministic errors of one sensor triad (gyro or accelerometer), SI units.

    ``u = (I + M)·x_i`` (per-axis linear input; x_i is the true input seen by sensor i)

    ``y = b + u + K2⊙u² + K3⊙u³ + Koq⊙u|u| + (asym/2)⊙|u| + G·f + G2·q(f)``

    Parameters
    ----------
    kind : {"gyro", "accel"}
        Which triad. Units below read [rad/s] for a gyro and [m/s²] for an accelerometer.
    bias : array_like, shape (3,), or float
        b, the output at zero input. [rad/s] or [m/s²]
    scale_misalignment : array_like, shape (3, 3)
        M: diagonal = scale-factor errors, off-diagonal = misalignment and non-orthogonality of
        the sensor axes s relative to the body frame b. [–]
    k2 : array_like, shape (3,), or float
        Quadratic coefficients. [1/(rad/s)] or [1/(m/s²)]
    k3 : array_like, shape (3,), or float
        Cubic coefficients. [1/(rad/s)²] or [1/(m/s²)²]
    koq : array_like, shape (3,), or float
        Odd-quadratic coefficients (term u·|u|). [1/(rad/s)] or [1/(m/s²)]
    scale_asymmetry : array_like, shape (3,), or float
        (K+ − K−)/mean of the positive- and negative-input scale factors. [–]
    g_sensitivity : array_like, shape (3, 3)
        G, gyro only (zero for an accelerometer): output per specific force. [rad/s per m/s²]
    g2_sensitivity : array_like, shape (3, 6)
        G2, gyro only: output per product of specific-force components, columns f_x², f_y², f_z²,
        f_x f_y, f_x f_z, f_y f_z. [rad/s per (m/s²)²]
    lever_arms_b_m : array_like, shape (3, 3)
        Accelerometer only (zero for a gyro): row i is the position of accelerometer i relative to
        the IMU origin, in b. [m]
    temperature : TemperatureDependence or None
        Temperature dependence of any of the parameters above, keyed by their names; the base
        values above hold at its reference temperature (and hysteresis state 0).

    Raises
    ------
    InvalidInputError
        If an array has the wrong shape (the message names the field, the expected and the
        received shape) or is not finite, or a temperature coefficient does not match its
        parameter's shape.
    ConfigurationError
        If `kind` is unknown, an accelerometer has g-sensitivity, a gyro has lever arms, or the
        temperature dependence names an unknown parameter.

    Notes
    -----
    Correspondence to the standards (docs/equations.md §3):

    - IEEE 1293 / IEEE 836 accelerometer model equation: K0 = `bias`; scale factor
      K1 = (1 + M_ii)·K1,nominal; K2 = `k2`·g0 [g/g²], K3 = `k3`·g0² [g/g³], Koq = `koq`·g0
      [g/g²] (g0 = 9.80665 m/s²; ×10⁶ for µg/g² and µg/g³); for sensor i with its pendulous and
      output axes along axes p and o, the misalignments are δo = M_ip and δp = −M_io; the size
      effect (docs/equations.md §7) is the lever-arm term. Cross-coupling (Kip, Kio) and
      cross-axis (Kpp, …) terms are not modelled.
    - IEEE 952 / IEEE 1431 gyro model: the fixed drift D_F = `bias`; the scale-factor
      error εk [ppm] = 10⁶·M_ii (its nonlinearity and asymmetry are `k2`, `k3`, `koq` and
      `scale_asymmetry`); the misalignment couplings θ are the off-diagonal M_ij; the
      acceleration-sensitive drift D_g(a) = G·f + G2·q(f) (g-sensitivity and g²/anisoelastic
      sensitivity, IEEE 1431); D_T·ΔT and D_Ṫ·dT/dt are the polynomial and rate terms of
      `temperature` (docs/equations.md §4).

    Arrays are copied and made read-only. Instances compare with :meth:`isclose`, not ``==``.
    """

    kind: TriadKind
    bias: NDArray[np.float64] = field(default_factory=partial(np.zeros, 3))
    scale_misalignment: NDArray[np.float64] = field(default_factory=partial(np.zeros, (3, 3)))
    k2: NDArray[np.float64] = field(default_factory=partial(np.zeros, 3))
    k3: NDArray[np.float64] = field(default_factory=partial(np.zeros, 3))
    koq: NDArray[np.float64] = field(default_factory=partial(np.zeros, 3))
    scale_asymmetry: NDArray[np.float64] = field(default_factory=partial(np.zeros, 3))
    g_sensitivity: NDArray[np.float64] = field(default_factory=partial(np.zeros, (3, 3)))
    g2_sensitivity: NDArray[np.float64] = field(default_factory=partial(np.zeros, (3, 6)))
    lever_arms_b_m: NDArray[np.float64] = field(default_factory=partial(np.zeros, (3, 3)))
    temperature: TemperatureDependence | None = None

    def __post_init__(self) -> None:
        if self.kind not in ("gyro", "accel"):
            raise ConfigurationError(f"`kind` must be 'gyro' or 'accel'; got {self.kind!r}")
        for name in PARAMETER_NAMES:
            shape = _SHAPES[name]
            arr = as_array(getattr(self, name), name)
            if arr.ndim == 0 and shape == (3,):
                arr = np.full(3, float(arr))  # a scalar applies to the three axes
            if arr.shape != shape:
                raise InvalidInputError(f"`{name}` must have shape {shape}; got {arr.shape}")
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        dep = self.temperature
        if dep is not None:
            if not isinstance(dep, TemperatureDependence):
                raise InvalidInputError(
                    f"`temperature` must be a TemperatureDependence or None; "
                    f"got {type(dep).__name__}"
                )
            unknown = sorted(set(dep.parameter_names) - set(PARAMETER_NAMES))
            if unknown:
                raise ConfigurationError(
                    f"`temperature` names unknown parameter(s) {unknown}; expected names from "
                    f"{list(PARAMETER_NAMES)}"
                )
            for name, coeffs in dep.coefficients.items():
                if coeffs.shape[1:] != _SHAPES[name]:
                    raise InvalidInputError(
                        f"`temperature.coefficients[{name!r}]` must have shape "
                        f"(K, {', '.join(map(str, _SHAPES[name]))}); got {coeffs.shape}"
                    )
            for label, arrays in (("rate_coefficients", dep.rate_coefficients),
                                  ("hysteresis", dep.hysteresis)):
                for name, d in arrays.items():
                    if d.shape != _SHAPES[name]:
                        raise InvalidInputError(
                            f"`temperature.{label}[{name!r}]` must have shape "
                            f"{_SHAPES[name]}; got {d.shape}"
                        )
        for name in _NOT_FOR[self.kind]:
            if self._active(name):
                what = "an accelerometer" if self.kind == "accel" else "a gyro"
                raise ConfigurationError(
                    f"`{name}` must be zero for {what} triad (kind={self.kind!r}); got max |value| "
                    f"{float(np.max(np.abs(getattr(self, name)))):g} or a temperature dependence"
                )

    def _active(self, name: str) -> bool:
        """Return True if parameter `name` is non-zero at some temperature."""
        if np.any(getattr(self, name) != 0.0):
            return True
        return self.temperature is not None and self.temperature.depends_on(name)

    @classmethod
    def ideal(cls, kind: TriadKind) -> TriadModel:
        """Return an error-free triad of the given kind (all parameters zero)."""
        return cls(kind=kind)

    def replace(self, **changes: Any) -> TriadModel:
        """Return a copy with some fields changed (validated like the constructor).

        Raises
        ------
        InvalidInputError
            If a keyword is not a field of :class:`TriadModel`.
        """
        fields = {f.name for f in dataclasses.fields(self)}
        unknown = sorted(set(changes) - fields)
        if unknown:
            raise InvalidInputError(
                f"unknown TriadModel field(s) {unknown}; expected names from {sorted(fields)}"
            )
        return dataclasses.replace(self, **changes)

    def isclose(self, other: TriadModel, *, atol: float) -> bool:
        """Return True if `other` is the same kind with every parameter within `atol`.

        `atol` is absolute and applies to every entry in its own SI unit (and to the temperature
        coefficients); None temperature dependence equals an empty one.
        """
        if not isinstance(other, TriadModel) or self.kind != other.kind:
            return False
        for name in PARAMETER_NAMES:
            if not np.allclose(getattr(self, name), getattr(other, name), rtol=0.0, atol=atol):
                return False
        mine = self.temperature or TemperatureDependence()
        theirs = other.temperature or TemperatureDependence()
        if self.temperature is None or other.temperature is None:
            # without coefficients the reference temperature is irrelevant
            mine = dataclasses.replace(
                mine, reference_temperature_degc=theirs.reference_temperature_degc
            )
        return mine.isclose(theirs, atol=atol)

    def is_linear(self) -> bool:
        """Return True if the model has no K2, K3, Koq, asymmetry or g² terms (at any T)."""
        return not any(self._active(n) for n in (*_PER_AXIS_NONLINEAR, "g2_sensitivity"))

    def to_dict(self) -> dict[str, Any]:
        """Return a JSON-able description; :meth:`from_dict` rebuilds it exactly."""
        out: dict[str, Any] = {"kind": self.kind}
        for name in PARAMETER_NAMES:
            out[name] = getattr(self, name).tolist()
        out["temperature"] = None if self.temperature is None else self.temperature.to_dict()
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> TriadModel:
        """Rebuild a model written by :meth:`to_dict`; missing parameters are zero.

        Raises
        ------
        InvalidInputError
            If `data` is not a mapping, lacks ``kind`` or has unknown keys.
        """
        if not isinstance(data, Mapping) or "kind" not in data:
            raise InvalidInputError("`data` must be a mapping with at least the key 'kind'")
        known = {"kind", "temperature", *PARAMETER_NAMES}
        unknown = sorted(set(data) - known)
        if unknown:
            raise InvalidInputError(
                f"unknown key(s) {unknown} in a TriadModel description; expected {sorted(known)}"
            )
        params = {name: data[name] for name in PARAMETER_NAMES if name in data}
        temp = data.get("temperature")
        return cls(
            kind=data["kind"],
            temperature=None if temp is None else TemperatureDependence.from_dict(temp),
            **params,
        )


# --------------------------------------------------------------------------------------------
# apply / correct


@dataclass(frozen=True)
class _Resolved:
    """Parameters at the samples' temperatures: constant (base shape) or per sample (n, …)."""

    p: dict[str, NDArray[np.float64]]
    _active: dict[str, bool] = field(default_factory=dict)

    def active(self, name: str) -> bool:
        if name not in self._active:
            self._active[name] = bool(np.any(self.p[name] != 0.0))
        return self._active[name]


def _samples(value: ArrayLike, name: str, n: int | None = None) -> tuple[NDArray[np.float64], bool]:
    """Return finite float64 samples of shape (n, 3) (no copy: the caller must not write to it)."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"`{name}` must be numeric; got {type(value).__name__}") from exc
    single = arr.shape == (3,)
    if single:
        arr = arr.reshape(1, 3)
    if arr.ndim != 2 or arr.shape[1] != 3 or (n is not None and arr.shape[0] != n):
        want = "(n, 3)" if n is None else f"({n}, 3) like the input"
        raise InvalidInputError(f"`{name}` must have shape {want} or (3,); got {arr.shape}")
    if not np.isfinite(arr).all():
        bad = int(arr.size - np.count_nonzero(np.isfinite(arr)))
        raise InvalidInputError(f"`{name}` must be finite; got {bad} NaN or infinite value(s)")
    return arr, single


def _temperature_arg(value: ArrayLike, name: str, n: int) -> NDArray[np.float64]:
    arr = as_array(value, name)
    if arr.ndim > 1 or (arr.ndim == 1 and arr.size not in (1, n)):
        raise InvalidInputError(
            f"`{name}` must be a scalar or have shape ({n},), one per sample; got {arr.shape}"
        )
    return arr.reshape(-1)


def _resolve(
    model: TriadModel,
    n: int,
    temperature_degc: ArrayLike | None,
    temperature_rate_degc_ps: ArrayLike | None,
    hysteresis_state: ArrayLike | None = None,
) -> _Resolved:
    dep = model.temperature
    p = {name: getattr(model, name) for name in PARAMETER_NAMES}
    if dep is None:
        return _Resolved(p)
    thermal = sorted(set(dep.coefficients) | set(dep.rate_coefficients))
    hyst = list(dep.hysteresis) if hysteresis_state is not None else []
    if not (thermal or hyst):
        return _Resolved(p)
    temp = rate = state = np.zeros(1)
    if thermal:
        if temperature_degc is None:
            raise InvalidInputError(
                f"`temperature_degc` is required: the {model.kind} model's "
                f"{', '.join(thermal)} depend(s) on temperature"
            )
        temp = _temperature_arg(temperature_degc, "temperature_degc", n)
        if temperature_rate_degc_ps is not None:
            rate = _temperature_arg(temperature_rate_degc_ps, "temperature_rate_degc_ps", n)
    if hyst and hysteresis_state is not None:
        state = _temperature_arg(hysteresis_state, "hysteresis_state", n)
    constant = temp.size == 1 and rate.size == 1 and state.size == 1
    if not constant:
        temp = np.broadcast_to(temp, (n,))
        rate = np.broadcast_to(rate, (n,))
        state = np.broadcast_to(state, (n,))
    for name in sorted(set(thermal) | set(hyst)):
        value = evaluate_parameter(p[name], name, dep, temp, rate,
                                   state if name in hyst else None)
        p[name] = value[0] if constant else value
    return _Resolved(p)


def _matvec(mat: NDArray[np.float64], x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Row-wise mat @ x for x (n, k): mat is (m, k) constant or (n, m, k) per sample."""
    if mat.ndim == 2:
        return x @ mat.T
    return np.einsum("nij,nj->ni", mat, x)


def _g_terms(r: _Resolved, specific_force_b_mps2: ArrayLike | None,
             n: int) -> NDArray[np.float64] | None:
    """Gyro G·f + G2·q(f), or None when both are zero."""
    use_g, use_g2 = r.active("g_sensitivity"), r.active("g2_sensitivity")
    if not (use_g or use_g2):
        return None
    if specific_force_b_mps2 is None:
        raise InvalidInputError(
            "`specific_force_b_mps2` is required: the gyro model has non-zero "
            "g_sensitivity or g2_sensitivity"
        )
    f, _ = _samples(specific_force_b_mps2, "specific_force_b_mps2", n)
    out = _matvec(r.p["g_sensitivity"], f) if use_g else np.zeros_like(f)
    if use_g2:
        fx, fy, fz = f[:, 0], f[:, 1], f[:, 2]
        q = np.stack([fx * fx, fy * fy, fz * fz, fx * fy, fx * fz, fy * fz], axis=1)
        out += _matvec(r.p["g2_sensitivity"], q)
    return out


def _size_effect(r: _Resolved, A: NDArray[np.float64], rate_b_rps: ArrayLike | None,
                 angular_accel_b_rps2: ArrayLike | None, n: int) -> NDArray[np.float64] | None:
    """Accelerometer size effect in u: s_i = A_i·(ω̇ × r_i + ω × (ω × r_i)), or None if r = 0."""
    if not r.active("lever_arms_b_m"):
        return None
    if rate_b_rps is None or angular_accel_b_rps2 is None:
        name = "rate_b_rps" if rate_b_rps is None else "angular_accel_b_rps2"
        raise InvalidInputError(
            f"`{name}` is required: the accelerometer model has non-zero lever arms (size effect)"
        )
    w, _ = _samples(rate_b_rps, "rate_b_rps", n)
    alpha, _ = _samples(angular_accel_b_rps2, "angular_accel_b_rps2", n)
    R = r.p["lever_arms_b_m"]
    # A_i·(α × r_i) = α·(r_i × A_i);  A_i·(ω × (ω × r_i)) = (A_i·ω)(r_i·ω) − (A_i·r_i)|ω|²
    if A.ndim == 3 and R.ndim == 2:  # per-sample A: rows α × r_i = αᵀ[r_i]ₓ in one product
        skew = np.zeros((3, 3, 3))  # skew[k, i, j] = ([r_i]ₓ)_kj
        skew[2, :, 1], skew[1, :, 2] = R[:, 0], -R[:, 0]
        skew[0, :, 2], skew[2, :, 0] = R[:, 1], -R[:, 1]
        skew[1, :, 0], skew[0, :, 1] = R[:, 2], -R[:, 2]
        cross_alpha = (alpha @ skew.reshape(3, 9)).reshape(n, 3, 3)
        s = np.einsum("nij,nij->ni", A, cross_alpha)
    else:
        s = _matvec(np.cross(R, A), alpha)
    s += _matvec(A, w) * _matvec(R, w)
    s -= np.sum(A * R, axis=-1) * np.einsum("ni,ni->n", w, w)[:, None]
    return s


def _h(u: NDArray[np.float64], r: _Resolved) -> NDArray[np.float64]:
    """Per-axis nonlinearity h(u) = u + K2u² + K3u³ + Koq·u|u| + (asym/2)|u|, in place on u."""
    if not any(r.active(n) for n in _PER_AXIS_NONLINEAR):
        return u
    au = np.abs(u)
    terms = []
    if r.active("k2") or r.active("k3"):
        terms.append(u * u * (r.p["k2"] + r.p["k3"] * u))
    if r.active("koq"):
        terms.append(r.p["koq"] * u * au)
    if r.active("scale_asymmetry"):
        terms.append(0.5 * r.p["scale_asymmetry"] * au)
    for term in terms:  # every term is computed from the unmodified u first
        u += term
    return u


def _h_inverse(y: NDArray[np.float64], r: _Resolved, tol: float,
               max_iter: int) -> NDArray[np.float64]:
    """Solve h(u) = y per axis (blocks of rows, so that the iteration runs in cache)."""
    if not any(r.active(n) for n in _PER_AXIS_NONLINEAR):
        return y
    k2, k3, koq = r.p["k2"], r.p["k3"], r.p["koq"]
    c = 0.5 * r.p["scale_asymmetry"]
    if np.any(np.abs(c) >= 1.0):
        raise InvalidInputError(
            "cannot invert the nonlinear model: |scale_asymmetry| ≥ 2 makes h non-monotonic at 0"
        )
    out = np.empty_like(y)
    for start in range(0, y.shape[0], _BLOCK_ROWS):
        rows = slice(start, start + _BLOCK_ROWS)
        k2b, k3b, koqb, cb = (p[rows] if p.ndim == 2 else p for p in (k2, k3, koq, c))
        out[rows] = _h_inverse_block(y[rows], k2b, k3b, koqb, cb, tol, max_iter)
    return out


def _h_inverse_block(y: NDArray[np.float64], k2: NDArray[np.float64], k3: NDArray[np.float64],
                     koq: NDArray[np.float64], c: NDArray[np.float64], tol: float,
                     max_iter: int) -> NDArray[np.float64]:
    # h is increasing with h(0) = 0, so sign(u) = sign(y). With v = |u| ≥ 0 and t = |y|:
    # g(v) = a1 v + a2 v² + a3 v³ = t, a1 = 1 ± asym/2, a2 = Koq ± K2, a3 = K3 (±: sign of y).
    sgn = np.copysign(1.0, y)
    t = np.abs(y)
    a1 = 1.0 + c * sgn
    a2 = koq + k2 * sgn
    a3 = np.broadcast_to(k3, y.shape)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # start at the root of the quadratic part (the exact root when K3 = 0)
        v = 2.0 * t / (a1 + np.sqrt(np.maximum(a1 * a1 + 4.0 * a2 * t, 0.0)))
        conv = np.zeros(y.shape, dtype=bool)
        for _ in range(max_iter):  # plain Newton
            q = a3 * v
            dg = (3.0 * q + 2.0 * a2) * v + a1
            step = (((q + a2) * v + a1) * v - t) / dg
            v = v - step
            # next error ≈ |g''/2g'|·step² (quadratic convergence): stop when below tol·v
            conv = 10.0 * np.abs(a2 + 3.0 * a3 * v) * step * step <= tol * v * dg
            if conv.all() or not (np.all(dg > 0.0) and np.all(np.isfinite(v))):
                break
        pending = ~conv
        if pending.any():  # Newton misbehaved for these: bracketed Newton with bisection
            v[pending] = _bracketed_newton(
                a1[pending], a2[pending], a3[pending], t[pending], tol, max_iter
            )
        # accept a root only on the increasing part: g' > 0 on [0, v] (g' is quadratic in v)
        vmax = float(np.max(v, initial=0.0))
        bound = (np.min(a1, initial=np.inf) - 2.0 * np.max(np.abs(a2), initial=0.0) * vmax
                 - 3.0 * np.max(np.abs(a3), initial=0.0) * vmax**2)
        if not (bound > 0.0):
            slope = np.minimum(a1, (3.0 * a3 * v + 2.0 * a2) * v + a1)
            vertex = np.where(a3 != 0.0, -a2 / (3.0 * a3), -1.0)
            inside = (vertex > 0.0) & (vertex < v)
            slope = np.where(inside, np.minimum(slope, a1 - a2 * a2 / (3.0 * a3)), slope)
            failed = ~(slope > 0.0)  # also catches NaN (no convergence)
            if np.any(failed):
                raise InvalidInputError(
                    f"cannot invert the nonlinear scale-factor model h(u) for "
                    f"{int(np.count_nonzero(failed))} value(s) (largest |measured - bias| "
                    f"{float(np.max(t[failed])):g}): outside the monotonic range of h, or no "
                    f"convergence within max_iter={max_iter} to tol={tol:g}"
                )
    out: NDArray[np.float64] = sgn * v
    return out


def _bracketed_newton(a1: NDArray[np.float64], a2: NDArray[np.float64], a3: NDArray[np.float64],
                      t: NDArray[np.float64], tol: float, max_iter: int) -> NDArray[np.float64]:
    """Solve a1 v + a2 v² + a3 v³ = t for v ≥ 0, Newton safeguarded by a bracket; NaN if not."""
    v = t / a1
    lo = np.zeros_like(v)
    hi = np.full_like(v, np.inf)
    for _ in range(max_iter):
        g = ((a3 * v + a2) * v + a1) * v - t
        dg = (3.0 * a3 * v + 2.0 * a2) * v + a1
        below = g < 0.0
        lo = np.where(below, v, lo)
        hi = np.where(below, hi, v)
        v_new = v - g / dg
        bad = ~(dg > 0.0) | (v_new < lo) | (v_new > hi) | ~np.isfinite(v_new)
        # bisect inside the bracket, or expand it while it is unbounded above
        v_new = np.where(bad, np.where(np.isfinite(hi), 0.5 * (lo + hi), 2.0 * v + t), v_new)
        done = np.abs(v_new - v) <= tol * v_new
        v = v_new
        if np.all(done):
            return v
    return np.where(done, v, np.nan)


def _solve(A: NDArray[np.float64], u: NDArray[np.float64]) -> NDArray[np.float64]:
    try:
        if A.ndim == 2:
            # I + M is close to I, so an explicit inverse is as accurate as solve and much faster
            x: NDArray[np.float64] = u @ np.linalg.inv(A).T
        else:
            x = np.asarray(np.linalg.solve(A, u[..., None])[..., 0], dtype=np.float64)
    except np.linalg.LinAlgError as exc:
        raise InvalidInputError("cannot correct: (I + scale_misalignment) is singular") from exc
    return x


def apply_triad(
    model: TriadModel,
    input_b: ArrayLike,
    *,
    specific_force_b_mps2: ArrayLike | None = None,
    rate_b_rps: ArrayLike | None = None,
    angular_accel_b_rps2: ArrayLike | None = None,
    temperature_degc: ArrayLike | None = None,
    temperature_rate_degc_ps: ArrayLike | None = None,
    hysteresis_state: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Pass the true input through the triad's error model (true → measured).

    ``y = b + h((I + M)·x_i) + G·f + G2·q(f)`` with h the per-axis nonlinearity (see
    :class:`TriadModel`).

    Parameters
    ----------
    model : TriadModel
        The triad's errors.
    input_b : array_like, shape (n, 3) or (3,)
        Gyro: true inertial rate ω_ib in b [rad/s]. Accelerometer: true specific force at the IMU
        origin in b [m/s²].
    specific_force_b_mps2 : array_like, shape (n, 3) or (3,), optional
        Gyro only: specific force in b, feeding G and G2; required when either is non-zero and
        ignored otherwise (and for an accelerometer). [m/s²]
    rate_b_rps : array_like, shape (n, 3) or (3,), optional
        Accelerometer only: angular rate ω in b; required when a lever arm is non-zero. [rad/s]
    angular_accel_b_rps2 : array_like, shape (n, 3) or (3,), optional
        Accelerometer only: angular acceleration ω̇ in b; required when a lever arm is non-zero.
        [rad/s²]
    temperature_degc : float or array_like, shape (n,), optional
        Sensor temperature; required when the model depends on temperature. [°C]
    temperature_rate_degc_ps : float or array_like, shape (n,), optional
        Temperature rate dT/dt; 0 when omitted. [°C/s]
    hysteresis_state : float or array_like, shape (n,), optional
        Thermal hysteresis state s in [−1, 1]
        (:func:`~imucalib.models.temperature.hysteresis_state`); the hysteresis terms h·s of
        the temperature dependence are added only when given (omitted means s = 0). [–]

    Returns
    -------
    numpy.ndarray, shape (n, 3) or (3,)
        Measured output in the sensor axes s, shaped like `input_b`. [rad/s] or [m/s²]

    Raises
    ------
    InvalidInputError
        If an array has the wrong shape or is not finite, or an argument the model needs is
        missing (the message names it).

    Notes
    -----
    The accelerometer i at lever arm r_i senses x_i = f + ω̇ × r_i + ω × (ω × r_i)
    (docs/equations.md §7). Parameters that depend on temperature are evaluated per sample
    (:func:`~imucalib.models.temperature.evaluate_parameter`, docs/equations.md §4).
    """
    x, single = _samples(input_b, "input_b")
    n = x.shape[0]
    r = _resolve(model, n, temperature_degc, temperature_rate_degc_ps, hysteresis_state)
    A = r.p["scale_misalignment"] + _EYE3
    u = _matvec(A, x)
    if model.kind == "accel":
        s = _size_effect(r, A, rate_b_rps, angular_accel_b_rps2, n)
        if s is not None:
            u += s
    y = _h(u, r)
    y += r.p["bias"]
    if model.kind == "gyro":
        g = _g_terms(r, specific_force_b_mps2, n)
        if g is not None:
            y += g
    return y[0] if single else y


def correct_triad(
    model: TriadModel,
    measured_s: ArrayLike,
    *,
    specific_force_b_mps2: ArrayLike | None = None,
    rate_b_rps: ArrayLike | None = None,
    angular_accel_b_rps2: ArrayLike | None = None,
    temperature_degc: ArrayLike | None = None,
    temperature_rate_degc_ps: ArrayLike | None = None,
    hysteresis_state: ArrayLike | None = None,
    tol: float = 1e-13,
    max_iter: int = 50,
) -> NDArray[np.float64]:
    """Recover the true input from the measured output (measured → true), inverse of apply.

    ``x = (I + M)⁻¹·(h⁻¹(y − b − G·f − G2·q(f)) − s)`` with s the accelerometer size effect.

    Parameters
    ----------
    model : TriadModel
        The triad's errors.
    measured_s : array_like, shape (n, 3) or (3,)
        Measured output in the sensor axes s. [rad/s] or [m/s²]
    specific_force_b_mps2, rate_b_rps, angular_accel_b_rps2 : array_like, optional
        As in :func:`apply_triad`: the true (or best known) specific force [m/s²] for the gyro
        g-sensitivity, angular rate [rad/s] and angular acceleration [rad/s²] for the
        accelerometer size effect.
    temperature_degc : float or array_like, shape (n,), optional
        Sensor temperature; required when the model depends on temperature. [°C]
    temperature_rate_degc_ps : float or array_like, shape (n,), optional
        Temperature rate dT/dt; 0 when omitted. [°C/s]
    hysteresis_state : float or array_like, shape (n,), optional
        Thermal hysteresis state s in [−1, 1]
        (:func:`~imucalib.models.temperature.hysteresis_state`); the hysteresis terms h·s of
        the temperature dependence are added only when given (omitted means s = 0). [–]
    tol : float
        Relative tolerance of the Newton iteration that inverts h. [–]
    max_iter : int
        Maximum number of Newton iterations.

    Returns
    -------
    numpy.ndarray, shape (n, 3) or (3,)
        Gyro: inertial rate in b [rad/s]; accelerometer: specific force at the IMU origin in b
        [m/s²].

    Raises
    ------
    InvalidInputError
        As :func:`apply_triad`; also if h cannot be inverted (a value outside the monotonic range
        of h, or no convergence) or I + M is singular.

    Notes
    -----
    The linear part is exact: bias, g-sensitivity and the size effect are subtracted and I + M is
    solved. The size effect enters u_i as s_i = A_i·(ω̇ × r_i + ω × (ω × r_i)) with A_i the row i
    of I + M, so it is removed *after* inverting h and *before* solving A. The per-axis h is
    inverted on the branch sign(u) = sign(y − …) by Newton's method, started from the exact root
    of the quadratic part and safeguarded by bisection; the root is accepted only where h is
    increasing between 0 and it.
    """
    tol = check_positive(tol, "tol")
    if not isinstance(max_iter, int | np.integer) or max_iter < 1:
        raise InvalidInputError(f"`max_iter` must be an integer ≥ 1; got {max_iter!r}")
    y, single = _samples(measured_s, "measured_s")
    n = y.shape[0]
    r = _resolve(model, n, temperature_degc, temperature_rate_degc_ps, hysteresis_state)
    rest = y - r.p["bias"]
    if model.kind == "gyro":
        g = _g_terms(r, specific_force_b_mps2, n)
        if g is not None:
            rest -= g
    u = _h_inverse(rest, r, tol, max_iter)
    A = r.p["scale_misalignment"] + _EYE3
    if model.kind == "accel":
        s = _size_effect(r, A, rate_b_rps, angular_accel_b_rps2, n)
        if s is not None:
            u = u - s
    x = _solve(A, u)
    return x[0] if single else x
