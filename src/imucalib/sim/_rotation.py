"""Vectorised unit-quaternion arithmetic on plain arrays (private).

The public API of :mod:`imucalib.sim` returns :class:`scipy.spatial.transform.Rotation` objects,
but composing and applying millions of rotations through ``Rotation`` is slow (SciPy 1.17:
composing two arrays of 3.6·10⁶ rotations takes about 2.4 s, applying one to as many vectors
about 0.8 s), so the table chain and the kinematics work on quaternion arrays here and wrap the
result once with :meth:`Rotation.from_quat`. :func:`evaluate_chain` evaluates the rate-table
chain of :mod:`imucalib.sim.table`.

Layout is **component-major** for speed: a quaternion array has shape (4, n) with rows
``x, y, z, w`` (scalar last, as in SciPy), a vector array shape (3, n); a constant vector may be
given as shape (3,) and a constant quaternion as (4, 1). Products are in the Hamilton convention:
``quat_mul(q1, q2)`` is the rotation ``R(q1)·R(q2)`` (``q2`` applied first), like
``Rotation(q1) * Rotation(q2)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["cross", "evaluate_chain", "quat_conj", "quat_mul", "quat_rotate"]

_F64 = NDArray[np.float64]
_BLOCK = 1 << 16  # samples per block (keeps temporaries small and in cache)


def cross(a: _F64, b: _F64) -> _F64:
    """Cross product of component-major vectors, shape (3, n) (or broadcastable)."""
    return np.array((a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]))


def quat_mul(q1: _F64, q2: _F64) -> _F64:
    """Hamilton product ``q1 ⊗ q2`` (rotation ``R(q1)·R(q2)``), shape (4, n)."""
    x1, y1, z1, w1 = q1
    x2, y2, z2, w2 = q2
    return np.array((
        w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
        w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
        w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
    ))


def quat_conj(q: _F64) -> _F64:
    """Conjugate (the inverse rotation of a unit quaternion)."""
    return np.array((-q[0], -q[1], -q[2], q[3]))


def quat_rotate(q: _F64, v: _F64) -> _F64:
    """Apply the rotations `q` (4, n) to vectors `v` (3, n) or (3,): ``v' = R(q)·v``."""
    vv = v if v.ndim == 2 else v[:, None]
    u, w = q[:3], q[3]
    t = 2.0 * cross(u, vv)
    return vv + w * t + cross(u, t)


def evaluate_chain(geometry: Sequence[tuple[_F64, _F64, float, float]], th: _F64, thd: _F64,
                   thdd: _F64) -> tuple[_F64, _F64, _F64]:
    """Attitude and angular motion of a chain of tilted, wobbling axes (:mod:`imucalib.sim.table`).

    Parameters
    ----------
    geometry : sequence of (n, u1, δ, W)
        Per axis, outer first: nominal axis n (3,) and tilt axis u1 ⟂ n (3,) in the parent
        frame, fixed tilt δ [rad] and wobble amplitude W [rad]; the axis turns the child frame
        by J(θ) = R_u1(δ)·R_w(θ)·R_n(θ), w(θ) = W·(cos 2θ·u1 + sin 2θ·n × u1).
    th, thd, thdd : ndarray, shape (n, len(geometry))
        Axis angles, rates and accelerations.

    Returns
    -------
    q : ndarray, shape (n, 4)
        Quaternions of rot_tp (scalar last).
    omega_p, alpha_p : ndarray, shape (n, 3)
        Angular rate and acceleration of p relative to t, in p.
    """
    n = th.shape[0]
    # Evaluate once per run of identical rows (a static record is a single run).
    change = np.zeros(n, dtype=bool)
    change[:1] = True
    for col in (*th.T, *thd.T, *thdd.T):
        change[1:] |= col[1:] != col[:-1]
    starts = np.flatnonzero(change)
    if starts.size <= n // 4:
        counts = np.diff(np.append(starts, n))
        q, om, al = _chain(geometry, th[starts], thd[starts], thdd[starts])
        return np.repeat(q, counts, axis=0), np.repeat(om, counts, axis=0), np.repeat(
            al, counts, axis=0)
    q, om, al = np.empty((n, 4)), np.empty((n, 3)), np.empty((n, 3))
    for s in range(0, n, _BLOCK):
        e = min(s + _BLOCK, n)
        q[s:e], om[s:e], al[s:e] = _chain(geometry, th[s:e], thd[s:e], thdd[s:e])
    return q, om, al


def _chain(geometry: Sequence[tuple[_F64, _F64, float, float]], th: _F64, thd: _F64,
           thdd: _F64) -> tuple[_F64, _F64, _F64]:
    """Evaluate the chain of elementary rotations on one block; outputs (m, 4), (m, 3), (m, 3).

    With P_j the product of the first j elementary rotations (axes κ_j, angles q_j), in t:
    ω = Σ_j P_{j−1}κ_j·q̇_j and α = Σ_j [P_{j−1}κ_j·q̈_j + ω_{<j} × P_{j−1}κ_j·q̇_j].
    """
    m = th.shape[0]
    # Elementary rotations: (axis κ, sin and cos of half the angle, rate, accel); a None rate
    # marks a constant rotation. R_w(θ)·R_n(θ) = R_n(2θ)·R_u1(W)·R_n(−θ) for a wobbling axis.
    elements: list[tuple[_F64, _F64 | float, _F64 | float, _F64 | None, _F64 | None]] = []
    for i, (k, u1, tilt, w) in enumerate(geometry):
        if tilt != 0.0:
            elements.append((u1, math.sin(0.5 * tilt), math.cos(0.5 * tilt), None, None))
        half = 0.5 * th[:, i]
        s, c = np.sin(half), np.cos(half)
        if w > 0.0:
            elements.append((k, 2.0 * s * c, c * c - s * s, 2.0 * thd[:, i], 2.0 * thdd[:, i]))
            elements.append((u1, math.sin(0.5 * w), math.cos(0.5 * w), None, None))
            elements.append((k, -s, c, -thd[:, i], -thdd[:, i]))
        else:
            elements.append((k, s, c, thd[:, i], thdd[:, i]))
    q: _F64 | None = None
    omega = np.zeros((3, m))
    alpha = np.zeros((3, m))
    for kappa, sin_half, cos_half, rate, acc in elements:
        if rate is not None and acc is not None:
            kt = np.broadcast_to(kappa[:, None], (3, m)) if q is None else quat_rotate(q, kappa)
            if q is not None:
                alpha += cross(omega, kt) * rate
            alpha += kt * acc
            omega += kt * rate
        qe = np.empty((4, m) if np.ndim(sin_half) else (4, 1))
        qe[:3] = kappa[:, None] * sin_half
        qe[3] = cos_half
        q = qe if q is None else quat_mul(q, qe)
    if q is None:
        q = np.zeros((4, m))
        q[3] = 1.0
        return q.T, omega.T, alpha.T
    q = np.broadcast_to(q, (4, m))
    qc = quat_conj(q)
    return q.T, quat_rotate(qc, omega).T, quat_rotate(qc, alpha).T
