"""Precision centrifuge with dynamic unbalance (docs/procedures.md, P3; IEEE Std 836).

Contents
--------
:class:`CentrifugeSpec`
    Static radius of the test position, unbalance coefficient c (and its load dependence), arm
    stretch, limits and the spin axis' imperfections.
:func:`dynamic_radius_m`
    r = r_s + c·ω² (+ κ·r_s·ω²).
:class:`SimCentrifuge`
    The stateful twin: a single-axis :class:`~imucalib.sim.table.SimRateTable` (rate mode, and
    arm positioning at rest by position commands) with the arm's dynamic geometry.

Geometry and signs
------------------
- The spin axis is z_t (up), tilted from the vertical by ``spin_axis_tilt_rad`` (towards x_t,
  with the arm's plane of rotation tilted alike); a positive rate turns the arm counter-clockwise
  seen from above. A tilt makes gravity leak into the radial input once per revolution
  (amplitude g·sin θ_s), which averages out over whole revolutions. Earth rate enters the gyro
  input and, through the Coriolis term 2Ω × v, the specific force: on average
  (ω + Ω_U)²·r ≈ ω²r + 2ωΩ_U·r with Ω_U = Ω_e sin L (docs/equations.md §7; computed exactly by
  :func:`~imucalib.sim.kinematics.compute_imu_kinematics`).
- The arm points along +x_p; the test position is at +r_t·x_p (``static_radius_m``). A mount is
  given by its static position p_s in p (signed: the side opposite the test position has
  x < 0).
- **Dynamic unbalance** (docs/procedures.md, P3): under load the rotor's centre shifts by c·ω²
  along +x_p (towards the test side for c > 0), so every point on the arm moves by c·ω²·x̂_p
  relative to the spin axis: the test position's radius becomes r_t + c·ω², a reference at
  +r_t/3 on the same side gets r_t/3 + c·ω² and one at −r_t/3 on the far side gets
  r_t/3 − c·ω² (it shares the sign of c only on the test side). c = c0 + c_per_kg·load
  [m/(rad/s)²].
- **Arm stretch** (IEEE 836 §3.1.1): an optional elastic radial elongation κ·ω²·(p_s,x, p_s,y, 0),
  proportional to the radius (``arm_stretch_s2`` κ [s²]); zero by default.
- Specific force at a point at distance r from the axis: −ω²·r towards the axis (plus gravity,
  +g up). An accelerometer whose input axis points **inward** (towards the axis) reads +ω²r; one
  pointing outward reads −ω²r.
- During ramps the mount also moves radially (ṙ = 2c·ω·ω̇, r̈ = 2c·(ω̇² + ω·ω̈)), which enters the
  specific force through 2ω × ṙ + r̈; the tangential term ω̇ × r is present during ramps.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from imucalib import units
from imucalib._checks import as_array, check_finite_scalar, check_nonnegative, check_positive
from imucalib.conventions import TABLE_AXIS_VECTORS
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models.earth import Site
from imucalib.sim.fixture import MountedImu, as_rotation
from imucalib.sim.kinematics import ImuKinematics, compute_imu_kinematics
from imucalib.sim.table import AxisSpec, PlatformMotion, RateTableSpec, SimRateTable, TableFeedback

__all__ = ["CentrifugeSpec", "SimCentrifuge", "dynamic_radius_m"]

_F64 = NDArray[np.float64]
_ARM = np.array([1.0, 0.0, 0.0])  # arm direction x_p


def dynamic_radius_m(rate_rps: ArrayLike, static_radius_m: float, unbalance_m_per_rps_sq: float,
                     arm_stretch_s2: float = 0.0) -> _F64:
    """Signed radius along the arm while spinning: r_s + c·ω² + κ·r_s·ω² [m].

    Parameters
    ----------
    rate_rps : array_like
        Spin rate ω (its sign does not matter). [rad/s]
    static_radius_m : float
        Signed static position along the arm (+x_p: test side). [m]
    unbalance_m_per_rps_sq : float
        Dynamic-unbalance coefficient c. [m/(rad/s)²]
    arm_stretch_s2 : float
        Relative elastic stretch κ per ω². [s²]
    """
    w2 = np.square(np.asarray(rate_rps, dtype=np.float64))
    r_s = check_finite_scalar(static_radius_m, "static_radius_m")
    return np.asarray(r_s + (check_finite_scalar(unbalance_m_per_rps_sq, "unbalance_m_per_rps_sq")
                             + check_finite_scalar(arm_stretch_s2, "arm_stretch_s2") * r_s) * w2,
                      dtype=np.float64)


@dataclass(frozen=True)
class CentrifugeSpec:
    """A precision centrifuge.

    Parameters
    ----------
    static_radius_m : float
        Static radius r_t of the test position, on +x_p. [m]
    unbalance_c0_m_per_rps_sq : float
        Dynamic-unbalance coefficient without load. [m/(rad/s)²]
    unbalance_c_m_per_rps_sq_per_kg : float
        Its change per kilogram of test load. [m/(rad/s)² per kg]
    max_rate_rps, max_accel_rps2 : float
        Spin limits. [rad/s], [rad/s²]
    arm_stretch_s2 : float
        Elastic radial stretch κ per ω² (Δr = κ·r·ω²). [s²]
    spin_axis_tilt_rad : float
        Tilt of the spin axis from the vertical. [rad]
    wobble_rad, rate_ripple_fraction, rate_ripple_hz, encoder_error_rad, encoder_resolution_rad,
    position_noise_rad, settling_frequency_hz, settling_damping : float
        As in :class:`~imucalib.sim.table.AxisSpec`.
    """

    static_radius_m: float = 1.0
    unbalance_c0_m_per_rps_sq: float = 0.0
    unbalance_c_m_per_rps_sq_per_kg: float = 0.0
    max_rate_rps: float = 720.0 * units.DEG
    max_accel_rps2: float = 90.0 * units.DEG
    arm_stretch_s2: float = 0.0
    spin_axis_tilt_rad: float = 0.0
    wobble_rad: float = 0.0
    rate_ripple_fraction: float = 0.0
    rate_ripple_hz: float = 1.0
    encoder_error_rad: float = 0.0
    encoder_resolution_rad: float = 0.0
    position_noise_rad: float = 0.0
    settling_frequency_hz: float = 2.0
    settling_damping: float = 0.9

    def __post_init__(self) -> None:
        check_positive(self.static_radius_m, "static_radius_m")
        check_finite_scalar(self.unbalance_c0_m_per_rps_sq, "unbalance_c0_m_per_rps_sq")
        check_finite_scalar(self.unbalance_c_m_per_rps_sq_per_kg, "unbalance_c_m_per_rps_sq_per_kg")
        check_finite_scalar(self.arm_stretch_s2, "arm_stretch_s2")
        self.axis_spec()  # validates the remaining fields

    def unbalance_m_per_rps_sq(self, load_kg: float) -> float:
        """Unbalance coefficient c = c0 + c_per_kg·load for a test load [m/(rad/s)²]."""
        load = check_nonnegative(load_kg, "load_kg")
        return (float(self.unbalance_c0_m_per_rps_sq)
                + float(self.unbalance_c_m_per_rps_sq_per_kg) * load)

    def axis_spec(self) -> AxisSpec:
        """Return the spin axis as a table axis (z_t up, tilt as non-orthogonality)."""
        return AxisSpec(
            "spin", np.array(TABLE_AXIS_VECTORS["spin"]), max_rate_rps=self.max_rate_rps,
            max_accel_rps2=self.max_accel_rps2, settling_frequency_hz=self.settling_frequency_hz,
            settling_damping=self.settling_damping, encoder_error_rad=self.encoder_error_rad,
            encoder_resolution_rad=self.encoder_resolution_rad,
            rate_ripple_fraction=self.rate_ripple_fraction, rate_ripple_hz=self.rate_ripple_hz,
            wobble_rad=self.wobble_rad, non_orthogonality_rad=self.spin_axis_tilt_rad,
            position_noise_rad=self.position_noise_rad,
        )

    def p3_positions_p_m(self) -> dict[str, _F64]:
        """Return the static mount positions of P3 (docs/procedures.md) in p [m].

        The test position is at +r_t, reference A at +r_t/3 (same side) and reference B at
        −r_t/3 (opposite side), all on the x_p axis.
        """
        r = float(self.static_radius_m)
        return {"test": r * _ARM, "ref_a": r / 3.0 * _ARM, "ref_b": -r / 3.0 * _ARM}


class SimCentrifuge:
    """The twin of a precision centrifuge, in virtual time.

    Parameters
    ----------
    spec : CentrifugeSpec
        The centrifuge.
    load_kg : float
        Test load on the arm; sets the unbalance c. [kg]
    rng : numpy.random.Generator or int or None
        Source of the encoder noise in :meth:`feedback`.
    """

    def __init__(self, spec: CentrifugeSpec, load_kg: float = 0.0,
                 rng: np.random.Generator | int | None = None) -> None:
        if not isinstance(spec, CentrifugeSpec):
            raise ConfigurationError(f"`spec` must be a CentrifugeSpec; got {type(spec).__name__}")
        self.spec = spec
        self.load_kg = check_nonnegative(load_kg, "load_kg")
        self.table = SimRateTable(RateTableSpec(axes=(spec.axis_spec(),)), rng=rng)

    @property
    def unbalance_m_per_rps_sq(self) -> float:
        """The unbalance coefficient c with the current load [m/(rad/s)²]."""
        return self.spec.unbalance_m_per_rps_sq(self.load_kg)

    # --- commands -----------------------------------------------------------------------------
    def command_rate(self, rate_rps: float, at_time_s: float) -> float:
        """Spin at `rate_rps` [rad/s]; returns the end of the ramp [s] (see SimRateTable)."""
        return self.table.command_rate(0, rate_rps, at_time_s)

    def command_stop(self, at_time_s: float) -> float:
        """Decelerate to rest; returns when the arm stops [s]."""
        return self.table.command_stop(0, at_time_s)

    def command_arm_position(self, angle_rad: float, at_time_s: float) -> float:
        """Turn the arm, at rest, to an angle (round-robin positions of P3); returns the move end.

        Raises InvalidInputError while the centrifuge is spinning in rate mode (stop it first).
        """
        if self.table.mode(0, check_finite_scalar(at_time_s, "at_time_s")) == "rate":
            raise InvalidInputError(
                "arm positioning needs the centrifuge at rest; command_stop it first "
                f"(it is in rate mode at {at_time_s:g} s)"
            )
        return self.table.command_position(0, angle_rad, at_time_s)

    # --- evaluation ---------------------------------------------------------------------------
    def radius_m(self, rate_rps: ArrayLike, static_radius_m: float) -> _F64:
        """Signed dynamic radius r_s + c·ω² + κ·r_s·ω² for this load [m]."""
        return dynamic_radius_m(rate_rps, static_radius_m, self.unbalance_m_per_rps_sq,
                                self.spec.arm_stretch_s2)

    def motion(self, time_s: ArrayLike) -> PlatformMotion:
        """Return the true arm (platform) motion; see :meth:`SimRateTable.motion`."""
        return self.table.motion(time_s)

    def feedback(self, time_s: ArrayLike) -> TableFeedback:
        """Return the measured arm angle and rate; see :meth:`SimRateTable.feedback`."""
        return self.table.feedback(time_s)

    def mount_kinematics_p(self, time_s: ArrayLike, static_position_p_m: ArrayLike
                           ) -> tuple[_F64, _F64, _F64]:
        """Position, velocity and acceleration of a mount point relative to p, each (n, 3).

        p(t) = p_s + ω²·(c·x̂_p + κ·(p_s,x, p_s,y, 0)); its derivatives use ω̇ and ω̈ of the
        true spin motion. [m], [m/s], [m/s²]
        """
        p_s = as_array(static_position_p_m, "static_position_p_m", shape=(3,))
        _, w, wd, wdd = self.table.axis_motion(0, time_s)
        shift = self.unbalance_m_per_rps_sq * _ARM + float(self.spec.arm_stretch_s2) * np.array(
            [p_s[0], p_s[1], 0.0])
        w2 = w * w
        w2_d = 2.0 * w * wd
        w2_dd = 2.0 * (wd * wd + w * wdd)
        return p_s + np.outer(w2, shift), np.outer(w2_d, shift), np.outer(w2_dd, shift)

    def mount_position_p_m(self, time_s: ArrayLike, static_position_p_m: ArrayLike) -> _F64:
        """Time-varying position of a mount point in p, shape (n, 3) [m]."""
        return self.mount_kinematics_p(time_s, static_position_p_m)[0]

    def imu_kinematics(self, time_s: ArrayLike, site: Site, mount: MountedImu,
                       rot_pm: Rotation | None = None, *, gravity_gradient: bool = False
                       ) -> ImuKinematics:
        """Return the true inputs of an IMU on the arm, with the arm's dynamic geometry.

        The mount's static position is ``rot_pm · lever_arm_m_m`` (m origin on the spin axis).
        """
        r_pm = Rotation.identity() if rot_pm is None else as_rotation(rot_pm, "rot_pm")
        motion = self.motion(time_s)
        static = np.asarray(r_pm.apply(mount.lever_arm_m_m), dtype=np.float64)
        pos, vel, acc = self.mount_kinematics_p(motion.time_s, static)
        return compute_imu_kinematics(motion, site, mount, r_pm, pos, lever_arm_rate_p_mps=vel,
                                      lever_arm_accel_p_mps2=acc,
                                      gravity_gradient=gravity_gradient)
