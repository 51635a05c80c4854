"""True inertial inputs of an IMU on a moving platform: angular rate and specific force.

Contents
--------
:class:`PlatformMotion`
    True motion of a table platform relative to its base (made by
    :mod:`imucalib.sim.table`, consumed here).
:class:`ImuKinematics`
    What an ideal IMU would measure, in its body frame, with its attitude.
:func:`compute_imu_kinematics`
    From the platform motion, the site and the IMU's mount.
:func:`compute_fixture_kinematics`
    The same for every IMU on a :class:`~imucalib.sim.fixture.Fixture`.
:func:`stationary_platform_motion`
    A platform at rest (no table, or a table holding still) as a :class:`PlatformMotion`.

Equations
---------
The table base t is fixed to the Earth; the platform p turns relative to t with angular rate ω
and acceleration α (``motion.omega_tp_p_rps``, ``motion.alpha_tp_p_rps2``, in p); the IMU origin
sits at r (in p, relative to the rotation centre; ṙ, r̈ non-zero only for a stretching centrifuge
arm); its body frame has the fixed orientation R_pb = R_pm·R_mb. With R_tb = R_tp·R_pb, Earth rate
Ω = ω_ie (in t) and g the local gravity magnitude:

    ω_ib^b = R_bt·Ω + R_bp·ω                                                  (gyro input)
    v^t    = R_tp·(ω × r + ṙ)                        (velocity relative to the Earth)
    a^p    = α × r + ω × (ω × r) + 2 ω × ṙ + r̈       (acceleration relative to t, in p)
    f^b    = R_bt·([0, 0, g] + R_tp·a^p + 2 Ω × v^t)                  (accelerometer input)
    ω̇_ib^b = R_bp·α + (R_bt·Ω) × (R_bp·ω)

The specific force is f = a_i − G (conventions: a level IMU at rest reads +g on its up axis).
The inertial acceleration of a point moving relative to the rotating Earth is
a_i = a_e + 2Ω × v_e + Ω × (Ω × R) ([2], ch. 2); the plumb-line gravity g = G − Ω × (Ω × R) =
[0, 0, −g]_t absorbs the centrifugal part, so f = a_e + 2Ω × v_e − g_t. The centripetal term
ω × (ω × r) is constant in p at constant ω and does not average out over revolutions; 2Ω × v
adds the (ω + Ω_U)² ≈ ω² + 2ωΩ_U effect of IEEE 836 ([1], §7, Eqs. (7.1) and (7.3)). Terms of
order Ω²·|r| (< 10⁻⁸ m/s² at r = 1 m) are neglected; with ``gravity_gradient=True`` the
normal-field gradient of g over the lever arm (≈ 3·10⁻⁶ s⁻² · |r|) is added ([1], §2, the
free-air gradient of Eq. (2.3)). ω̇_ib^b is the derivative of the body-frame components of ω_ib
(equal to its inertial derivative expressed in b), the input of the accelerometer size effect
([1], §7, Eq. (7.2)).

References
----------
.. [1] docs/equations.md §2 (gravity and its free-air gradient) and §7 (centripetal, tangential
   and Earth-rate terms of continuous rotation, the size effect, the centrifuge input); IEEE Std
   836-2009 (precision centrifuge testing).
.. [2] P. D. Groves, *Principles of GNSS, Inertial, and Multisensor Integrated Navigation
   Systems*, 2nd ed., Artech House, 2013, ch. 2 (kinematics in rotating frames, specific force
   and gravity).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from imucalib._checks import as_array
from imucalib.errors import InvalidInputError
from imucalib.models.earth import Site
from imucalib.sim._rotation import cross, quat_conj, quat_mul, quat_rotate
from imucalib.sim.fixture import Fixture, MountedImu, as_rotation

__all__ = [
    "ImuKinematics",
    "PlatformMotion",
    "compute_fixture_kinematics",
    "compute_imu_kinematics",
    "stationary_platform_motion",
]

_F64 = NDArray[np.float64]
_BLOCK = 1 << 16  # samples per block (keeps temporaries small)


@dataclass(frozen=True, eq=False)
class PlatformMotion:
    """True motion of the table platform p relative to the base t.

    Attributes
    ----------
    time_s : ndarray, shape (n,)
    angle_rad, rate_rps, accel_rps2 : ndarray, shape (n, k)
        True axis angles, rates and accelerations, outer axis first. [rad], [rad/s], [rad/s²]
    rot_tp : Rotation, length n
        Platform attitude; ``v_t = rot_tp.apply(v_p)``.
    omega_tp_p_rps : ndarray, shape (n, 3)
        Angular rate of p relative to t, expressed in p. [rad/s]
    alpha_tp_p_rps2 : ndarray, shape (n, 3)
        Its time derivative (equal in p and t components). [rad/s²]
    """

    time_s: _F64
    angle_rad: _F64
    rate_rps: _F64
    accel_rps2: _F64
    rot_tp: Rotation
    omega_tp_p_rps: _F64
    alpha_tp_p_rps2: _F64

    def __len__(self) -> int:
        return int(self.time_s.shape[0])

    def __getitem__(self, index: slice) -> PlatformMotion:
        """Return the samples selected by a slice."""
        if not isinstance(index, slice):
            raise InvalidInputError(f"a PlatformMotion is indexed by a slice; got {index!r}")
        return PlatformMotion(time_s=self.time_s[index], angle_rad=self.angle_rad[index],
                              rate_rps=self.rate_rps[index], accel_rps2=self.accel_rps2[index],
                              rot_tp=self.rot_tp[index],
                              omega_tp_p_rps=self.omega_tp_p_rps[index],
                              alpha_tp_p_rps2=self.alpha_tp_p_rps2[index])


@dataclass(frozen=True, eq=False)
class ImuKinematics:
    """True inertial inputs of one IMU.

    Attributes
    ----------
    time_s : ndarray, shape (n,)
        Sample times. [s]
    rate_b_rps : ndarray, shape (n, 3)
        Inertial angular rate ω_ib in the body frame b. [rad/s]
    specific_force_b_mps2 : ndarray, shape (n, 3)
        Specific force at the IMU origin, in b. [m/s²]
    angular_accel_b_rps2 : ndarray, shape (n, 3)
        Time derivative of ω_ib (body components). [rad/s²]
    rot_tb : Rotation, length n
        Attitude of b relative to the table base t; ``v_t = rot_tb.apply(v_b)``.
    constant : bool
        True when every sample is known to equal the first (set by :meth:`repeat`; the arrays
        are then read-only broadcast views).
    """

    time_s: _F64
    rate_b_rps: _F64
    specific_force_b_mps2: _F64
    angular_accel_b_rps2: _F64
    rot_tb: Rotation
    constant: bool = False

    def __len__(self) -> int:
        return int(self.time_s.shape[0])

    def repeat(self, n: int, *, time_s: _F64) -> ImuKinematics:
        """Return the first sample's inputs repeated `n` times, at `time_s` (shape (n,))."""
        if len(self) == 0 or time_s.shape != (n,):
            raise InvalidInputError(
                f"repeat needs a non-empty ImuKinematics and `time_s` of shape ({n},); "
                f"got {len(self)} sample(s) and shape {time_s.shape}"
            )
        return ImuKinematics(
            time_s=time_s,
            rate_b_rps=np.broadcast_to(self.rate_b_rps[:1], (n, 3)),
            specific_force_b_mps2=np.broadcast_to(self.specific_force_b_mps2[:1], (n, 3)),
            angular_accel_b_rps2=np.broadcast_to(self.angular_accel_b_rps2[:1], (n, 3)),
            rot_tb=self.rot_tb[np.zeros(n, dtype=np.intp)],
            constant=True,
        )


def _samples(value: ArrayLike | None, name: str, n: int) -> _F64 | None:
    if value is None:
        return None
    arr = as_array(value, name, shape=(None, 3))
    if arr.shape[0] != n:
        raise InvalidInputError(
            f"`{name}` must have shape ({n}, 3) like the motion; got {arr.shape}"
        )
    return np.ascontiguousarray(arr.T)  # component-major (3, n)


def compute_imu_kinematics(motion: PlatformMotion, site: Site, mount: MountedImu,
                           rot_pm: Rotation | None = None, lever_arm_p_m: ArrayLike | None = None,
                           *, lever_arm_rate_p_mps: ArrayLike | None = None,
                           lever_arm_accel_p_mps2: ArrayLike | None = None,
                           gravity_gradient: bool = False) -> ImuKinematics:
    """Compute the true angular rate and specific force of an IMU on the platform.

    Parameters
    ----------
    motion : PlatformMotion
        Platform motion relative to the base (from ``SimRateTable.motion``,
        ``compute_platform_motion`` or :func:`stationary_platform_motion`).
    site : Site
        Latitude, heading and gravity of the station.
    mount : MountedImu
        The IMU's orientation ``rot_mb`` and lever arm ``lever_arm_m_m``.
    rot_pm : Rotation, optional
        The fixture's mounting on the platform (default identity).
    lever_arm_p_m : array_like, shape (n, 3), optional
        Time-varying IMU origin in p, replacing ``rot_pm · lever_arm_m_m`` (the centrifuge's
        stretched arm). [m]
    lever_arm_rate_p_mps, lever_arm_accel_p_mps2 : array_like, shape (n, 3), optional
        Its first and second time derivatives (zero when omitted). [m/s], [m/s²]
    gravity_gradient : bool
        Add the normal-field gravity gradient over the lever arm (``Site.gravity_gradient_t_ps2``).

    Returns
    -------
    ImuKinematics
    """
    if not isinstance(motion, PlatformMotion):
        raise InvalidInputError(f"`motion` must be a PlatformMotion; got {type(motion).__name__}")
    n = len(motion)
    r_pm = Rotation.identity() if rot_pm is None else as_rotation(rot_pm, "rot_pm")
    r = _samples(lever_arm_p_m, "lever_arm_p_m", n)
    rd = _samples(lever_arm_rate_p_mps, "lever_arm_rate_p_mps", n)
    rdd = _samples(lever_arm_accel_p_mps2, "lever_arm_accel_p_mps2", n)
    r_fixed = np.asarray(r_pm.apply(mount.lever_arm_m_m), dtype=np.float64)
    q_pb = (r_pm * mount.rot_mb).as_quat()[:, None]  # (4, 1)
    q_tp_all = motion.rot_tp.as_quat().reshape(-1, 4)
    grad = site.gravity_gradient_t_ps2 if gravity_gradient else None
    out = np.empty((n, 13))  # rate, force, angular accel, q_tb
    for s in range(0, n, _BLOCK):  # in blocks, so that the temporaries stay small
        e = min(s + _BLOCK, n)
        out[s:e] = _kinematics_block(
            q_tp_all[s:e].T, q_pb, motion.omega_tp_p_rps[s:e].T, motion.alpha_tp_p_rps2[s:e].T,
            r_fixed[:, None] if r is None else r[:, s:e], None if rd is None else rd[:, s:e],
            None if rdd is None else rdd[:, s:e], site, grad).T
    return ImuKinematics(
        time_s=motion.time_s,
        rate_b_rps=out[:, 0:3].copy(),
        specific_force_b_mps2=out[:, 3:6].copy(),
        angular_accel_b_rps2=out[:, 6:9].copy(),
        rot_tb=Rotation.from_quat(out[:, 9:13]),
    )


def _kinematics_block(q_tp: _F64, q_pb: _F64, omega: _F64, alpha: _F64, r: _F64,
                      rd: _F64 | None, rdd: _F64 | None, site: Site, grad: _F64 | None) -> _F64:
    """Evaluate the module equations on one block (component-major); rows: ω_ib, f, ω̇, q_tb."""
    m = q_tp.shape[1]
    q_tb = quat_mul(q_tp, q_pb)
    q_bt, q_bp = quat_conj(q_tb), quat_conj(q_pb)
    earth_t = site.earth_rate_t_rps
    w_cross_r = cross(omega, r)
    v_rel_p = w_cross_r if rd is None else w_cross_r + rd
    a_rel_p = cross(alpha, r) + cross(omega, w_cross_r)
    if rd is not None:
        a_rel_p += 2.0 * cross(omega, rd)
    if rdd is not None:
        a_rel_p += rdd
    f_t = quat_rotate(q_tp, a_rel_p) + 2.0 * cross(earth_t[:, None], quat_rotate(q_tp, v_rel_p))
    f_t[2] += site.local_gravity_mps2
    if grad is not None:
        f_t -= grad @ np.broadcast_to(quat_rotate(q_tp, r), (3, m))  # f = a − g, g = g0 + Γ·ρ
    earth_b = quat_rotate(q_bt, earth_t)
    omega_tb_b = quat_rotate(q_bp, omega)
    block = np.empty((13, m))
    block[0:3] = earth_b + omega_tb_b
    block[3:6] = quat_rotate(q_bt, f_t)
    block[6:9] = quat_rotate(q_bp, alpha) + cross(earth_b, omega_tb_b)
    block[9:13] = q_tb
    return block


def compute_fixture_kinematics(motion: PlatformMotion, site: Site, fixture: Fixture, *,
                               gravity_gradient: bool = False) -> dict[str, ImuKinematics]:
    """:func:`compute_imu_kinematics` for every IMU of `fixture`, by name."""
    return {m.name: compute_imu_kinematics(motion, site, m, fixture.rot_pm,
                                           gravity_gradient=gravity_gradient)
            for m in fixture.mounts}


def stationary_platform_motion(time_s: ArrayLike, rot_tp: Rotation | None = None
                               ) -> PlatformMotion:
    """Return a platform at rest with attitude `rot_tp` (default identity) and no axes (k = 0)."""
    t = as_array(time_s, "time_s", shape=(None,))
    n = t.shape[0]
    rot = Rotation.identity() if rot_tp is None else as_rotation(rot_tp, "rot_tp")
    z0 = np.zeros((n, 0))
    return PlatformMotion(time_s=t, angle_rad=z0, rate_rps=z0.copy(), accel_rps2=z0.copy(),
                          rot_tp=Rotation.from_quat(np.tile(rot.as_quat(), (n, 1))),
                          omega_tp_p_rps=np.zeros((n, 3)), alpha_tp_p_rps2=np.zeros((n, 3)))
