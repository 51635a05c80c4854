"""Fixtures: how IMUs sit on the table platform.

Contents
--------
:class:`MountedImu`
    One IMU on a fixture: its name, orientation ``rot_mb`` and lever arm ``lever_arm_m_m``.
:class:`Fixture`
    The IMUs on one fixture and the fixture's own mounting rotation on the platform ``rot_pm``.
:func:`single_imu_fixture`, :func:`hexahedral_fixture`, :func:`array_fixture`
    Builders for one IMU, the cube of P2 (docs/procedures.md, P2), and N IMUs on a plate.
:func:`as_rotation`
    A validated single proper rotation from a Rotation or a 3×3 matrix.

Frames (:mod:`imucalib.conventions`): the fixture frame m has its origin at the point where the
table's axes intersect (the rotation centre); ``rot_mb`` maps IMU body vectors into m, and
``lever_arm_m_m`` is the position of the IMU origin (its reference point) in m. ``rot_pm`` maps m
into the platform frame p; identity for an ideally mounted fixture, a small rotation for a
mounting error, or a large one to re-mount the fixture in another orientation.

Hexahedral fixture
------------------
A cube of half edge h centred on the rotation centre carries IMUs on its faces, each IMU's z axis
along its face's outward normal n̂ and its origin at the face centre (lever arm h·n̂) or moved
within the face along its own x_b, y_b (lever arm h·n̂ + o_x·x_b + o_y·y_b). Up to 64 IMUs fill
the faces round robin. Faces in order (the six orientations of P2 when m = t: z up, z down, y
up, y down, x up, x down; named by their normal in :data:`HEXAHEDRAL_FACE_NAMES`), with the
columns of ``mat_mb`` (x_b, y_b, z_b expressed in m):

====  ========  ==============================  ====================
face  n̂         rot_mb                          x_b, y_b, z_b in m
====  ========  ==============================  ====================
0     +z_m      identity                        +x, +y, +z
1     −z_m      R_x(180°)                       +x, −y, −z
2     +y_m      R_x(−90°)                       +x, −z, +y
3     −y_m      R_x(+90°)                       +x, +z, −y
4     +x_m      R_y(+90°)                       −z, +y, +x
5     −x_m      R_y(−90°)                       +z, +y, −x
====  ========  ==============================  ====================

The cube is remounted (placed on the table with another axis up) by replacing ``rot_pm``
(:meth:`Fixture.remounted`; the poses are :mod:`imucalib.plan.fixture_poses`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from imucalib._checks import as_array, check_positive
from imucalib.errors import ConfigurationError
from imucalib.plan.bounds import MAX_IMUS
from imucalib.plan.fixture_poses import FIXTURE_AXES

__all__ = [
    "HEXAHEDRAL_FACES",
    "HEXAHEDRAL_FACE_NAMES",
    "Fixture",
    "MountedImu",
    "array_fixture",
    "as_rotation",
    "hexahedral_fixture",
    "single_imu_fixture",
]

#: (outward normal in m, rot_mb as a matrix with columns x_b, y_b, z_b in m) of the six faces.
HEXAHEDRAL_FACES: tuple[tuple[tuple[float, float, float], tuple[tuple[float, ...], ...]], ...] = (
    ((0.0, 0.0, 1.0), ((1, 0, 0), (0, 1, 0), (0, 0, 1))),
    ((0.0, 0.0, -1.0), ((1, 0, 0), (0, -1, 0), (0, 0, -1))),
    ((0.0, 1.0, 0.0), ((1, 0, 0), (0, 0, -1), (0, 1, 0))),
    ((0.0, -1.0, 0.0), ((1, 0, 0), (0, 0, 1), (0, -1, 0))),
    ((1.0, 0.0, 0.0), ((0, 0, -1), (0, 1, 0), (1, 0, 0))),
    ((-1.0, 0.0, 0.0), ((0, 0, 1), (0, 1, 0), (-1, 0, 0))),
)
#: Names of the faces in the order of :data:`HEXAHEDRAL_FACES` (their outward normals).
HEXAHEDRAL_FACE_NAMES: tuple[str, ...] = FIXTURE_AXES
_HEX_NAMES = ("imu_zp", "imu_zn", "imu_yp", "imu_yn", "imu_xp", "imu_xn")


def as_rotation(value: Rotation | ArrayLike, name: str) -> Rotation:
    """Return a single proper rotation from a Rotation or a 3×3 rotation matrix.

    Raises
    ------
    ConfigurationError
        If `value` is a Rotation array, or a matrix that is not orthonormal with determinant +1
        (tolerance 1e-9).
    """
    if isinstance(value, Rotation):
        if not value.single:
            raise ConfigurationError(f"`{name}` must be a single rotation; got {len(value)}")
        return value
    mat = as_array(value, name, shape=(3, 3))
    err = float(np.max(np.abs(mat @ mat.T - np.eye(3))))
    det = float(np.linalg.det(mat))
    if err > 1e-9 or abs(det - 1.0) > 1e-9:
        raise ConfigurationError(
            f"`{name}` must be a proper rotation matrix (orthonormal, det +1); got "
            f"det {det:.6g}, max |M·Mᵀ − I| {err:.3g}"
        )
    return Rotation.from_matrix(mat)


def _rotation_or_identity(value: Rotation | ArrayLike | None, name: str) -> Rotation:
    return Rotation.identity() if value is None else as_rotation(value, name)


@dataclass(frozen=True, eq=False)
class MountedImu:
    """One IMU on a fixture.

    Parameters
    ----------
    name : str
        Unit name (serial); unique on a fixture.
    rot_mb : Rotation or array_like (3, 3)
        Maps IMU body vectors into the fixture frame m (a matrix is checked to be proper).
    lever_arm_m_m : array_like, shape (3,)
        Position of the IMU origin in m, relative to the rotation centre. [m]
    """

    name: str
    rot_mb: Rotation = field(default_factory=Rotation.identity)
    lever_arm_m_m: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ConfigurationError(f"`name` of a mounted IMU must be a non-empty string; "
                                     f"got {self.name!r}")
        object.__setattr__(self, "rot_mb", as_rotation(self.rot_mb, f"rot_mb of {self.name!r}"))
        arm = as_array(self.lever_arm_m_m, f"lever_arm_m_m of {self.name!r}", shape=(3,))
        object.__setattr__(self, "lever_arm_m_m", arm)


@dataclass(frozen=True, eq=False)
class Fixture:
    """IMUs on one fixture, and the fixture's mounting rotation on the platform.

    Parameters
    ----------
    mounts : tuple of MountedImu
        At least one; names unique.
    rot_pm : Rotation or array_like (3, 3)
        Maps fixture vectors into the platform frame p (identity: ideal mounting).
    """

    mounts: tuple[MountedImu, ...]
    rot_pm: Rotation = field(default_factory=Rotation.identity)

    def __post_init__(self) -> None:
        mounts = tuple(self.mounts)
        if not mounts:
            raise ConfigurationError("a fixture needs at least one mounted IMU; got none")
        for mount in mounts:
            if not isinstance(mount, MountedImu):
                raise ConfigurationError(f"`mounts` must hold MountedImu; got "
                                         f"{type(mount).__name__}")
        names = [m.name for m in mounts]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ConfigurationError(f"IMU names on a fixture must be unique; repeated: {dup}")
        object.__setattr__(self, "mounts", mounts)
        object.__setattr__(self, "rot_pm", as_rotation(self.rot_pm, "rot_pm"))

    def __len__(self) -> int:
        return len(self.mounts)

    @property
    def names(self) -> tuple[str, ...]:
        """IMU names in mount order."""
        return tuple(m.name for m in self.mounts)

    def mount(self, name: str) -> MountedImu:
        """Return the mount of the IMU called `name`."""
        for m in self.mounts:
            if m.name == name:
                return m
        raise ConfigurationError(f"no IMU named {name!r} on this fixture; have {self.names}")

    def lever_arms_p_m(self) -> NDArray[np.float64]:
        """IMU origins in the platform frame, shape (N, 3): ``rot_pm · lever_arm_m_m`` [m]."""
        arms = np.array([m.lever_arm_m_m for m in self.mounts])
        return np.asarray(self.rot_pm.apply(arms), dtype=np.float64).reshape(-1, 3)

    def rot_pb(self, name: str) -> Rotation:
        """Rotation mapping the body frame of IMU `name` into p: ``rot_pm · rot_mb``."""
        return self.rot_pm * self.mount(name).rot_mb

    def remounted(self, rot_pm: Rotation | ArrayLike) -> Fixture:
        """Return the same fixture mounted on the platform with another ``rot_pm``."""
        return dataclasses.replace(self, rot_pm=as_rotation(rot_pm, "rot_pm"))


def single_imu_fixture(lever_arm_m_m: ArrayLike = (0.0, 0.0, 0.0),
                       rot_mb: Rotation | ArrayLike | None = None, name: str = "imu0",
                       rot_pm: Rotation | ArrayLike | None = None) -> Fixture:
    """Build a fixture carrying one IMU (by default at the rotation centre, axes along m)."""
    mount = MountedImu(name, _rotation_or_identity(rot_mb, "rot_mb"),
                       np.asarray(lever_arm_m_m, dtype=float))
    return Fixture((mount,), _rotation_or_identity(rot_pm, "rot_pm"))


def hexahedral_fixture(half_edge_m: float, names: Sequence[str] | None = None,
                       rot_pm: Rotation | ArrayLike | None = None,
                       faces: Sequence[str] | None = None,
                       offsets_m: ArrayLike | None = None) -> Fixture:
    """Build the cube of P2 (docs/procedures.md): IMUs on its faces, z_b along the outward normal.

    Parameters
    ----------
    half_edge_m : float
        Half the cube's edge: the distance of each face centre from the cube's centre. [m]
    names : sequence of str, optional
        1 to :data:`~imucalib.plan.bounds.MAX_IMUS` names. Default: six IMUs ``imu_zp``,
        ``imu_zn``, … (one per face).
    rot_pm : Rotation or array_like (3, 3), optional
        The cube's mounting on the platform (a remount pose:
        :func:`imucalib.plan.fixture_poses.rot_pm_for_pose`).
    faces : sequence of str, optional
        The face of each IMU, by its outward normal (``"+z"``, ``"-z"``, ``"+y"``, ``"-y"``,
        ``"+x"``, ``"-x"``); default round robin in the order of :data:`HEXAHEDRAL_FACES`
        (IMU i on face i mod 6).
    offsets_m : array_like, shape (N, 2), optional
        Each IMU's origin relative to its face centre, along its own x_b and y_b; each component
        within ±`half_edge_m`. Default: every IMU at its face centre. [m]

    The lever arm of an IMU on face n̂ is h·n̂ + offset_x·x_b + offset_y·y_b (x_b, y_b, z_b = n̂ as
    in the module docstring's table).

    Raises
    ------
    ConfigurationError
        If the counts disagree, a face name is unknown, an offset leaves its face or two IMUs
        share a place.
    """
    h = check_positive(half_edge_m, "half_edge_m")
    chosen = _HEX_NAMES if names is None else tuple(names)
    if not 1 <= len(chosen) <= MAX_IMUS:
        raise ConfigurationError(
            f"a hexahedral fixture carries 1 to {MAX_IMUS} IMUs; got {len(chosen)} names"
        )
    n = len(chosen)
    if faces is None:
        face_index = [i % 6 for i in range(n)]
    else:
        face_names = tuple(faces)
        if len(face_names) != n:
            raise ConfigurationError(f"`faces` must have {n} entries (one per IMU); got "
                                     f"{len(face_names)}")
        unknown = sorted({f for f in face_names if f not in HEXAHEDRAL_FACE_NAMES}, key=str)
        if unknown:
            raise ConfigurationError(f"unknown cube faces {unknown}; a face is one of "
                                     f"{list(HEXAHEDRAL_FACE_NAMES)}")
        face_index = [HEXAHEDRAL_FACE_NAMES.index(f) for f in face_names]
    offsets = (np.zeros((n, 2)) if offsets_m is None
               else as_array(offsets_m, "offsets_m", shape=(n, 2)))
    outside = np.flatnonzero(np.max(np.abs(offsets), axis=1) > h * (1.0 + 1e-12))
    if outside.size:
        i = int(outside[0])
        raise ConfigurationError(
            f"IMU {chosen[i]!r}: offset ({offsets[i, 0]:g}, {offsets[i, 1]:g}) m leaves its face "
            f"(each component within ±half_edge_m {h:g} m)")
    seen: dict[tuple[int, float, float], str] = {}
    for name, k, (ox, oy) in zip(chosen, face_index, offsets, strict=True):
        other = seen.setdefault((k, float(ox), float(oy)), name)
        if other != name:
            raise ConfigurationError(
                f"IMUs {other!r} and {name!r} sit at the same place on face "
                f"{HEXAHEDRAL_FACE_NAMES[k]} (offset ({ox:g}, {oy:g}) m); give each its own "
                "`offsets_m`")
    mounts = []
    for name, k, (ox, oy) in zip(chosen, face_index, offsets, strict=True):
        normal, cols = HEXAHEDRAL_FACES[k]
        mat = np.array(cols, dtype=float).T  # columns x_b, y_b, z_b in m
        arm = h * np.array(normal) + ox * mat[:, 0] + oy * mat[:, 1]
        mounts.append(MountedImu(name, Rotation.from_matrix(mat), arm))
    return Fixture(tuple(mounts), _rotation_or_identity(rot_pm, "rot_pm"))


def array_fixture(offsets_m_m: ArrayLike, names: Sequence[str] | None = None,
                  rot_mb: Rotation | Sequence[Rotation | ArrayLike] | None = None,
                  rot_pm: Rotation | ArrayLike | None = None) -> Fixture:
    """N IMUs on a plate (or anywhere) at given offsets.

    Parameters
    ----------
    offsets_m_m : array_like, shape (N, 3)
        IMU origins in m. [m]
    names : sequence of str, optional
        N unique names; default ``imu0`` … ``imu{N−1}``.
    rot_mb : Rotation or sequence of N Rotations or 3×3 matrices, optional
        One orientation for all IMUs (a single Rotation), or one each (a Rotation array or a
        sequence); default identity.
    rot_pm : Rotation or array_like (3, 3), optional
        The plate's mounting on the platform.
    """
    offsets = as_array(offsets_m_m, "offsets_m_m", shape=(None, 3))
    n = offsets.shape[0]
    if n == 0:
        raise ConfigurationError("`offsets_m_m` must hold at least one IMU position; got none")
    chosen = tuple(f"imu{i}" for i in range(n)) if names is None else tuple(names)
    if len(chosen) != n:
        raise ConfigurationError(
            f"`names` must have {n} entries (one per offset); got {len(chosen)}"
        )
    if rot_mb is None:
        rots = [Rotation.identity()] * n
    elif isinstance(rot_mb, Rotation):
        rots = [rot_mb] * n if rot_mb.single else [rot_mb[i] for i in range(len(rot_mb))]
    else:
        rots = [as_rotation(r, f"rot_mb[{i}]") for i, r in enumerate(rot_mb)]
    if len(rots) != n:
        raise ConfigurationError(f"`rot_mb` must be one rotation or {n}; got {len(rots)}")
    mounts = tuple(MountedImu(nm, r, off) for nm, r, off in zip(chosen, rots, offsets, strict=True))
    return Fixture(mounts, _rotation_or_identity(rot_pm, "rot_pm"))
