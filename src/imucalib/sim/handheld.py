"""Hand-held calibration sessions on the twin: an IMU put on its faces on a desk, turned by hand.

Field calibration has no rate table: the user lays the IMU on a desk, leaves it still for a few
seconds, turns it by hand to another face, and so on (Tedaldi, Pretto & Menegatti, "A robust and
easy to implement method for IMU calibration without external equipments", ICRA 2014), and for
the gyro scale factors turns it through known angles, whole turns flat on the desk (Ferraris,
Grimaldi & Parvis, "Procedure for effortless in-field calibration of three-axis rate gyros and
accelerometers", Sensors and Materials 7(5), 1995). :func:`handheld_session` simulates such a
session with the twin's own IMU (a truth drawn from a grade, its noise and output stage,
:class:`~imucalib.sim.synth.ImuSynthesizer`), so that every true value is known;
:func:`~imucalib.sim.handheld_csv.write_session_csv` writes it as the CSV a user would have.

Session
-------
1. The initial rest (pose 0): z up, tilted less than ``level_tilt_deg``, a random heading, for
   ``init_static_s`` (the variance detector's reference interval).
2. Poses 1 … n: pose k has face F_k up, cycling +x, −x, +y, −y, +z, −z (every axis direction),
   at the attitude

       R_tb = R_z(ψ) · R_h(θ) · R_F                                                   (H.5)

   (R_F puts F up, R_h(θ) tilts it by θ ~ U(off_axis_deg) about a random horizontal axis h,
   R_z(ψ) a heading ψ ~ U(0, 2π)), held still for U(static_s). With ``full_turns``, the first
   +x, +y and +z up poses are level instead (θ ~ U(0, level_tilt_deg)) and carry, after their
   static, a +360° turn about the vertical, a static, a −360° turn and a static: the known
   angles ±2π of Ferraris' method.
3. Between poses, a hand rotation along the shortest arc ((H.1) of
   :mod:`imucalib.sim.hand_motion`), of duration U(rotation_s) (twice that for a full turn),
   its rate peak at c ~ U(0.3, 0.7) of each move, with probability ``pause_probability`` a pause
   of 0.2–0.5 s halfway (at s ~ U(0.35, 0.65)), and a tremor of amplitude ``tremor_deg`` at
   U(6, 10) Hz about a random axis (about the vertical in a full turn: the IMU lies on the desk).

Harsher sessions, as real hands and sensors give them (:data:`HARSH`,
:func:`harsh_handheld_session`):

4. With ``rotation_deg`` the poses are not faces: pose k is pose k − 1 turned by an angle
   α ~ U(rotation_deg) about a random axis u of the body (φ = α·u, so 90–180° turns about any
   axis), and its face is the body axis nearest the vertical.
5. With ``bump_probability`` a pose is knocked, with that chance, partway through its static
   (at U(0.3, 0.7) of it): a jolt of U(0.1, 0.3) s turns it by U(1, 5)° about a random axis,
   and it rests in the new attitude (two statics of the same pose index, the rotation between
   them marked ``bump``).
6. ``gyro_bias_dps`` replaces the grade's gyro biases by U(−b, b) per axis; ``gyro_range_dps``
   narrows the gyro's full scale (a fast hand turn then clips, as on a ±250 °/s part).
7. ``warmup_degc`` warms the IMU during the session, T(t) = T₀ + ΔT·(1 − e^(−t/τ)) with
   τ = ``warmup_tau_s`` (self-heating after power-up), and the truth is drawn with the grade's
   typical temperature dependence (:func:`~imucalib.models.imu.sample_imu_model`), so that the
   biases drift with it: the true parameters at a time are ``model.parameters_at(T(t))``.

The IMU turns about its own origin at a fixed place (no translation): its specific force is
gravity seen in the body, its rate ω_tb plus Earth rate
(:func:`~imucalib.sim.kinematics.compute_imu_kinematics` with the hand attitude as the
platform). Statics are exactly still relative to the Earth.

Randomness
----------
One seed gives the session: a :class:`numpy.random.SeedSequence` of ``seed`` spawns four
children, the IMU's truth (:func:`~imucalib.models.imu.sample_imu_model`), the motion, the
synthesiser's noise, and the replaced gyro biases (the first three as before the fourth was
added, so a seed gives the same gentle session as it always did).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Final, Literal

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from imucalib import units
from imucalib._checks import check_finite_scalar, check_nonnegative, check_positive
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models.earth import Site
from imucalib.models.imu import GRADES, ImuModel, sample_imu_model
from imucalib.models.noise import NoiseModel
from imucalib.plan.equipment import ImuConfig
from imucalib.sim.build import _with_errors
from imucalib.sim.fixture import MountedImu
from imucalib.sim.hand_motion import HandMotion, HandMove, HandSegment
from imucalib.sim.kinematics import ImuKinematics, compute_imu_kinematics
from imucalib.sim.synth import ClockSpec, ImuSynthesizer, SimImu

__all__ = ["FACES", "HARSH", "HandRotation", "HandheldSession", "StaticPose", "handheld_session",
           "harsh_handheld_session"]

_F64 = NDArray[np.float64]
#: The face cycle of the poses: the body axis pointing up.
FACES: tuple[str, ...] = ("+x", "-x", "+y", "-y", "+z", "-z")
_AXIS = {"+x": (1.0, 0.0, 0.0), "-x": (-1.0, 0.0, 0.0), "+y": (0.0, 1.0, 0.0),
         "-y": (0.0, -1.0, 0.0), "+z": (0.0, 0.0, 1.0), "-z": (0.0, 0.0, -1.0)}
_UP_T = np.array([0.0, 0.0, 1.0])
_PAUSE_S = (0.2, 0.5)
_TREMOR_HZ = (6.0, 10.0)
_BUMP_S = (0.1, 0.3)
_BUMP_DEG = (1.0, 5.0)

#: A session as real hands and consumer sensors give it (module docstring, items 4–7): 40
#: poses of 2–5 s after a 50 s rest, each reached by a 90–180° turn about any axis in 1–3 s
#: with tremor and pauses, no full turns, a pose knocked now and then, gyro biases up to
#: 5 °/s, a ±500 °/s gyro, and the IMU warming by 4 °C.
HARSH: Final[Mapping[str, Any]] = MappingProxyType({
    "n_poses": 40, "static_s": (2.0, 5.0), "rotation_s": (1.0, 3.0), "init_static_s": 50.0,
    "full_turns": False, "rotation_deg": (90.0, 180.0), "tremor_deg": 1.0,
    "pause_probability": 0.4, "bump_probability": 0.1, "gyro_bias_dps": 5.0,
    "gyro_range_dps": 500.0, "warmup_degc": 4.0, "warmup_tau_s": 300.0,
})


@dataclass(frozen=True, eq=False)
class StaticPose:
    """A true static interval of a session.

    Attributes
    ----------
    pose_index : int
        0 for the initial rest, 1 … n_poses for the visited poses (a pose with full turns has
        three static intervals of the same index).
    face : str
        The body axis nominally up (``"+x"`` …).
    tilt_deg : float
        θ of (H.5): the angle between that axis and the vertical. [°]
    start_time_s, stop_time_s : float
        The interval [start, stop) of true time. [s]
    rot_tb : Rotation
        The true attitude (``v_t = rot_tb.apply(v_b)``).
    up_b : ndarray, shape (3,)
        The vertical (up) in the body: the direction of the true specific force. [–]
    """

    pose_index: int
    face: str
    tilt_deg: float
    start_time_s: float
    stop_time_s: float
    rot_tb: Rotation
    up_b: _F64


@dataclass(frozen=True, eq=False)
class HandRotation:
    """A true hand rotation between two static intervals.

    Attributes
    ----------
    start_time_s, stop_time_s : float
        Its span (the end of the static before, the start of the one after). [s]
    rotvec_b_rad : ndarray, shape (3,)
        φ: R_1 = R_0·exp([φ]×), in the body at the start ((H.1) of
        :mod:`imucalib.sim.hand_motion`). [rad]
    full_turn : bool
        A whole turn about the vertical (φ = ±2π·up_b).
    angle_rad : float
        The signed angle: ±2π for a full turn (+ counter-clockwise seen from above), ‖φ‖
        otherwise. [rad]
    bump : bool
        A jolt within a pose (module docstring, item 5), not a turn to a new pose.
    """

    start_time_s: float
    stop_time_s: float
    rotvec_b_rad: _F64
    full_turn: bool
    angle_rad: float
    bump: bool = False


@dataclass(frozen=True, eq=False)
class HandheldSession:
    """A simulated hand-held session: the IMU's output and the truth behind it.

    Attributes
    ----------
    time_s : ndarray, shape (n,)
        Sample times (k / sample_rate_hz). [s]
    gyro_rps, accel_mps2 : ndarray, shape (n, 3)
        The IMU's outputs. [rad/s], [m/s²]
    temperature_degc : ndarray, shape (n,)
        Its temperature sensor. [°C]
    model : ImuModel
        The true IMU (errors, noise, output stage).
    site : Site
        Where the desk is.
    statics : tuple of StaticPose
        The true static intervals, in time order.
    rotations : tuple of HandRotation
        The true rotations, one between each two consecutive statics.
    motion : HandMotion
        The motion, to evaluate at any time (:meth:`HandMotion.evaluate`).
    true_rate_b_rps, true_specific_force_b_mps2 : ndarray, shape (n, 3)
        The true inputs at the samples (Earth rate included). [rad/s], [m/s²]
    sample_rate_hz : float
    grade : str
    seed : int
    """

    time_s: _F64
    gyro_rps: _F64
    accel_mps2: _F64
    temperature_degc: _F64
    model: ImuModel
    site: Site
    statics: tuple[StaticPose, ...]
    rotations: tuple[HandRotation, ...]
    motion: HandMotion
    true_rate_b_rps: _F64
    true_specific_force_b_mps2: _F64
    sample_rate_hz: float
    grade: str
    seed: int

    def __len__(self) -> int:
        return int(self.time_s.shape[0])

    @property
    def full_turns(self) -> tuple[HandRotation, ...]:
        """The full turns about the vertical (Ferraris' known angles)."""
        return tuple(r for r in self.rotations if r.full_turn)

    def kinematics(self, time_s: _F64) -> ImuKinematics:
        """Return the true inputs at any times (the same equations as the samples')."""
        return compute_imu_kinematics(self.motion.platform_motion(time_s), self.site,
                                      MountedImu("handheld"))


def _range(value: tuple[float, float], name: str, *, low: float = 0.0) -> tuple[float, float]:
    a, b = (check_finite_scalar(v, name) for v in value)
    if not low <= a <= b:
        raise InvalidInputError(f"`{name}` must be a range ({low:g} ≤ min ≤ max); got {value}")
    return a, b


def _probability(value: float, name: str) -> float:
    p = check_finite_scalar(value, name)
    if not 0.0 <= p <= 1.0:
        raise InvalidInputError(f"`{name}` must be in [0, 1]; got {p}")
    return p


def _pose_attitude(face: str, tilt_rad: float, rng: np.random.Generator) -> Rotation:
    """(H.5): face up, tilted by `tilt_rad` about a random horizontal axis, random heading."""
    rot_face, _ = Rotation.align_vectors([_UP_T], [_AXIS[face]])
    az = rng.uniform(0.0, 2.0 * math.pi)
    tilt = Rotation.from_rotvec(tilt_rad * np.array([math.cos(az), math.sin(az), 0.0]))
    heading = Rotation.from_rotvec([0.0, 0.0, rng.uniform(0.0, 2.0 * math.pi)])
    return heading * tilt * rot_face


def _moves(t0: float, dur: float, rng: np.random.Generator,
           pause_probability: float) -> tuple[HandMove, ...]:
    """Return the moves of s over [t0, t0 + dur]: one, or two with a pause between them."""
    if rng.random() >= pause_probability:
        return (HandMove(t0, t0 + dur, 0.0, 1.0, rng.uniform(0.3, 0.7)),)
    pause = min(rng.uniform(*_PAUSE_S), 0.3 * dur)
    mid = rng.uniform(0.35, 0.65)
    t1 = t0 + (dur - pause) * mid
    return (HandMove(t0, t1, 0.0, mid, rng.uniform(0.3, 0.7)),
            HandMove(t1 + pause, t0 + dur, mid, 1.0, rng.uniform(0.3, 0.7)))


def _random_unit(rng: np.random.Generator) -> _F64:
    v = rng.standard_normal(3)
    return np.asarray(v / np.linalg.norm(v), dtype=np.float64)


def _rotation(t0: float, dur: float, rot0: Rotation, phi: _F64, rng: np.random.Generator,
              tremor_rad: float, pause_probability: float, axis: _F64 | None) -> HandSegment:
    moves = _moves(t0, dur, rng, pause_probability)
    return HandSegment(t0, t0 + dur, rot0, phi, moves, tremor_rad=tremor_rad,
                       tremor_hz=rng.uniform(*_TREMOR_HZ),
                       tremor_phase_rad=rng.uniform(0.0, 2.0 * math.pi),
                       tremor_axis_b=_random_unit(rng) if axis is None else axis)


@dataclass(frozen=True)
class _Shape:
    """What a session's motion is drawn from (the arguments of :func:`handheld_session`)."""

    n_poses: int
    off_axis_deg: tuple[float, float]
    static_s: tuple[float, float]
    rotation_s: tuple[float, float]
    init_static_s: float
    full_turns: bool
    level_tilt_deg: float
    tremor_rad: float
    pause_probability: float
    rotation_deg: tuple[float, float] | None
    bump_probability: float


def _face_of(rot: Rotation) -> tuple[str, float]:
    """Return the body axis nearest the vertical at `rot`, and its angle from it [°]."""
    up_b = rot.inv().apply(_UP_T)
    i = int(np.argmax(np.abs(up_b)))
    face = ("+" if up_b[i] > 0 else "-") + "xyz"[i]
    return face, math.degrees(math.acos(min(1.0, abs(float(up_b[i])))))


def _plan(shape: _Shape, rng: np.random.Generator
          ) -> tuple[HandMotion, list[StaticPose], list[HandRotation]]:
    """Draw the poses and rotations of a session (module docstring)."""
    segments: list[HandSegment] = []
    statics: list[StaticPose] = []
    rotations: list[HandRotation] = []
    t = 0.0

    def hold(index: int, face: str, tilt: float, rot: Rotation, dur: float) -> None:
        nonlocal t
        segments.append(HandSegment(t, t + dur, rot, np.zeros(3)))
        statics.append(StaticPose(index, face, tilt, t, t + dur, rot, rot.inv().apply(_UP_T)))
        t += dur

    def move(rot0: Rotation, phi: _F64, dur: float, turn: bool, axis: _F64 | None, *,
             bump: bool = False) -> Rotation:
        nonlocal t
        if bump:
            segments.append(_rotation(t, dur, rot0, phi, rng, 0.0, 0.0, None))
        else:
            segments.append(_rotation(t, dur, rot0, phi, rng, shape.tremor_rad,
                                      shape.pause_probability, axis))
        angle = float(np.dot(phi, rot0.inv().apply(_UP_T))) if turn else float(
            np.linalg.norm(phi))
        rotations.append(HandRotation(t, t + dur, phi, turn, angle, bump))
        t += dur
        return rot0 * Rotation.from_rotvec(phi)

    def rest(index: int, face: str, tilt: float, rot: Rotation, dur: float) -> Rotation:
        """Hold a pose, knocked partway with chance `bump_probability` (item 5)."""
        if shape.bump_probability <= 0.0 or rng.random() >= shape.bump_probability:
            hold(index, face, tilt, rot, dur)
            return rot
        jolt = rng.uniform(*_BUMP_S)
        first = (dur - jolt) * rng.uniform(0.3, 0.7)
        hold(index, face, tilt, rot, first)
        rot = move(rot, math.radians(rng.uniform(*_BUMP_DEG)) * _random_unit(rng), jolt,
                   False, None, bump=True)
        hold(index, *_face_of(rot), rot, max(dur - jolt - first, 1e-3))
        return rot

    tilt0 = rng.uniform(0.0, shape.level_tilt_deg)
    if shape.rotation_deg is not None:  # item 4: turns about any axis, poses anywhere
        rot = _pose_attitude("+z", math.radians(tilt0), rng)
        hold(0, "+z", tilt0, rot, shape.init_static_s)
        for k in range(shape.n_poses):
            phi = math.radians(rng.uniform(*shape.rotation_deg)) * _random_unit(rng)
            rot = move(rot, phi, rng.uniform(*shape.rotation_s), False, None)
            rot = rest(k + 1, *_face_of(rot), rot, rng.uniform(*shape.static_s))
        return HandMotion(tuple(segments)), statics, rotations
    # (pose index, face, tilt [°], with turns), every tilt drawn first
    poses: list[tuple[int, str, float, bool]] = [(0, "+z", tilt0, False)]
    turned: set[str] = set()
    for k in range(shape.n_poses):
        face = FACES[k % len(FACES)]
        turns = shape.full_turns and face.startswith("+") and face not in turned
        if turns:
            turned.add(face)
        tilt = (rng.uniform(0.0, shape.level_tilt_deg) if turns
                else rng.uniform(*shape.off_axis_deg))
        poses.append((k + 1, face, tilt, turns))
    rot = Rotation.identity()
    for index, face, tilt, turns in poses:
        new = _pose_attitude(face, math.radians(tilt), rng)
        if index > 0:
            move(rot, (rot.inv() * new).as_rotvec(), rng.uniform(*shape.rotation_s), False, None)
        rot = new
        if index == 0:
            hold(0, face, tilt, rot, shape.init_static_s)
        elif not turns:
            rot = rest(index, face, tilt, rot, rng.uniform(*shape.static_s))
        else:
            hold(index, face, tilt, rot, rng.uniform(*shape.static_s))
            up_b = rot.inv().apply(_UP_T)
            for sign in (1.0, -1.0):
                move(rot, sign * 2.0 * math.pi * up_b, 2.0 * rng.uniform(*shape.rotation_s),
                     True, up_b)
                hold(index, face, tilt, rot, rng.uniform(*shape.static_s))
    return HandMotion(tuple(segments)), statics, rotations


def _model(grade: str, rng: np.random.Generator, sample_rate_hz: float, noise: str,
           errors: dict[str, object] | None, *, thermal: bool, reference_degc: float
           ) -> ImuModel:
    if grade not in GRADES:
        raise ConfigurationError(f"unknown IMU grade {grade!r}; expected one of {sorted(GRADES)}")
    if noise not in ("grade", "white"):
        raise ConfigurationError(f"`noise` must be 'grade' or 'white'; got {noise!r}")
    if thermal:
        model = sample_imu_model(grade, rng, sample_rate_hz=sample_rate_hz,
                                 temperature_dependence="typical",
                                 reference_temperature_degc=reference_degc)
    else:
        model = sample_imu_model(grade, rng, sample_rate_hz=sample_rate_hz)
    if errors:
        try:
            cfg = ImuConfig(name="handheld", grade=grade, errors=errors)
        except ValueError as exc:  # pydantic's ValidationError: the key or shape named
            raise InvalidInputError(f"`errors`: {exc}") from exc
        model = _with_errors(model, cfg)
    if noise == "white":
        model = dataclasses.replace(
            model, gyro_noise=NoiseModel(white_density=model.gyro_noise.white_density),
            accel_noise=NoiseModel(white_density=model.accel_noise.white_density))
    return model


def _harsher(model: ImuModel, rng: np.random.Generator, gyro_bias_dps: float | None,
             gyro_range_dps: float | None) -> ImuModel:
    """Item 6 of the module docstring: the gyro biases and full scale replaced."""
    if gyro_bias_dps is not None:
        bias = rng.uniform(-gyro_bias_dps, gyro_bias_dps, 3) * units.DEG
        model = dataclasses.replace(model, gyro=dataclasses.replace(model.gyro, bias=bias))
    if gyro_range_dps is not None:
        model = dataclasses.replace(model, gyro_output=dataclasses.replace(
            model.gyro_output, range=gyro_range_dps * units.DEG))
    return model


def handheld_session(
    grade: str = "consumer",
    *,
    seed: int,
    n_poses: int = 18,
    off_axis_deg: tuple[float, float] = (5.0, 30.0),
    static_s: tuple[float, float] = (4.0, 8.0),
    rotation_s: tuple[float, float] = (1.5, 4.0),
    init_static_s: float = 10.0,
    full_turns: bool = True,
    sample_rate_hz: float = 100.0,
    site: Site | None = None,
    noise: Literal["grade", "white"] = "grade",
    errors: dict[str, object] | None = None,
    tremor_deg: float = 0.3,
    pause_probability: float = 0.3,
    level_tilt_deg: float = 2.0,
    temperature_degc: float = 25.0,
    rotation_deg: tuple[float, float] | None = None,
    bump_probability: float = 0.0,
    gyro_bias_dps: float | None = None,
    gyro_range_dps: float | None = None,
    warmup_degc: float = 0.0,
    warmup_tau_s: float = 300.0,
) -> HandheldSession:
    """Simulate a hand-held calibration session on the twin (module docstring).

    Parameters
    ----------
    grade : {"consumer", "tactical", "navigation"}
        The IMU's grade; its truth is drawn from it.
    seed : int
        Seeds everything: the same seed gives the same session, bit for bit.
    n_poses : int
        Poses visited after the initial rest (at least 6: every face up once).
    off_axis_deg : (float, float)
        Range of a pose's tilt θ from its face (H.5). [°]
    static_s, rotation_s : (float, float)
        Ranges of a static's and a rotation's duration (a full turn takes twice). [s]
    init_static_s : float
        The initial rest. [s]
    full_turns : bool
        Add ±360° turns about the vertical at the first +x, +y and +z up poses (then level).
    sample_rate_hz : float
        The IMU's output data rate. [Hz]
    site : Site, optional
        Where the desk is (default latitude 45°, the twin's default site).
    noise : {"grade", "white"}
        The grade's noise, or its white terms only (a bias that does not wander).
    errors : dict, optional
        Truth parameters replaced, ``"<triad>.<parameter>"`` → values (SI), as
        ``ImuConfig.errors`` (docs/twin.md).
    tremor_deg : float
        Hand tremor amplitude during rotations. [°]
    pause_probability : float
        Chance that a rotation pauses halfway, in [0, 1].
    level_tilt_deg : float
        Largest tilt of the initial rest and of the poses with full turns. [°]
    temperature_degc : float
        The IMU's temperature (at the start, with `warmup_degc`). [°C]
    rotation_deg : (float, float), optional
        Turn each pose by an angle in this range about a random axis instead of visiting the
        faces (module docstring, item 4; `off_axis_deg` and `full_turns` then do not apply). [°]
    bump_probability : float
        Chance that a pose is knocked partway through its static, in [0, 1] (item 5).
    gyro_bias_dps : float, optional
        Replace the gyro biases by U(−b, b) per axis (item 6). [°/s]
    gyro_range_dps : float, optional
        Replace the gyro's full scale ± (item 6). [°/s]
    warmup_degc, warmup_tau_s : float
        The IMU warms by ΔT with time constant τ during the session, its parameters following
        the grade's typical temperature dependence (item 7; 0: constant temperature, no
        temperature dependence). [°C], [s]

    Returns
    -------
    HandheldSession

    Raises
    ------
    InvalidInputError
        A range that is not one, n_poses < 6, a bad `errors` entry, a probability outside
        [0, 1], a non-positive bias bound, full scale or time constant.
    ConfigurationError
        An unknown grade or noise kind.
    """
    if not isinstance(n_poses, int) or n_poses < len(FACES):
        raise InvalidInputError(f"`n_poses` must be an integer ≥ {len(FACES)} (every face up "
                                f"once); got {n_poses!r}")
    off_axis = _range(off_axis_deg, "off_axis_deg")
    if off_axis[1] >= 90.0:
        raise InvalidInputError(f"`off_axis_deg` must stay below 90°; got {off_axis_deg}")
    statics_s = _range(static_s, "static_s", low=1e-3)
    rotations_s = _range(rotation_s, "rotation_s", low=1e-3)
    init_s = check_positive(init_static_s, "init_static_s")
    fs = check_positive(sample_rate_hz, "sample_rate_hz")
    tremor = check_nonnegative(tremor_deg, "tremor_deg") * units.DEG
    pause = _probability(pause_probability, "pause_probability")
    bump = _probability(bump_probability, "bump_probability")
    level = check_nonnegative(level_tilt_deg, "level_tilt_deg")
    temp = check_finite_scalar(temperature_degc, "temperature_degc")
    turn_deg = None if rotation_deg is None else _range(rotation_deg, "rotation_deg")
    if turn_deg is not None and turn_deg[1] > 180.0:
        raise InvalidInputError(f"`rotation_deg` must stay within 180°; got {rotation_deg}")
    bias_dps = None if gyro_bias_dps is None else check_positive(gyro_bias_dps, "gyro_bias_dps")
    range_dps = (None if gyro_range_dps is None
                 else check_positive(gyro_range_dps, "gyro_range_dps"))
    warm = check_finite_scalar(warmup_degc, "warmup_degc")
    tau = check_positive(warmup_tau_s, "warmup_tau_s")
    site = Site(latitude_deg=45.0) if site is None else site
    model_ss, motion_ss, synth_ss, bias_ss = np.random.SeedSequence(abs(int(seed))).spawn(4)
    model = _harsher(_model(grade, np.random.default_rng(model_ss), fs, noise, errors,
                            thermal=warm != 0.0, reference_degc=temp),
                     np.random.default_rng(bias_ss), bias_dps, range_dps)
    shape = _Shape(n_poses, off_axis, statics_s, rotations_s, init_s, full_turns, level,
                   tremor, pause, turn_deg, bump)
    motion, statics, rotations = _plan(shape, np.random.default_rng(motion_ss))
    mount = MountedImu("handheld")
    synth = ImuSynthesizer(SimImu("handheld", model, ClockSpec()), np.random.default_rng(synth_ss))

    def temperature(t: _F64) -> tuple[_F64, _F64]:
        """Item 7: T₀ + ΔT·(1 − e^(−t/τ)) and its rate."""
        decay = np.exp(-np.asarray(t, dtype=np.float64) / tau)
        return temp + warm * (1.0 - decay), warm / tau * decay

    samples = synth.synthesize(
        motion.duration_s,
        lambda t: compute_imu_kinematics(motion.platform_motion(t), site, mount),
        temperature)
    return HandheldSession(
        time_s=samples.time_s, gyro_rps=samples.gyro_rps, accel_mps2=samples.accel_mps2,
        temperature_degc=samples.temperature_degc, model=model, site=site,
        statics=tuple(statics), rotations=tuple(rotations), motion=motion,
        true_rate_b_rps=samples.true_rate_b_rps,
        true_specific_force_b_mps2=samples.true_specific_force_b_mps2,
        sample_rate_hz=fs, grade=grade, seed=int(seed))


def harsh_handheld_session(grade: str = "consumer", *, seed: int, **overrides: Any
                           ) -> HandheldSession:
    """Return :func:`handheld_session` with :data:`HARSH`, any of its entries overridden.

    Examples
    --------
    >>> s = harsh_handheld_session("consumer", seed=3, n_poses=8, init_static_s=5.0)
    >>> sum(not r.bump for r in s.rotations)
    8
    """
    return handheld_session(grade, seed=seed, **{**HARSH, **overrides})
