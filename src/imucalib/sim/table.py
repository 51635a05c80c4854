"""Rate tables with one or two axes: specification, motion profiles, kinematics and feedback.

Contents
--------
:class:`AxisSpec`
    One axis: direction, limits, servo dynamics and imperfections; presets :meth:`AxisSpec.ideal`,
    :meth:`AxisSpec.lab_grade`, :meth:`AxisSpec.high_grade`.
:class:`RateTableSpec`
    The axes, outer first; :meth:`~RateTableSpec.single_axis`,
    :meth:`~RateTableSpec.dual_axis_pitch_roll`, :meth:`~RateTableSpec.fixed`.
:class:`TableFeedback`
    What the controller reports (the true motion is a
    :class:`~imucalib.sim.kinematics.PlatformMotion`).
:func:`compute_platform_motion`
    Pure function: axis angles, rates and accelerations → platform attitude and angular motion.
:class:`SimRateTable`
    The stateful twin of a table controller in virtual time (position, rate, stop, off commands).

Geometry
--------
Axis i turns the frame of axis i+1 (the outer gimbal carries the inner one; the innermost axis
carries the platform p). ``axis_vector`` is the nominal direction of the axis in its parent frame
(the base t for the outer axis; the outer gimbal frame, which equals t at home, for the inner).
With every angle zero, p coincides with t (up to the imperfections), and::

    rot_tp = J_1(θ_1) · J_2(θ_2) · …,   J_i(θ) = R_{u1}(δ_i) · R_{w_i(θ)} · R_{n_i}(θ)

where R_v(α) is a right-handed rotation by α about the unit vector v, R_w the rotation with
rotation vector w, and

- R_{u1}(δ_i) is the fixed ``non_orthogonality_rad`` δ_i, a tilt about u1 ⟂ n_i (``tilt_axis``;
  by default unit(n_i × e_j), e_j the base vector least aligned with n_i) of the axis *and*
  everything it carries, as for a bearing mounted askew: the actual axis is k_i = R_{u1}(δ_i)·n_i
  and the child frame at angle 0 is tilted by δ_i. The presets tilt a vertical axis z_t towards
  x_t (a level error: the platform plane stays ⟂ the axis), the outer pitch axis −y_t about x_t
  (out of level) and the inner roll axis x about z, in the plane of the two axes (the angle
  between pitch and roll becomes 90° + δ);
- w_i(θ) = W_i·(cos 2θ·u1 + sin 2θ·u2), u2 = n_i × u1, is the ``wobble_rad`` W_i: the platform is
  tilted by W_i about an axis ⟂ the axis that turns at twice the axis angle in the parent frame,
  i.e. once per revolution relative to the rotor (a tilt turning once per revolution in the
  parent frame would be a constant tilt of the platform, which belongs to the fixture's
  ``rot_pm``). Equivalently R_w(θ)·R_n(θ) = R_n(2θ)·R_{u1}(W_i)·R_n(−θ), as it is evaluated.

The angular velocity and acceleration follow from this chain exactly (no small-angle
approximation): with P_j the product of the first j elementary rotations (axes κ_j, angles q_j),
ω = Σ_j P_{j−1}κ_j q̇_j and α = Σ_j [P_{j−1}κ_j q̈_j + ω_{<j} × P_{j−1}κ_j q̇_j] in t.

Motion model
------------
A command sets a *reference* profile r(t) that respects the limits: a trapezoidal velocity move
(accelerate, cruise, decelerate, hold) for a position command; a ramp then a constant rate for a
rate command. The axis follows it through the type-2 servo loop of :mod:`imucalib.sim._servo`
(natural frequency ``settling_frequency_hz``, damping ``settling_damping``), so angle, rate and
acceleration are continuous, each move ends with a damped second-order settling transient, and
a constant-rate command is tracked without steady error. The reference acceleration is
``max_accel_rps2 / ‖g‖₁`` (‖g‖₁ the L1 norm of the loop's impulse response: 1.27 for ζ = 1,
1.37 for 0.8, 1.55 for 0.6), so the true acceleration never exceeds ``max_accel_rps2``; the
cruise rate of a position move leaves room for the servo's rate overshoot, so position moves
stay within ``max_rate_rps`` too. A rate command at exactly ``max_rate_rps`` may overshoot it
transiently by at most ``rate_overshoot_rps`` = ‖k‖₁·a_ref (‖k‖₁ ≈ 0.86/ω for ζ = 0.8; 0.5 % of
the limit for the high-grade preset, 1.3 % for the lab-grade one). At constant commanded rate
ω_c the axis has a rate ripple ω_c·ρ·sin(2π f_r τ) (``rate_ripple_fraction`` ρ,
``rate_ripple_hz`` f_r, τ from the start of the constant-rate phase), outside the servo loop.
Commands start at t = 0 s.

Feedback model
--------------
measured angle = quantize(θ + ε(θ) + σ_p·n, resolution), measured rate = θ̇·(1 + ε′(θ)), with
ε(θ) = E·(sin θ + cos 2θ) the once- and twice-per-revolution encoder error (E =
``encoder_error_rad`` is its RMS over a revolution, peak ≈ 1.76·E), σ_p = ``position_noise_rad``
and n standard normal. Over whole revolutions ε′ averages to zero, so the measured mean rate is
unbiased. Angles are reported unwrapped (multi-turn), in radians.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from imucalib import units
from imucalib._checks import as_array, check_finite_scalar, check_nonnegative, check_positive
from imucalib.conventions import TABLE_AXIS_VECTORS
from imucalib.errors import ConfigurationError, InvalidInputError, LimitExceededError
from imucalib.sim import _servo
from imucalib.sim._rotation import evaluate_chain
from imucalib.sim.kinematics import PlatformMotion

__all__ = [
    "AxisSpec",
    "PlatformMotion",  # re-exported from imucalib.sim.kinematics
    "RateTableSpec",
    "SimRateTable",
    "TableFeedback",
    "TableGrade",
    "compute_platform_motion",
]

TableGrade = Literal["ideal", "lab", "high"]
AxisMode = Literal["off", "position", "rate", "stop"]

_F64 = NDArray[np.float64]
_BLOCK = 1 << 16  # samples per block in the vectorised evaluations (keeps temporaries small)


def _default_tilt_axis(n: _F64) -> _F64:
    """Return u1 = unit(n × e_j), e_j the base vector least aligned with n."""
    e = np.zeros(3)
    e[int(np.argmin(np.abs(n)))] = 1.0
    u1 = np.cross(n, e)
    return np.asarray(u1 / np.linalg.norm(u1), dtype=np.float64)


@dataclass(frozen=True, eq=False)
class AxisSpec:
    """One table axis.

    Parameters
    ----------
    name : str
        Axis name (``"pitch"``, ``"roll"``, ``"azimuth"`` …), unique on a table.
    axis_vector : array_like, shape (3,)
        Nominal unit direction of the axis in its parent frame (see the module docstring).
    max_rate_rps, max_accel_rps2 : float
        Rate and acceleration limits. [rad/s], [rad/s²]
    settling_frequency_hz : float
        Natural frequency of the servo loop; ``math.inf`` tracks the reference exactly. [Hz]
    settling_damping : float
        Damping ratio ζ of the servo loop, > 0.
    encoder_error_rad : float
        RMS E of the encoder error ε(θ) = E·(sin θ + cos 2θ). [rad]
    encoder_resolution_rad : float
        Quantization step of the reported angle (0: none). [rad]
    rate_ripple_fraction : float
        Relative amplitude ρ of the rate ripple at constant rate. [–]
    rate_ripple_hz : float
        Ripple frequency. [Hz]
    wobble_rad : float
        Amplitude of the axis wobble (module docstring). [rad]
    non_orthogonality_rad : float
        Fixed tilt of the axis (and what it carries) from its nominal direction (module
        docstring); a level error for an outer axis. [rad]
    position_noise_rad : float
        Standard deviation of white noise on the reported angle. [rad]
    angle_limits_rad : tuple of float or None
        (min, max) travel of a limited axis; None for unlimited rotation. [rad]
    tilt_axis : array_like, shape (3,), or None
        Unit vector ⟂ `axis_vector` (parent frame) about which `non_orthogonality_rad` tilts
        the axis and about which the wobble tilts the platform at angle 0; None: the default of
        the module docstring.
    """

    name: str
    axis_vector: _F64
    max_rate_rps: float = 1000.0 * units.DEG
    max_accel_rps2: float = 500.0 * units.DEG
    settling_frequency_hz: float = 10.0
    settling_damping: float = 0.8
    encoder_error_rad: float = 0.0
    encoder_resolution_rad: float = 0.0
    rate_ripple_fraction: float = 0.0
    rate_ripple_hz: float = 1.0
    wobble_rad: float = 0.0
    non_orthogonality_rad: float = 0.0
    position_noise_rad: float = 0.0
    angle_limits_rad: tuple[float, float] | None = None
    tilt_axis: _F64 | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ConfigurationError(
                f"`name` of an axis must be a non-empty string; got {self.name!r}"
            )
        vec = as_array(self.axis_vector, f"axis_vector of axis {self.name!r}", shape=(3,))
        norm = float(np.linalg.norm(vec))
        if abs(norm - 1.0) > 1e-9:
            raise ConfigurationError(
                f"`axis_vector` of axis {self.name!r} must be a unit vector; got norm {norm:.12g}"
            )
        vec = vec / norm
        object.__setattr__(self, "axis_vector", vec)
        check_positive(self.max_rate_rps, "max_rate_rps")
        check_positive(self.max_accel_rps2, "max_accel_rps2")
        f = float(self.settling_frequency_hz)
        if math.isnan(f) or f <= 0.0:
            raise ConfigurationError(f"`settling_frequency_hz` must be > 0 (or inf); got {f}")
        check_positive(self.settling_damping, "settling_damping")
        for field_name in ("encoder_error_rad", "encoder_resolution_rad", "rate_ripple_fraction",
                           "rate_ripple_hz", "wobble_rad", "position_noise_rad"):
            check_nonnegative(getattr(self, field_name), field_name)
        check_finite_scalar(self.non_orthogonality_rad, "non_orthogonality_rad")
        if self.rate_ripple_fraction > 0 and self.rate_ripple_hz <= 0:
            raise ConfigurationError("`rate_ripple_hz` must be > 0 when `rate_ripple_fraction` > 0")
        if self.angle_limits_rad is not None:
            lo, hi = (check_finite_scalar(v, "angle_limits_rad") for v in self.angle_limits_rad)
            if not lo < hi:
                raise ConfigurationError(f"`angle_limits_rad` must be (min, max); got {(lo, hi)}")
        if self.tilt_axis is not None:
            u = as_array(self.tilt_axis, f"tilt_axis of axis {self.name!r}", shape=(3,))
            if abs(np.linalg.norm(u) - 1.0) > 1e-9 or abs(float(u @ vec)) > 1e-9:
                raise ConfigurationError(
                    f"`tilt_axis` of axis {self.name!r} must be a unit vector ⟂ `axis_vector`; "
                    f"got {u.tolist()}"
                )
            object.__setattr__(self, "tilt_axis", u / np.linalg.norm(u))

    # --- presets ------------------------------------------------------------------------------
    @classmethod
    def ideal(cls, name: str, axis_vector: ArrayLike, **overrides: Any) -> AxisSpec:
        """Build an axis without imperfections (servo dynamics kept: 10 Hz, ζ = 0.8)."""
        return dataclasses.replace(cls(name, np.asarray(axis_vector, dtype=float)), **overrides)

    @classmethod
    def high_grade(cls, name: str, axis_vector: ArrayLike, **overrides: Any) -> AxisSpec:
        """Build a navigation-test-grade axis (docs/twin.md, "Table grades").

        1″ encoder RMS, 0.05″ resolution, 0.1″ noise, 2″ non-orthogonality, 1″ wobble, 1 ppm
        rate ripple at 1 Hz, 10 Hz / ζ = 0.8 servo, 1000 °/s and 500 °/s² limits.
        """
        return cls._preset(name, axis_vector, overrides, encoder_error_rad=1.0 * units.ARCSEC,
                           encoder_resolution_rad=0.05 * units.ARCSEC,
                           position_noise_rad=0.1 * units.ARCSEC, wobble_rad=1.0 * units.ARCSEC,
                           non_orthogonality_rad=2.0 * units.ARCSEC,
                           rate_ripple_fraction=1e-6, rate_ripple_hz=1.0,
                           settling_frequency_hz=10.0, settling_damping=0.8)

    @classmethod
    def lab_grade(cls, name: str, axis_vector: ArrayLike, **overrides: Any) -> AxisSpec:
        """Build a lab/MEMS-grade axis (docs/twin.md, "Table grades").

        15″ encoder RMS, 1″ resolution, 1″ noise, 20″ non-orthogonality, 10″ wobble, 100 ppm
        rate ripple at 2 Hz, 5 Hz / ζ = 0.7 servo, 500 °/s and 300 °/s² limits.
        """
        return cls._preset(name, axis_vector, overrides, encoder_error_rad=15.0 * units.ARCSEC,
                           encoder_resolution_rad=1.0 * units.ARCSEC,
                           position_noise_rad=1.0 * units.ARCSEC, wobble_rad=10.0 * units.ARCSEC,
                           non_orthogonality_rad=20.0 * units.ARCSEC,
                           rate_ripple_fraction=1e-4, rate_ripple_hz=2.0,
                           settling_frequency_hz=5.0, settling_damping=0.7,
                           max_rate_rps=500.0 * units.DEG, max_accel_rps2=300.0 * units.DEG)

    @classmethod
    def _preset(cls, name: str, axis_vector: ArrayLike, overrides: dict[str, Any],
                **values: Any) -> AxisSpec:
        values.update(overrides)
        return cls(name, np.asarray(axis_vector, dtype=float), **values)

    # --- derived quantities -------------------------------------------------------------------
    @property
    def omega_n_rps(self) -> float:
        """Servo natural frequency 2π·f [rad/s] (inf for exact tracking)."""
        return 2.0 * math.pi * float(self.settling_frequency_hz)

    @property
    def reference_accel_rps2(self) -> float:
        """Acceleration of the reference profile, ``max_accel_rps2 / ‖g‖₁`` [rad/s²]."""
        if math.isinf(self.omega_n_rps):
            return float(self.max_accel_rps2)
        return float(self.max_accel_rps2) / _servo.loop_norms(float(self.settling_damping))[0]

    @property
    def rate_overshoot_rps(self) -> float:
        """Bound on the servo's transient rate error, ‖k‖₁·a_ref [rad/s]."""
        if math.isinf(self.omega_n_rps):
            return 0.0
        k_norm = _servo.loop_norms(float(self.settling_damping))[1] / self.omega_n_rps
        return k_norm * self.reference_accel_rps2

    @cached_property
    def tilt_axis_resolved(self) -> _F64:
        """The tilt axis u1 (``tilt_axis`` or its default), ⟂ the nominal and actual axes."""
        if self.tilt_axis is not None:
            return np.array(self.tilt_axis)
        return _default_tilt_axis(np.array(self.axis_vector))

    @cached_property
    def actual_axis(self) -> _F64:
        """Axis direction in the parent frame, including the non-orthogonality tilt."""
        n = np.array(self.axis_vector)
        d = float(self.non_orthogonality_rad)
        u1 = self.tilt_axis_resolved
        return np.asarray(n * math.cos(d) + np.cross(u1, n) * math.sin(d))  # R_u1(δ)·n

    def wobble_axes(self) -> tuple[_F64, _F64]:
        """Return the wobble's tilt axes (u1, u2 = n × u1) in the tilted parent frame."""
        u1 = self.tilt_axis_resolved
        return u1, np.cross(self.axis_vector, u1)

    def encoder_error_rad_at(self, angle_rad: ArrayLike) -> _F64:
        """Return the encoder error ε(θ) = E·(sin θ + cos 2θ) [rad]."""
        th = np.asarray(angle_rad, dtype=np.float64)
        return float(self.encoder_error_rad) * (np.sin(th) + np.cos(2.0 * th))


@dataclass(frozen=True, eq=False)
class RateTableSpec:
    """A rate table: its axes, outer first (an empty tuple is a fixed plate)."""

    axes: tuple[AxisSpec, ...]

    def __post_init__(self) -> None:
        axes = tuple(self.axes)
        for ax in axes:
            if not isinstance(ax, AxisSpec):
                raise ConfigurationError(f"`axes` must hold AxisSpec; got {type(ax).__name__}")
        names = [ax.name for ax in axes]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ConfigurationError(f"axis names must be unique; repeated: {dup}")
        object.__setattr__(self, "axes", axes)

    @property
    def names(self) -> tuple[str, ...]:
        """Axis names, outer first."""
        return tuple(ax.name for ax in self.axes)

    def axis_index(self, axis: int | str) -> int:
        """Index of an axis given by index or name; raises InvalidInputError if it is absent."""
        if isinstance(axis, str):
            if axis in self.names:
                return self.names.index(axis)
        elif isinstance(axis, int | np.integer) and 0 <= int(axis) < len(self.axes):
            return int(axis)
        raise InvalidInputError(
            f"`axis` must be an index in 0..{len(self.axes) - 1} or a name in {self.names}; "
            f"got {axis!r}"
        )

    @classmethod
    def fixed(cls) -> RateTableSpec:
        """No moving axis: the platform is the base (p = t)."""
        return cls(axes=())

    @classmethod
    def single_axis(cls, grade: TableGrade = "high", *, name: str = "azimuth",
                    **overrides: Any) -> RateTableSpec:
        """Build a single-axis table turning about z_t (up); `overrides` replace AxisSpec fields."""
        return cls(axes=(_preset(grade, name, TABLE_AXIS_VECTORS["azimuth"], overrides),))

    @classmethod
    def dual_axis_pitch_roll(cls, grade: TableGrade = "high", **overrides: Any) -> RateTableSpec:
        """Build the dual-axis table of P1 (docs/p1.md): outer pitch about −y_t, inner roll about x.

        The axis directions are :data:`imucalib.conventions.TABLE_AXIS_VECTORS`, the ones the
        analysis uses.

        At (pitch θ, roll φ) an IMU with b = p (at home b = t) reads the specific force
        g·[sin θ, sin φ cos θ, cos θ cos φ]: with rot_tp = R_{−y}(θ)·R_x(φ),
        f_p = R_x(−φ)·R_y(θ)·[0, 0, g]. (90°, 0°) puts x_b up, (0°, 90°) puts y_b up.
        """
        pitch = _preset(grade, "pitch", TABLE_AXIS_VECTORS["pitch"],
                        {"tilt_axis": np.array(TABLE_AXIS_VECTORS["roll"]), **overrides})
        return cls(axes=(pitch, _preset(grade, "roll", TABLE_AXIS_VECTORS["roll"], overrides)))


def _preset(grade: str, name: str, vec: tuple[float, float, float],
            overrides: dict[str, Any]) -> AxisSpec:
    makers = {"ideal": AxisSpec.ideal, "lab": AxisSpec.lab_grade, "high": AxisSpec.high_grade}
    if grade not in makers:
        raise ConfigurationError(f"`grade` must be one of {sorted(makers)}; got {grade!r}")
    return makers[grade](name, vec, **overrides)


@dataclass(frozen=True, eq=False)
class TableFeedback:
    """What the table controller reports: measured axis angles [rad] and rates [rad/s], (n, k)."""

    time_s: _F64
    angle_rad: _F64
    rate_rps: _F64


def compute_platform_motion(spec: RateTableSpec, time_s: ArrayLike, angle_rad: ArrayLike,
                            rate_rps: ArrayLike, accel_rps2: ArrayLike) -> PlatformMotion:
    """Platform attitude and angular motion for given true axis trajectories (pure function).

    Parameters
    ----------
    spec : RateTableSpec
        The table (geometry, wobble and non-orthogonality are used).
    time_s : array_like, shape (n,)
        Sample times. [s]
    angle_rad, rate_rps, accel_rps2 : array_like, shape (n, k)
        True axis angles and their first and second derivatives, outer axis first.

    Returns
    -------
    PlatformMotion
    """
    t = as_array(time_s, "time_s", shape=(None,))
    k = len(spec.axes)
    n = t.shape[0]
    th = as_array(angle_rad, "angle_rad", shape=(n, k))
    thd = as_array(rate_rps, "rate_rps", shape=(n, k))
    thdd = as_array(accel_rps2, "accel_rps2", shape=(n, k))
    return _platform_motion(spec, t, th, thd, thdd)


def _platform_motion(spec: RateTableSpec, t: _F64, th: _F64, thd: _F64, thdd: _F64
                     ) -> PlatformMotion:
    """:func:`compute_platform_motion` on validated arrays."""
    geometry = [(np.array(ax.axis_vector), ax.tilt_axis_resolved, float(ax.non_orthogonality_rad),
                 float(ax.wobble_rad)) for ax in spec.axes]
    q, om, al = evaluate_chain(geometry, th, thd, thdd)
    return PlatformMotion(time_s=t, angle_rad=th, rate_rps=thd, accel_rps2=thdd,
                          rot_tp=Rotation.from_quat(q), omega_tp_p_rps=om, alpha_tp_p_rps2=al)


# --- the stateful controller twin ---------------------------------------------------------------
_MODES: tuple[AxisMode, ...] = ("off", "position", "rate", "stop")


class SimRateTable:
    """The twin of a rate-table controller, in virtual time.

    Commands are issued in non-decreasing time (``at_time_s`` ≥ 0); each replaces whatever the
    axis was still going to do after ``at_time_s``. The true motion and the controller's
    feedback can be evaluated at any times, before or after the last command.

    Parameters
    ----------
    spec : RateTableSpec
        The table.
    initial_angle_rad : array_like, shape (k,), optional
        Axis angles at rest at time 0 (default zeros); the axes start in mode ``"off"``. [rad]
    rng : numpy.random.Generator or int or None
        Source of the feedback's position noise.

    Examples
    --------
    >>> table = SimRateTable(RateTableSpec.dual_axis_pitch_roll("ideal"))
    >>> t_end = table.command_position("pitch", np.pi / 2, at_time_s=0.0)
    >>> motion = table.motion(np.array([t_end + 30.0]))
    >>> round(float(motion.angle_rad[0, 0]), 12)
    1.570796326795
    """

    def __init__(self, spec: RateTableSpec, *, initial_angle_rad: ArrayLike | None = None,
                 rng: np.random.Generator | int | None = None) -> None:
        if not isinstance(spec, RateTableSpec):
            raise ConfigurationError(f"`spec` must be a RateTableSpec; got {type(spec).__name__}")
        k = len(spec.axes)
        init = (np.zeros(k) if initial_angle_rad is None
                else as_array(initial_angle_rad, "initial_angle_rad", shape=(k,)))
        self.spec = spec
        self._profiles = [_servo.AxisProfile(ax.omega_n_rps, float(ax.settling_damping),
                                             float(ax.rate_ripple_hz), float(a0))
                          for ax, a0 in zip(spec.axes, init, strict=True)]
        self._rng = np.random.default_rng(rng)
        self._last_command_s = 0.0

    @property
    def n_axes(self) -> int:
        """Number of axes k."""
        return len(self.spec.axes)

    # --- commands -----------------------------------------------------------------------------
    def command_position(self, axis: int | str, angle_rad: float, at_time_s: float, *,
                         rate_rps: float | None = None, accel_rps2: float | None = None) -> float:
        """Move an axis to an angle (trapezoidal move, then servo settling), and hold it there.

        Parameters
        ----------
        axis : int or str
            Axis index (0 = outer) or name.
        angle_rad : float
            Target angle (unwrapped: 2π means one turn further than 0). [rad]
        at_time_s : float
            Time of the command. [s]
        rate_rps, accel_rps2 : float, optional
            Slower cruise rate and acceleration for this move (within the axis limits).

        Returns
        -------
        float
            Time at which the reference move ends (settling follows). [s]

        Raises
        ------
        LimitExceededError
            If the angle is outside the axis travel or a rate/acceleration exceeds a limit.
        InvalidInputError
            For an unknown axis, a non-finite value or a command earlier than the previous one.
        """
        i, ax = self._axis(axis)
        target = check_finite_scalar(angle_rad, "angle_rad")
        if ax.angle_limits_rad is not None:
            lo, hi = ax.angle_limits_rad
            if not lo <= target <= hi:
                raise LimitExceededError(
                    f"axis {ax.name!r}: angle {target:.9g} rad ({target / units.DEG:.6g}°) is "
                    f"outside the travel [{lo:.9g}, {hi:.9g}] rad"
                )
        v_lim = self._rate_limit(ax, ax.max_rate_rps if rate_rps is None else rate_rps)
        a_ref = self._accel_reference(ax, accel_rps2)
        t = self._check_time(at_time_s)
        v_cruise = v_lim - ax.rate_overshoot_rps * (a_ref / ax.reference_accel_rps2)
        return self._profiles[i].move_to(t, target, max(v_cruise, 0.5 * v_lim), a_ref,
                                         _MODES.index("position"))

    def command_rate(self, axis: int | str, rate_rps: float, at_time_s: float, *,
                     accel_rps2: float | None = None) -> float:
        """Spin an axis at a constant rate (ramp at the acceleration limit, then constant rate).

        Returns the time at which the reference ramp ends [s]. Raises LimitExceededError when
        |`rate_rps`| exceeds the axis limit; see :meth:`command_position` for the rest.
        """
        i, ax = self._axis(axis)
        rate = check_finite_scalar(rate_rps, "rate_rps")
        self._rate_limit(ax, rate, allow_zero=True)
        a_ref = self._accel_reference(ax, accel_rps2)
        t = self._check_time(at_time_s)
        mode = _MODES.index("rate" if rate != 0.0 else "stop")
        return self._profiles[i].spin(t, rate, a_ref, float(ax.rate_ripple_fraction), mode)

    def command_stop(self, axis: int | str, at_time_s: float) -> float:
        """Decelerate an axis to rest at the acceleration limit and hold where it stops.

        Returns the time at which the reference comes to rest. [s]
        """
        return self._brake(axis, at_time_s, "stop")

    def command_off(self, axis: int | str, at_time_s: float) -> float:
        """Switch an axis off: brake to rest at the acceleration limit, then hold (mode ``off``)."""
        return self._brake(axis, at_time_s, "off")

    def _brake(self, axis: int | str, at_time_s: float, mode: AxisMode) -> float:
        i, ax = self._axis(axis)
        t = self._check_time(at_time_s)
        return self._profiles[i].spin(t, 0.0, ax.reference_accel_rps2, 0.0, _MODES.index(mode))

    # --- evaluation ---------------------------------------------------------------------------
    def _axes_motion(self, t: _F64) -> tuple[_F64, _F64, _F64]:
        n, k = t.shape[0], self.n_axes
        th, thd, thdd = np.empty((n, k)), np.empty((n, k)), np.empty((n, k))
        for s in range(0, n, _BLOCK):  # in blocks, so that the temporaries stay small
            e = min(s + _BLOCK, n)
            for i, prof in enumerate(self._profiles):
                th[s:e, i], thd[s:e, i], thdd[s:e, i], _, _ = prof.evaluate(t[s:e])
        return th, thd, thdd

    def motion(self, time_s: ArrayLike) -> PlatformMotion:
        """Return the true platform motion at `time_s` (shape (n,), any order) [s]."""
        t = as_array(time_s, "time_s", shape=(None,))
        th, thd, thdd = self._axes_motion(t)
        return _platform_motion(self.spec, t, th, thd, thdd)

    def feedback(self, time_s: ArrayLike) -> TableFeedback:
        """Return measured axis angles and rates at `time_s` (module docstring: feedback model)."""
        t = as_array(time_s, "time_s", shape=(None,))
        th, thd, _ = self._axes_motion(t)
        angle, rate = np.empty_like(th), np.empty_like(thd)
        for i, ax in enumerate(self.spec.axes):
            e = float(ax.encoder_error_rad)
            meas = th[:, i] + ax.encoder_error_rad_at(th[:, i])
            if ax.position_noise_rad > 0:
                meas = meas + float(ax.position_noise_rad) * self._rng.standard_normal(t.shape[0])
            res = float(ax.encoder_resolution_rad)
            angle[:, i] = np.round(meas / res) * res if res > 0 else meas
            slope = e * (np.cos(th[:, i]) - 2.0 * np.sin(2.0 * th[:, i])) if e > 0 else 0.0
            rate[:, i] = thd[:, i] * (1.0 + slope)
        return TableFeedback(time_s=t, angle_rad=angle, rate_rps=rate)

    def axis_motion(self, axis: int | str, time_s: ArrayLike
                    ) -> tuple[_F64, _F64, _F64, _F64]:
        """Return true angle [rad], rate [rad/s], accel [rad/s²] and jerk [rad/s³] of an axis."""
        i, _ = self._axis(axis)
        t = as_array(time_s, "time_s", shape=(None,))
        th, thd, thdd, _, jerk = self._profiles[i].evaluate(t, with_jerk=True)
        return th, thd, thdd, np.zeros_like(th) if jerk is None else jerk

    def is_still(self, t_start_s: float, t_end_s: float) -> bool:
        """Whether every axis holds one angle, exactly at rest, from `t_start_s` to `t_end_s`."""
        return all(prof.is_still(float(t_start_s), float(t_end_s)) for prof in self._profiles)

    def hold_pose(self, time_s: float) -> tuple[float, ...]:
        """Return the reference angles of the pieces active at `time_s` [rad].

        While :meth:`is_still`, they are the axes' exact angles: equal poses give equal motion.
        """
        t = float(time_s)
        return tuple(p.segments[p.active_index(t)].r0 for p in self._profiles)

    def mode(self, axis: int | str, time_s: float) -> AxisMode:
        """Mode of an axis at a time: ``"off"``, ``"position"``, ``"rate"`` or ``"stop"``."""
        i, _ = self._axis(axis)
        prof = self._profiles[i]
        return _MODES[prof.segments[prof.active_index(check_finite_scalar(time_s, "time_s"))].mode]

    def is_settled(self, axis: int | str, time_s: ArrayLike, position_tol_rad: float,
                   rate_tol_rps: float) -> bool | NDArray[np.bool_]:
        """Whether the true axis motion is within tolerance of what was commanded.

        In rate mode: |rate − commanded rate| ≤ `rate_tol_rps`. Otherwise: |angle − target| ≤
        `position_tol_rad` and |rate| ≤ `rate_tol_rps`. Returns a bool for a scalar time, else
        an array of bools.
        """
        i, _ = self._axis(axis)
        pos_tol = check_nonnegative(position_tol_rad, "position_tol_rad")
        rate_tol = check_nonnegative(rate_tol_rps, "rate_tol_rps")
        scalar = np.ndim(time_s) == 0
        t = as_array(np.atleast_1d(np.asarray(time_s, dtype=float)), "time_s", shape=(None,))
        prof = self._profiles[i]
        th, thd, _, idx, _ = prof.evaluate(t)
        arr = prof.arrays()
        mode, target = arr["mode"][idx], arr["target"][idx]
        is_rate = mode == _MODES.index("rate")
        ok = np.where(is_rate, np.abs(thd - target) <= rate_tol,
                      (np.abs(th - target) <= pos_tol) & (np.abs(thd) <= rate_tol))
        return bool(ok[0]) if scalar else ok

    def settled_after_s(self, axis: int | str, position_tol_rad: float,
                        rate_tol_rps: float) -> float:
        """Time from which the axis stays settled (:meth:`is_settled`) after its last command.

        A conservative bound from the exponential envelope of the servo transient; ``inf`` in
        rate mode when the rate ripple alone exceeds `rate_tol_rps`. [s]
        """
        i, ax = self._axis(axis)
        seg = self._profiles[i].segments[-1]
        return _servo.settled_after(seg, float(ax.settling_damping), ax.omega_n_rps,
                                    check_positive(position_tol_rad, "position_tol_rad"),
                                    check_positive(rate_tol_rps, "rate_tol_rps"),
                                    _MODES[seg.mode] == "rate")

    # --- checks -------------------------------------------------------------------------------
    def _axis(self, axis: int | str) -> tuple[int, AxisSpec]:
        i = self.spec.axis_index(axis)
        return i, self.spec.axes[i]

    def _check_time(self, at_time_s: float) -> float:
        t = check_finite_scalar(at_time_s, "at_time_s")
        if t < self._last_command_s:
            raise InvalidInputError(
                f"commands must be issued in non-decreasing time (from 0 s); got at_time_s={t:g} "
                f"after a command at {self._last_command_s:g} s"
            )
        self._last_command_s = t
        return t

    def check_rate(self, axis: int, rate_rps: float) -> None:
        """Refuse a rate command beyond an axis's limit (nothing is commanded).

        Raises
        ------
        LimitExceededError
            If ``|rate_rps|`` exceeds the axis's ``max_rate_rps``.
        """
        _, ax = self._axis(axis)
        self._rate_limit(ax, rate_rps, allow_zero=True)

    @staticmethod
    def _rate_limit(ax: AxisSpec, rate_rps: float, *, allow_zero: bool = False) -> float:
        """Check |rate| against the limit (a move rate must also be > 0); return |rate|."""
        rate = check_finite_scalar(rate_rps, "rate_rps")
        if abs(rate) > ax.max_rate_rps:
            raise LimitExceededError(
                f"axis {ax.name!r}: rate {rate:.6g} rad/s ({rate / units.DEG:.6g} °/s) exceeds "
                f"the limit ±{ax.max_rate_rps:.6g} rad/s ({ax.max_rate_rps / units.DEG:.6g} °/s)"
            )
        if not allow_zero and rate <= 0.0:
            raise InvalidInputError(f"axis {ax.name!r}: move rate must be > 0; got {rate:g} rad/s")
        return abs(rate)

    @staticmethod
    def _accel_reference(ax: AxisSpec, accel_rps2: float | None) -> float:
        if accel_rps2 is None:
            return ax.reference_accel_rps2
        acc = check_positive(accel_rps2, "accel_rps2")
        if acc > ax.max_accel_rps2:
            raise LimitExceededError(
                f"axis {ax.name!r}: acceleration {acc:.6g} rad/s² exceeds the limit "
                f"{ax.max_accel_rps2:.6g} rad/s²"
            )
        return ax.reference_accel_rps2 * acc / ax.max_accel_rps2
