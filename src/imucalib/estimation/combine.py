"""Combine the triad parameters several tests estimated into one model of the unit.

Each classical test estimates part of a unit's triad model y = b + (I + M)·x (+ G·f, K2·x²):
the tumble the accelerometer biases, scale factors, misalignments and K2; the rate transfer
the gyro biases and scale factors; the installation test the gyro misalignments; the
g-sensitivity test G (docs/procedures.md, "Combining tests"). :func:`combine_triad_parameters`
fuses the parts by generalised least squares, treating the tests as independent:

    y = H·θ + e,   Cov e = blockdiag(C_1, …, C_k),                                   (C.1)
    θ̂ = (Hᵀ C⁻¹ H)⁻¹ Hᵀ C⁻¹ y,   Cov θ̂ = (Hᵀ C⁻¹ H)⁻¹                              (C.2)

y the stacked estimates of the parts, H the 0/1 matrix that picks each part's parameters out
of θ (the union of the names). A parameter estimated by one test only keeps its value and
variance; one estimated by two (a gyro bias from the rate transfer and from the g-sensitivity
test) gets their weighted mean, and χ² = rᵀC⁻¹r of (C.1) tests whether the tests agree
(ν = rows − parameters): a misfit (99 % quantile) is reported and the covariance scaled by the
Birge ratio, as every fit of the project does (docs/processing-estimation.md). (C.2) is solved by
the project's one weighted least-squares solver (:func:`~imucalib.estimation.linear.
solve_weighted_lsq`, generalised least squares through the Cholesky factor of the full
covariance).

The result is a :class:`~imucalib.models.result.CalibrationResult` of model ``"triad"``:
every triad that appears must be complete (its 12 bias and M names; G, K2 and K3 are optional
blocks, all nine or three of them), else :class:`~imucalib.errors.InsufficientExcitationError`
names what is missing.

Contents
--------
:class:`TriadPart`, :func:`combine_triad_parameters`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation.linear import solve_weighted_lsq
from imucalib.models.fit_quality import assess_fit
from imucalib.models.result import (
    CalibrationResult,
    Provenance,
    triad_parameter_names,
    triad_parameter_unit,
)

__all__ = ["TriadPart", "combine_triad_parameters"]


@dataclass(frozen=True)
class TriadPart:
    """The triad parameters one test estimated, with their covariance.

    Attributes
    ----------
    source : str
        The test (its procedure name, e.g. ``"tumble"``).
    names : tuple of str
        Parameter names of :mod:`imucalib.models.result` (``accel_bias_x``, ``gyro_M_xy`` …).
    values : ndarray, shape (k,)
    covariance : ndarray, shape (k, k)
    """

    source: str
    names: tuple[str, ...]
    values: NDArray[np.float64]
    covariance: NDArray[np.float64]
    details: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def of(cls, result: Any) -> TriadPart:
        """Build from a procedure result that has ``triad_parameters()``."""
        names, values, cov = result.triad_parameters()
        return cls(str(result.procedure), tuple(names), np.asarray(values, dtype=float),
                   np.asarray(cov, dtype=float))

    def __post_init__(self) -> None:
        k = len(self.names)
        v = np.asarray(self.values, dtype=float)
        c = np.asarray(self.covariance, dtype=float)
        if len(set(self.names)) != k or v.shape != (k,) or c.shape != (k, k):
            raise InvalidInputError(f"part {self.source!r}: {k} unique names need {k} values "
                                    f"and a {k}×{k} covariance; got {v.shape}, {c.shape}")
        if not (np.all(np.isfinite(v)) and np.all(np.isfinite(c))):
            raise InvalidInputError(f"part {self.source!r}: values and covariance must be "
                                    "finite")


def combine_triad_parameters(parts: Sequence[TriadPart | Any], *, sensor_id: str,
                             provenance: Provenance | None = None) -> CalibrationResult:
    """Fuse the parts into one triad CalibrationResult, Eqs. (C.1)–(C.2).

    Parameters
    ----------
    parts : sequence of TriadPart or results with ``triad_parameters()``
    sensor_id : str
        The unit.
    provenance : Provenance, optional

    Raises
    ------
    InsufficientExcitationError
        A triad that appears but lacks some of its parameters (named, with what gave the rest).
    InvalidInputError
        No parts, a name that is not a triad parameter, a covariance not positive definite.
    """
    items = [p if isinstance(p, TriadPart) else TriadPart.of(p) for p in parts]
    if not items:
        raise InvalidInputError("nothing to combine: give at least one test's parameters")
    union: list[str] = []
    for part in items:
        union += [n for n in part.names if n not in union]
    order = []
    for triad in ("accel", "gyro"):
        mine = [n for n in union if n.startswith(triad + "_")]
        if not mine:
            continue
        want = triad_parameter_names(
            triad, "triad", g_sensitivity=any("_G_" in n for n in mine),
            k2=any("_K2_" in n for n in mine), k3=any("_K3_" in n for n in mine))
        unknown = sorted(set(mine) - set(want))
        if unknown:
            raise InvalidInputError(f"not {triad} triad parameters: {unknown}")
        missing = [n for n in want if n not in mine]
        if missing:
            raise InsufficientExcitationError(
                missing, f"the {triad} triad is incomplete: no test gave {missing} (the parts "
                         f"give {sorted(mine)} from {sorted({p.source for p in items})})")
        order += list(want)
    strays = sorted(set(union) - set(order))
    if strays:
        raise InvalidInputError(f"not triad parameters: {strays}")
    rows = [(i, order.index(n)) for i, n in enumerate(n for p in items for n in p.names)]
    y = np.concatenate([p.values for p in items])
    c = np.zeros((y.size, y.size))
    at = 0
    for p in items:
        k = len(p.names)
        c[at:at + k, at:at + k] = p.covariance
        at += k
    h = np.zeros((y.size, len(order)))
    for r, j in rows:
        h[r, j] = 1.0
    # Eq. (C.2): the one weighted least-squares solver, with the parts' full covariance
    try:
        sol = solve_weighted_lsq(h, y, param_names=order, covariance=c, group="combined",
                                 context="the parts' selection matrix")
    except InvalidInputError as exc:
        raise InvalidInputError(f"the parts cannot be combined: {exc}") from exc
    theta, cov = sol.estimate, np.array(sol.covariance_noise)
    chi2, dof = sol.chi2, sol.dof
    # one group per triad, so that CalibrationResult.sigma_scale (by name prefix) applies the
    # fusion's Birge ratio to every parameter it scaled: the χ² of (C.1) is one test of all
    quality = tuple(assess_fit(triad, chi2, dof) for triad in ("accel", "gyro")
                    if any(n.startswith(triad + "_") for n in order))
    cov = 0.5 * (cov + cov.T)
    notes = [f"combined from {', '.join(p.source for p in items)} by generalised least "
             "squares (docs/procedures.md, \"Combining tests\")"]
    if dof:
        notes.append(assess_fit("combined", chi2, dof).summary())
    return CalibrationResult(
        sensor_id=sensor_id, procedure="combined", model="triad", param_names=tuple(order),
        values=theta, covariance=cov, units={n: triad_parameter_unit(n) for n in order},
        provenance=provenance or Provenance(details={"parts": [p.source for p in items]}),
        notes=tuple(notes), fit_quality=quality)
