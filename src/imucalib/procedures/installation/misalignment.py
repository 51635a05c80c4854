"""The installation (misalignment) errors of a gyro triad from ±ω turns about each axis.

Pure maths on whole-revolution means (docs/installation.md, eqs. (IN-1)–(IN-4)). With body
axis k up and the table turning at ω about it, the input is x = (ω + Ω_U)·e_k (the horizontal
Earth rate cancels over whole revolutions) and gyro i reads, by the triad model y = b + (I + M)·x
(IEEE Std 952-2020 / 1431-2004), ȳ_i = b_i + G_ik·g + (δ_ik + M_ik)·x.

Closed form (IN-2), the MIMU chapter's (docs/procedures.md): over a +ω and a −ω turn of n
whole revolutions each (2π·n = 360°·n turned), the integrated angles Θ_i± = ȳ_i±·T± (IN-1) give
θ_ik = (Θ_i₊ − Θ_i₋)/(2·2π·n): the bias and the g-sensitivity cancel in the difference and so
does Ω_U (equal spans). Written with the spans' own turned angles Φ± (±2π·n±) it is
θ_ik = (Θ_i₊/T₊ − Θ_i₋/T₋)/(Φ₊/T₊ − Φ₋/T₋), the same number when n₊ = n₋, T₊ = T₋ and
exact when they differ; the diagonal gives 1 + M_kk. Several rate magnitudes: their closed
forms are averaged with weights 1/σ².

Least squares (IN-3): for each gyro i, y_i − x_i = c_i,p + Σ_k M_ik·x_k over all turns, c_i,p
one constant per pose p (b_i + G_ip·g: the g-sensitivity changes with the axis up), weighted
by 1/σ²; with ``common_bias=True`` one b_i for all poses (G·g neglected) and more degrees of
freedom. Each gyro's fit is solved by :func:`~imucalib.estimation.linear.solve_weighted_lsq`;
χ²/ν of the three fits pooled scales σ by the Birge ratio on a misfit (IN-4).

Contents
--------
:class:`Misalignment`, :func:`closed_form_misalignment`, :func:`lsq_misalignment`
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import MissingSegmentError
from imucalib.estimation.linear import solve_weighted_lsq
from imucalib.models.fit_quality import FitQuality, assess_fit
from imucalib.procedures.common.rate_windows import RateWindow

__all__ = ["Misalignment", "closed_form_misalignment", "lsq_misalignment"]

_F64 = NDArray[np.float64]
_INDEX = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class Misalignment:
    """M (row: gyro, column: input axis) of the tested columns, and its covariance.

    Attributes
    ----------
    matrix : ndarray (3, 3)
        M_ik; NaN in the columns of axes not tested.
    cov : ndarray (9, 9)
        Covariance of M flattened row-major (M_xx, M_xy, …).
    quality : FitQuality or None
        χ²/ν of the least-squares form; None for the closed form.
    """

    matrix: _F64
    cov: _F64
    quality: FitQuality | None = None

    @property
    def std(self) -> _F64:
        """σ of every M_ik, (3, 3)."""
        return np.sqrt(np.diag(self.cov)).reshape(3, 3)


def _pairs(windows: Sequence[RateWindow]
           ) -> dict[str, list[tuple[RateWindow, RateWindow]]]:
    """Pair each axis's +ω and −ω turns of equal magnitude (commanded)."""
    out: dict[str, list[tuple[RateWindow, RateWindow]]] = {}
    for axis in sorted({w.axis for w in windows}):
        mine = [w for w in windows if w.axis == axis]
        mags = sorted({abs(w.commanded_rate_dps) for w in mine})
        for mag in mags:
            plus = [w for w in mine if w.commanded_rate_dps == mag]
            minus = [w for w in mine if w.commanded_rate_dps == -mag]
            if not plus or not minus:
                raise MissingSegmentError(
                    f"axis {axis}: the {'+' if not plus else '−'}{mag:g} °/s turn is missing; "
                    "the closed form needs a +ω and a −ω turn of each magnitude")
            out.setdefault(axis, []).append((plus[0], minus[0]))
    return out


def closed_form_misalignment(windows: Sequence[RateWindow], earth_up_rps: float
                             ) -> Misalignment:
    """Return M from the ± turns by the closed form (IN-2) (module docstring).

    Raises
    ------
    MissingSegmentError
        An axis with a +ω turn and no −ω turn of the same magnitude (or the reverse).
    """
    matrix = np.full((3, 3), np.nan)
    var = np.full((3, 3), np.nan)
    for axis, pairs in _pairs(windows).items():
        k = _INDEX[axis]
        ests, ws = [], []
        for p, m in pairs:
            # (Θ₊/T₊ − Θ₋/T₋)/(Φ₊/T₊ − Φ₋/T₋): Θ/T the mean, Φ/T the table rate
            den = p.table_rate_rps - m.table_rate_rps
            est = (p.angle_rad / p.duration_s - m.angle_rad / m.duration_s) / den
            se = np.hypot(p.gyro_se_rps, m.gyro_se_rps) / abs(den)
            ests.append(est)
            ws.append(1.0 / se ** 2)
        w = np.array(ws)
        matrix[:, k] = np.sum(np.array(ests) * w, axis=0) / np.sum(w, axis=0)
        var[:, k] = 1.0 / np.sum(w, axis=0)
        matrix[k, k] -= 1.0
    return Misalignment(matrix=matrix, cov=np.diag(var.ravel()))


def lsq_misalignment(windows: Sequence[RateWindow], earth_up_rps: float, *,
                     common_bias: bool = False) -> Misalignment:
    """Return M from the general least-squares form (IN-3) (module docstring).

    Raises
    ------
    InsufficientExcitationError
        An input axis turned at one rate only (its column and the pose constant coincide).
    """
    axes = sorted({w.axis for w in windows}, key=_INDEX.__getitem__)
    cols = [_INDEX[a] for a in axes]
    x = np.zeros((len(windows), 3))
    for j, w in enumerate(windows):
        x[j, _INDEX[w.axis]] = w.table_rate_rps + earth_up_rps
    if common_bias:
        consts = np.ones((len(windows), 1))
    else:
        consts = np.array([[1.0 if w.axis == a else 0.0 for a in axes] for w in windows])
    design = np.column_stack([consts, x[:, cols]])
    matrix = np.full((3, 3), np.nan)
    cov = np.zeros((9, 9))
    chi2, dof = 0.0, 0
    covs = []
    nc = consts.shape[1]
    for i in range(3):
        s = "xyz"[i]
        names = [f"gyro_{s}_constant" + ("" if common_bias else f"_{ax}") for ax in axes[:nc]]
        names += [f"gyro_M_{s}{ax}" for ax in axes]
        fit = solve_weighted_lsq(
            design, np.array([w.gyro_mean_rps[i] for w in windows]) - x[:, i],
            sigma=np.array([w.gyro_se_rps[i] for w in windows]), param_names=names,
            context=f"gyro {s} misalignment design",
            advice="the turns cannot separate the pose constants from M (each axis needs "
                   "turns at two rates or more, e.g. +ω and −ω)")
        chi2 += fit.chi2
        dof += fit.dof
        matrix[i, cols] = fit.estimate[nc:]
        covs.append(fit.covariance_noise[nc:, nc:])
    # the three axes' fits pooled: one χ², the misfit rule of estimation.linear (Eq. (6))
    quality = assess_fit("gyro misalignment", chi2, dof)
    for i, c in enumerate(covs):
        idx = [3 * i + k for k in cols]
        cov[np.ix_(idx, idx)] = c * quality.sigma_scale ** 2
    return Misalignment(matrix=matrix, cov=cov, quality=quality)
