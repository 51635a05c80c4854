"""The field calibration's accelerometer model: its form and its terms, chosen by the poses.

Step 3 of the analysis (:mod:`imucalib.procedures.field.analysis`; docs/field.md, "The
analysis, step by step" and "Model terms") decides what model the poses' mean specific forces
are fitted with, before the fit itself is used:

- **The form** (:func:`on_faces`): the nominal six-position form (F.10) when the poses hold at
  most six distinct directions, each near its own axis direction (a fixture's faces, or the twin
  station's exact remounts: the gravity-norm fit cannot see the non-orthogonality from such
  poses), else the gravity-norm fit (F.2).
- **The optional terms** of the form, each subset fitted and one chosen by the data
  (:func:`~imucalib.estimation.term_selection.choose_terms`, Eqs. (TS.1)–(TS.4)): in the
  gravity-norm form K2 (F.1′), K3 (F.1⁗, with K2, and only where the poses separate it from
  the scale factors: :data:`K3_SEPARATION_MAX`), the scale factors' temperature coefficients
  (F.1‴) by the data, the bias drift (F.1″) by rule (:data:`DRIFT_MIN_POSES`)
  (:func:`choose_gravity_norm`); in the six-position form K2 (F.12′) when all six faces and a
  seventh pose make it identifiable (:func:`choose_six_position`).
- **The pose-noise floor** (:func:`pose_noise_floor`): the bias instability between poses that
  makes the chosen fit's χ²/ν one (Paule & Mandel 1982, Eq. (PM.1) of
  :mod:`imucalib.estimation.dark_uncertainty`), estimated on request or suggested in a note.

Every function here is pure: poses in, a choice out; the analysis builds the result from it.

Contents
--------
:data:`K3_SEPARATION_MAX`, :data:`DRIFT_MIN_POSES`, :func:`on_faces`, :func:`accel_names`,
:func:`choose_gravity_norm`, :func:`choose_six_position`, :func:`pose_noise_floor`.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import CalibrationError, InsufficientExcitationError
from imucalib.estimation.term_selection import TermChoice, choose_terms

__all__ = ["DRIFT_MIN_POSES", "K3_SEPARATION_MAX", "accel_names", "choose_gravity_norm",
           "choose_six_position", "on_faces", "pose_noise_floor"]

_F64 = NDArray[np.float64]
#: K3 (F.1⁗) is a candidate only when the poses separate it from the scale factors: with it
#: no shared parameter's σ more than this many times its σ without it
#: (:func:`~imucalib.estimation.gravity_norm.k3_separation`; docs/field.md, "Model terms").
K3_SEPARATION_MAX = 2.0
#: Fewest poses with which the bias drift is fitted unless told (the accelerometer's 15
#: unknowns; the gyro's static fit uses the same rule): a rule, not the data's choice
#: (docs/field.md, "Model terms": the criteria, built on white noise, under-select a term that
#: stands for the bias's wander).
DRIFT_MIN_POSES = 20
#: Poses closer than this are the same pose (a face visited twice). [°]
_SAME_POSE_DEG = 1.0
#: A face's pose lies within this of its axis (a unit's own misalignment is ~1°). [°]
_FACE_DEG = 10.0


def on_faces(y: _F64) -> bool:
    """Whether the poses are a fixture's faces (the six-position form, F.10).

    At most six distinct directions (within 1°), each within 10° of a different axis direction.

    Parameters
    ----------
    y : ndarray, shape (n, 3)
        The poses' mean specific forces. [m/s²]
    """
    unit = y / np.linalg.norm(y, axis=1, keepdims=True)
    distinct: list[_F64] = []
    for u in unit:
        if not any(np.degrees(np.arccos(min(1.0, float(u @ d)))) <= _SAME_POSE_DEG
                   for d in distinct):
            distinct.append(u)
    axes = set()
    for u in distinct:
        k = int(np.argmax(np.abs(u)))
        if np.degrees(np.arccos(min(1.0, abs(float(u[k]))))) > _FACE_DEG:
            return False
        axes.add((k, bool(u[k] > 0)))
    return len(distinct) <= 6 and len(axes) == len(distinct)


def accel_names(terms: Collection[str], six: bool) -> list[str]:
    """Return the names of a step-3 fit's values for a term set (what (TS.4) pairs up).

    Parameters
    ----------
    terms : collection of str
        The optional terms fitted (``"k2"``, ``"k3"``, ``"drift"``, ``"temp"``).
    six : bool
        The six-position form's twelve values ``p0`` … ``p11`` (F.10) instead of the
        gravity-norm form's.
    """
    from imucalib.estimation.gravity_norm import (
        DRIFT_PARAMETERS,
        K2_PARAMETERS,
        K3_PARAMETERS,
        PARAMETERS,
        TEMPERATURE_PARAMETERS,
    )

    core = [f"p{i}" for i in range(12)] if six else list(PARAMETERS)
    return [*core, *(K2_PARAMETERS if "k2" in terms else ()),
            *(K3_PARAMETERS if "k3" in terms else ()),
            *(DRIFT_PARAMETERS if "drift" in terms else ()),
            *(TEMPERATURE_PARAMETERS if "temp" in terms else ())]


def _estimates(terms: frozenset[str], fit: Any, *, six: bool) -> tuple[list[str], _F64, _F64]:
    """Return a step-3 fit's (names, values, noise σ): what (TS.4) pairs up."""
    return accel_names(terms, six), fit.values, np.sqrt(np.diag(fit.covariance_noise))


def _summary(fit: Any) -> tuple[float, int, int]:
    """Return a fit's (χ², ν, parameter count): what the criteria of (TS.1)–(TS.3) weigh."""
    return float(fit.quality.chi2), int(fit.quality.dof), int(fit.values.size)


def choose_gravity_norm(y: _F64, sy: _F64, g: float, times: _F64, temps: _F64 | None,
                        forced: Mapping[str, bool], *, criterion: str, level: float
                        ) -> tuple[TermChoice, float]:
    """Choose the gravity-norm fit's terms: K2 (F.1′) and (F.1‴) by the data, the drift by rule.

    The scale factors' temperature coefficients (F.1‴) are a candidate when the poses have
    temperatures (`temps`); K3 (F.1⁗, with K2 only) when the poses separate it from the scale
    factors (:data:`K3_SEPARATION_MAX`). The drift (F.1″) stands for the bias's wander (its
    random walk and flicker), which the white-noise χ² the criteria are built on does not see as
    a likelihood would: left to AICc it is dropped and the accelerometer's z spread on the
    twin's grade noise rises from 1.2–1.3 to 2.1 (docs/field.md, "Model terms"). It is fitted
    with at least :data:`DRIFT_MIN_POSES` poses unless forced.

    Parameters
    ----------
    y, sy : ndarray, shape (n, 3)
        The poses' mean specific forces and their standard errors. [m/s²]
    g : float
        Local gravity. [m/s²]
    times : ndarray, shape (n,)
        The poses' mid times (the drift's regressor). [s]
    temps : ndarray, shape (n,), or None
        The poses' mean temperatures, when the log has them. [°C]
    forced : mapping of str to bool
        Terms forced in (True) or out (False); others of the group are chosen.
    criterion, level : str, float
        :func:`~imucalib.estimation.term_selection.choose_terms`'s criterion and the LRT's α.

    Returns
    -------
    choice : TermChoice
        The chosen terms, every candidate's fit quality, the model-choice σ of (TS.4).
    separation : float
        :func:`~imucalib.estimation.gravity_norm.k3_separation` at the K2 fit; NaN when not
        computed (K3 forced), inf when that fit fails.
    """
    from imucalib.estimation.gravity_norm import fit_gravity_norm, k3_separation

    optional = ("k2", "k3", "drift") if temps is None else ("k2", "k3", "drift", "temp")
    ruled = {"drift": len(y) >= DRIFT_MIN_POSES}
    separation = math.nan
    if "k3" not in forced:
        try:
            separation = k3_separation(y, sy, fit_gravity_norm(y, sy, g, k2=True).values)
        except CalibrationError:
            separation = math.inf
        ruled["k3"] = separation <= K3_SEPARATION_MAX

    def fit(t: frozenset[str]) -> Any:
        if "k3" in t and "k2" not in t:
            raise InsufficientExcitationError(
                [f"accel_K3_{a}" for a in "xyz"],
                "K3 is fitted with K2 (a cubic term without the quadratic one is no sensor's "
                "nonlinearity)")
        return fit_gravity_norm(y, sy, g, k2="k2" in t, k3="k3" in t,
                                times_s=times if "drift" in t else None,
                                temperatures_degc=temps if "temp" in t else None)

    choice, _, _ = choose_terms(
        "accel (gravity norm)", optional, fit, _summary,
        forced={k: v for k, v in forced.items() if k in optional},
        ruled=ruled, criterion=criterion, level=level,
        estimates=lambda t, f: _estimates(t, f, six=False))
    return choice, separation


def choose_six_position(y: _F64, sy: _F64, g: float, sg: float, forced: Mapping[str, bool], *,
                        criterion: str, level: float) -> tuple[TermChoice, Any]:
    """Choose the six-position fit's K2 (F.12′) by the data; return the choice and its fit.

    K2 is a candidate when all six faces and a seventh pose make it identifiable.

    Parameters
    ----------
    y, sy : ndarray, shape (n, 3)
        The poses' mean specific forces and their standard errors. [m/s²]
    g, sg : float
        Local gravity and its standard uncertainty. [m/s²]
    forced : mapping of str to bool
        ``"k2"`` forced in or out, if present.
    criterion, level : str, float
        :func:`~imucalib.estimation.term_selection.choose_terms`'s criterion and the LRT's α.
    """
    from imucalib.estimation.six_position import fit_six_position, nominal_directions

    directions = nominal_directions(y)
    can_k2 = len({tuple(d) for d in directions.tolist()}) == 6 and len(directions) >= 7

    def fit(terms: frozenset[str]) -> Any:
        if "k2" in terms and not can_k2:
            raise InsufficientExcitationError(
                ["accel_K2"], "K2 in the six-position form needs all six faces and a seventh "
                              "pose")
        return fit_six_position(y, sy, directions, g, gravity_std_mps2=sg, k2="k2" in terms)

    choice, chosen, _ = choose_terms(
        "accel (six-position)", ("k2",), fit, _summary,
        forced={k: v for k, v in forced.items() if k == "k2"},
        criterion=criterion, level=level,
        estimates=lambda t, f: _estimates(t, f, six=True))
    return choice, chosen


def pose_noise_floor(y: _F64, sy: _F64, g: float, form: str, k2: bool, times: _F64 | None,
                     gravity_std_mps2: float, temps: _F64 | None = None,
                     k3: bool = False) -> float:
    """Return the accelerometer's pose-noise floor by Paule–Mandel (Eq. (PM.1)) for the form.

    The floor s ≥ 0 that, added in quadrature to every pose's standard error, makes the chosen
    fit's χ²/ν one (:func:`~imucalib.estimation.dark_uncertainty.paule_mandel_floor`); 0 when
    the poses scatter no more than their white noise says.

    Parameters
    ----------
    y, sy : ndarray, shape (n, 3)
        The poses' mean specific forces and their standard errors. [m/s²]
    g : float
        Local gravity. [m/s²]
    form : {"gravity-norm", "six-position"}
        The accelerometer's form; `k2`, `k3`, `times` (the drift) and `temps` its terms.
    gravity_std_mps2 : float
        Local gravity's standard uncertainty (the six-position form's). [m/s²]
    """
    from imucalib.estimation.dark_uncertainty import paule_mandel_floor
    from imucalib.estimation.gravity_norm import fit_gravity_norm
    from imucalib.estimation.six_position import fit_six_position, nominal_directions

    if form == "gravity-norm":
        def chi2_of(s: float) -> tuple[float, int]:
            q = fit_gravity_norm(y, np.hypot(sy, s), g, k2=k2, k3=k3, times_s=times,
                                 temperatures_degc=temps).quality
            return float(q.chi2), int(q.dof)
    else:
        directions = nominal_directions(y)

        def chi2_of(s: float) -> tuple[float, int]:
            q = fit_six_position(y, np.hypot(sy, s), directions, g,
                                 gravity_std_mps2=gravity_std_mps2, k2=k2).quality
            return float(q.chi2), int(q.dof)
    return paule_mandel_floor(chi2_of, scale=float(np.median(sy)))
