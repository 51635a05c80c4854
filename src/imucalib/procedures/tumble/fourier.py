"""The tumble reduction: position means → Fourier coefficients → accelerometer coefficients.

docs/tumble.md, Eqs. (T.1)–(T.9). One accelerometer, M positions at gravity angles θ_k in its
IA–PA plane (a_i = g cos θ, a_p = g sin θ, a_o = 0), mean outputs y_k [m/s²] with standard
errors σ_k:

1. the Fourier fit (T.3): y_k ≈ A0 + Σ_n (A_n cos nθ_k + B_n sin nθ_k), by weighted least
   squares for any angles (:func:`fit_fourier`), or by the discrete Fourier transform for N
   equally spaced positions (:func:`fourier_dft`, (T.4)); both return the coefficients' full
   covariance and agree to rounding on the same data (the least squares by
   :func:`~imucalib.estimation.linear.solve_weighted_lsq`, whose gain K is the operator P);
2. the coefficient inversion (:func:`invert_coefficients`): the harmonics are linear in
   q = K1·(K0, 1, δ, K2−Kpp, Kip, K3, Koq), ĥ = G·q with G = P·D (T.6): D the physical design at
   the positions (T.1), P the Fourier fit's operator — so every alias of Koq's odd harmonics is
   in G exactly; q by GLS on ĥ with its covariance (the same solver), then the coefficients
   p(q) (T.7) with the covariance J·C_q·Jᵀ, J = ∂p/∂q; the χ² of both stages pooled, σ scaled
   by the Birge ratio on a misfit (:mod:`imucalib.models.fit_quality`);
3. identifiability (:func:`resolvable_coefficients`, :func:`check_identifiable`): a coefficient
   is resolved only if its signature harmonic (T.8) survives the aliasing of N positions and no
   other requested coefficient's lands on it; anything else raises
   :class:`~imucalib.errors.InsufficientExcitationError` naming the coefficients.

Contents
--------
:data:`COEFFICIENTS`, :data:`SIGNATURE_HARMONICS`, :class:`FourierFit`, :class:`TumbleFit`,
:func:`fit_fourier`, :func:`fourier_dft`, :func:`equally_spaced`, :func:`harmonic_names`,
:func:`identifiable_subset`, :func:`physical_design`,
:func:`invert_coefficients`, :func:`resolvable_coefficients`, :func:`check_identifiable`,
:func:`koq_harmonic`, :func:`closed_form_precision`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array
from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation.linear import solve_weighted_lsq
from imucalib.models.fit_quality import FitQuality, assess_fit

__all__ = [
    "COEFFICIENTS",
    "SIGNATURE_HARMONICS",
    "FourierFit",
    "TumbleFit",
    "check_identifiable",
    "closed_form_precision",
    "equally_spaced",
    "fit_fourier",
    "fourier_dft",
    "harmonic_names",
    "identifiable_subset",
    "invert_coefficients",
    "koq_harmonic",
    "physical_design",
    "resolvable_coefficients",
]

_F64 = NDArray[np.float64]

#: The coefficients of (T.1), in order: K0 [m/s²], K1 [–], delta (δ, IA towards PA) [rad],
#: K2 (K2 − Kpp) [1/(m/s²)], Kip [1/(m/s²)], K3 [1/(m/s²)²], Koq [1/(m/s²)].
COEFFICIENTS: tuple[str, ...] = ("K0", "K1", "delta", "K2", "Kip", "K3", "Koq")
#: Each coefficient's signature harmonic (T.8): (n, "cos" | "sin").
SIGNATURE_HARMONICS: dict[str, tuple[int, str]] = {
    "K0": (0, "cos"), "K1": (1, "cos"), "delta": (1, "sin"), "K2": (2, "cos"),
    "Kip": (2, "sin"), "K3": (3, "cos"), "Koq": (5, "cos")}
#: Always estimated: no tumble without bias and scale factor.
_ALWAYS = ("K0", "K1")


def koq_harmonic(n: int) -> float:
    """Return c_n of cos θ·|cos θ| = Σ c_n cos nθ: 8·(−1)^((n+1)/2)/(π·n·(n² − 4)), n odd, (T.2)."""
    if n % 2 == 0:
        return 0.0
    return 8.0 * (-1.0) ** ((n + 1) // 2) / (math.pi * n * (n * n - 4))


def harmonic_names(max_harmonic: int, n_positions: int | None = None) -> tuple[str, ...]:
    """Names of the Fourier terms up to `max_harmonic`: A0, A1, B1, A2, B2, …

    With `n_positions` equally spaced, B_{N/2} is left out (sin(N/2·θ_k) = 0 at every position).
    """
    names = ["A0"]
    for n in range(1, max_harmonic + 1):
        names.append(f"A{n}")
        if not (n_positions is not None and 2 * n == n_positions):
            names.append(f"B{n}")
    return tuple(names)


def _harmonic_design(theta: _F64, names: Sequence[str]) -> _F64:
    cols = []
    for name in names:
        n = int(name[1:])
        cols.append(np.cos(n * theta) if name[0] == "A" else np.sin(n * theta))
    return np.column_stack(cols)


@dataclass(frozen=True)
class FourierFit:
    """A fitted Fourier series of one accelerometer's position means, (T.3).

    Attributes
    ----------
    names : tuple of str
        A0, A1, B1, … in column order.
    values : ndarray, shape (k,)
        The coefficients. [m/s²]
    covariance : ndarray, shape (k, k)
        Their covariance from the means' σ. [(m/s²)²]
    operator : ndarray, shape (k, M)
        P: values = P·y (the fit is linear in the means).
    theta_rad : ndarray, shape (M,)
        The positions' gravity angles. [rad]
    chi2 : float
        Σ (r_k/σ_k)² of the series' residuals (0 when it interpolates: ν = 0).
    dof : int
        M − k.
    method : {"lsq", "dft"}
    """

    names: tuple[str, ...]
    values: _F64
    covariance: _F64
    operator: _F64
    theta_rad: _F64
    chi2: float
    dof: int
    method: str

    def value(self, name: str) -> float:
        """Return the coefficient `name`."""
        return float(self.values[self.names.index(name)])

    def std(self, name: str) -> float:
        """Its standard deviation."""
        i = self.names.index(name)
        return float(math.sqrt(self.covariance[i, i]))


def _inputs(theta_rad: ArrayLike, y: ArrayLike, sigma: ArrayLike) -> tuple[_F64, _F64, _F64]:
    """(θ, y, C): `sigma` is a σ (scalar or per mean) or the means' covariance (M, M)."""
    th = as_array(theta_rad, "theta_rad", shape=(None,))
    yy = as_array(y, "y", shape=(th.size,))
    sig = np.asarray(sigma, dtype=np.float64)
    if sig.ndim == 2:
        C = as_array(sig, "sigma", shape=(th.size, th.size))
        ok = np.allclose(C, C.T) and bool(np.all(np.linalg.eigvalsh(C) > 0))
        if not ok:
            raise InvalidInputError("`sigma` given as a covariance must be symmetric positive "
                                    "definite")
        return th, yy, C
    s = np.broadcast_to(sig, th.shape).copy()
    if not (np.all(np.isfinite(s)) and np.all(s > 0)):
        raise InvalidInputError(f"`sigma` must be positive and finite; got {s.tolist()}")
    return th, yy, np.diag(s**2)


def fit_fourier(theta_rad: ArrayLike, y: ArrayLike, sigma: ArrayLike, max_harmonic: int, *,
                n_positions: int | None = None) -> FourierFit:
    """Fit the Fourier series (T.3) up to `max_harmonic` by weighted least squares, any angles.

    Parameters
    ----------
    theta_rad : array_like, shape (M,)
        Gravity angle of each mean in the IA–PA plane. [rad]
    y : array_like, shape (M,)
        Mean outputs. [m/s²]
    sigma : float or array_like, shape (M,) or (M, M)
        Their standard errors, or their covariance (GLS). [m/s²], [(m/s²)²]
    max_harmonic : int
        Highest harmonic n fitted (cos and sin; a sine that vanishes at every position, the
        Nyquist term of equally spaced positions, is left out).
    n_positions : int, optional
        N of nominally equally spaced positions (measured angles a little off): B_{N/2} is left
        out, as in the DFT.

    Raises
    ------
    InsufficientExcitationError
        Fewer positions than terms, or terms the angles cannot separate (named).
    """
    th, yy, C = _inputs(theta_rad, y, sigma)
    if max_harmonic < 1:
        raise InvalidInputError(f"`max_harmonic` must be ≥ 1; got {max_harmonic!r}")
    names = list(harmonic_names(max_harmonic, n_positions))
    H = _harmonic_design(th, names)
    keep = np.linalg.norm(H, axis=0) > 1e-9 * math.sqrt(th.size)
    names = [n for n, k in zip(names, keep, strict=True) if k]
    H = H[:, keep]
    if H.shape[1] > th.size:
        raise InsufficientExcitationError(
            names, f"{th.size} positions cannot separate the Fourier terms {names} (up to "
            f"harmonic {max_harmonic}); fit fewer harmonics or add positions")
    sol = solve_weighted_lsq(H, yy, covariance=C, param_names=names, gain=True,
                             cond_limit=1e9, group="Fourier series",
                             context=f"Fourier design of {th.size} positions (up to harmonic "
                                     f"{max_harmonic})",
                             advice="fit fewer harmonics or add positions")
    assert sol.gain is not None  # asked for
    return FourierFit(names=tuple(names), values=sol.estimate, covariance=sol.covariance_noise,
                      operator=sol.gain, theta_rad=th, chi2=sol.chi2, dof=sol.dof, method="lsq")


def equally_spaced(theta_rad: ArrayLike, *, tol_rad: float = 1e-9) -> bool:
    """Whether the angles are N distinct positions 2π/N apart (any start), within `tol_rad`."""
    th = np.sort(np.mod(np.asarray(theta_rad, dtype=np.float64), 2 * math.pi))
    n = th.size
    if n < 2:
        return False
    gaps = np.diff(np.append(th, th[0] + 2 * math.pi))
    return bool(np.all(np.abs(gaps - 2 * math.pi / n) <= tol_rad))


def fourier_dft(theta_rad: ArrayLike, y: ArrayLike, sigma: ArrayLike, *,
                tol_rad: float = 1e-9) -> FourierFit:
    """Fit (T.3) in closed form for N equally spaced positions: the DFT, (T.4).

    A0 = (1/N)Σ y_k, A_n = (2/N)Σ y_k cos nθ_k, B_n = (2/N)Σ y_k sin nθ_k for 0 < n < N/2,
    A_{N/2} = (1/N)Σ y_k cos(N/2·θ_k): all N terms, ν = 0. The covariance is P·C·Pᵀ, C the
    means' (`sigma`: σ per mean or C itself)
    (var A0 = σ²/N, var A_n = var B_n = 2σ²/N for equal σ, (T.9)).

    Raises
    ------
    InvalidInputError
        The angles are not N distinct positions 2π/N apart (within `tol_rad`) — use
        :func:`fit_fourier`.
    """
    th, yy, C = _inputs(theta_rad, y, sigma)
    if not equally_spaced(th, tol_rad=tol_rad):
        got = np.round(np.degrees(np.mod(th, 2 * math.pi)), 6).tolist()
        raise InvalidInputError(
            f"the DFT form needs N positions equally spaced by 360°/N; got {th.size} positions "
            f"at {got} ° — use the least-squares Fourier fit (method='lsq')")
    n_pos = th.size
    names = harmonic_names(n_pos // 2, n_pos)
    rows = []
    for name in names:
        n = int(name[1:])
        w = 1.0 if n == 0 or 2 * n == n_pos else 2.0
        rows.append(w / n_pos * (np.cos(n * th) if name[0] == "A" else np.sin(n * th)))
    P = np.array(rows)
    cov = P @ C @ P.T
    return FourierFit(names=tuple(names), values=P @ yy, covariance=cov, operator=P,
                      theta_rad=th, chi2=0.0, dof=0, method="dft")


def physical_design(theta_rad: ArrayLike, gravity_mps2: float) -> _F64:
    """D of (T.1)/(T.5): columns ∂y/∂q for q = K1·(K0, 1, δ, K2, Kip, K3, Koq), shape (M, 7).

    With a_i = g cos θ and a_p = g sin θ: 1, a_i, a_p, a_i², a_i·a_p, a_i³, a_i·|a_i|.
    """
    th = np.asarray(theta_rad, dtype=np.float64)
    ai, ap = gravity_mps2 * np.cos(th), gravity_mps2 * np.sin(th)
    return np.column_stack([np.ones_like(th), ai, ap, ai**2, ai * ap, ai**3, ai * np.abs(ai)])


def resolvable_coefficients(n_positions: int) -> tuple[str, ...]:
    """Return the coefficients N equally spaced positions resolve (T.8): the default request."""
    out: list[str] = []
    for name in COEFFICIENTS:
        if not _unresolvable([*out, name], n_positions):
            out.append(name)
    return tuple(out)


def _alias(n: int, kind: str, n_positions: int) -> tuple[int, str] | None:
    """Where harmonic (n, kind) lands at N positions; None when it vanishes there."""
    m = n % n_positions
    if 2 * m > n_positions:
        m = n_positions - m
    if kind == "sin" and (m == 0 or 2 * m == n_positions):
        return None
    return (m, kind)


def _unresolvable(requested: Sequence[str], n_positions: int) -> list[str]:
    """Apply the rule of (T.8): each signature harmonic must land on a term no other one takes."""
    taken: dict[tuple[int, str], str] = {}
    bad = []
    for name in sorted(requested, key=COEFFICIENTS.index):
        where = _alias(*SIGNATURE_HARMONICS[name], n_positions)
        if where is None or where in taken:
            bad.append(name)
        else:
            taken[where] = name
    return bad


def _dependent(requested: Sequence[str], theta_rad: _F64, gravity_mps2: float) -> list[str]:
    """Return the coefficients whose column of (T.5) depends on earlier ones' (greedy rank)."""
    kept: list[_F64] = []
    bad = []
    D = physical_design(theta_rad, gravity_mps2)
    for name in sorted(requested, key=COEFFICIENTS.index):
        col = D[:, COEFFICIENTS.index(name)]
        col = col / max(float(np.linalg.norm(col)), 1e-300)
        trial = np.column_stack([*kept, col])
        # singular values of unit columns below 1e-4: dependent up to angle errors of ~10 µrad
        if np.linalg.matrix_rank(trial, tol=1e-4) < trial.shape[1]:
            bad.append(name)
        else:
            kept.append(col)
    return bad


def identifiable_subset(theta_rad: ArrayLike, gravity_mps2: float) -> tuple[str, ...]:
    """Return the coefficients the angles resolve: their columns of (T.5) are independent."""
    th = np.asarray(theta_rad, dtype=np.float64)
    bad = _dependent(COEFFICIENTS, th, gravity_mps2)
    return tuple(c for c in COEFFICIENTS if c not in bad)


def check_identifiable(requested: Sequence[str], *, n_positions: int | None = None,
                       theta_rad: ArrayLike | None = None, gravity_mps2: float = 9.80665
                       ) -> None:
    """Raise unless the positions resolve every requested coefficient, (T.8).

    With `n_positions` (N equally spaced): a coefficient's signature harmonic n, aliased onto
    |kN ± n| ≤ N/2, must land on a term no other requested coefficient takes, and must exist
    there (the sine of 0 or N/2 does not). With `theta_rad` (the actual angles): the columns of
    (T.5) must be independent; a coefficient whose column depends on the earlier ones' is named.

    Raises
    ------
    InvalidInputError
        An unknown or repeated coefficient, or K0/K1 not requested.
    InsufficientExcitationError
        The coefficients that cannot be resolved, in the order of :data:`COEFFICIENTS`.
    """
    unknown = [c for c in requested if c not in COEFFICIENTS]
    if unknown or len(set(requested)) != len(requested):
        raise InvalidInputError(f"coefficients must be distinct names of {list(COEFFICIENTS)}; "
                                f"got {list(requested)}")
    missing = [c for c in _ALWAYS if c not in requested]
    if missing:
        raise InvalidInputError(f"a tumble always estimates K0 and K1; {missing} not requested "
                                f"in {list(requested)}")
    bad: set[str] = set()
    why = []
    if n_positions is not None:
        rule = _unresolvable(requested, n_positions)
        bad.update(rule)
        if rule:
            why.append(f"{n_positions} equally spaced positions resolve harmonics up to "
                       f"{n_positions // 2} (without the sine of {n_positions / 2:g}) and "
                       f"harmonic n aliases onto |kN ± n|: they resolve "
                       f"{list(resolvable_coefficients(n_positions))}")
    if theta_rad is not None:
        th = np.asarray(theta_rad, dtype=np.float64)
        rank = _dependent(requested, th, gravity_mps2)
        bad.update(rank)
        if rank and not why:
            why.append(f"at the {th.size} positions "
                       f"{np.round(np.degrees(th), 3).tolist()} ° their terms of the model "
                       "depend on the other coefficients'")
    if bad:
        names = sorted(bad, key=COEFFICIENTS.index)
        raise InsufficientExcitationError(
            names, f"the tumble cannot resolve {names}: {'; '.join(why)}")


@dataclass(frozen=True)
class TumbleFit:
    """The coefficients of one accelerometer's tumble, (T.7), with their covariance.

    Attributes
    ----------
    names : tuple of str
        The coefficients estimated (of :data:`COEFFICIENTS`), in that order.
    values : ndarray
        SI: K0 [m/s²], K1 [–], delta [rad], K2, Kip, Koq [1/(m/s²)], K3 [1/(m/s²)²].
    covariance : ndarray
        Birge-scaled on a misfit (``covariance_noise`` the noise-only one).
    covariance_noise : ndarray
    q_names, q_values, q_covariance :
        q = K1·(K0, 1, δ, …) of (T.6) (the triad's b, 1 + M_ii, M_ip … follow from it).
    fourier : FourierFit
        The Fourier stage.
    quality : FitQuality
        χ² of both stages pooled: the Fourier series' residuals and the harmonics the
        coefficients do not explain (ν = M − p).
    harmonic_residuals : dict
        ĥ − G·q̂ per Fourier term. [m/s²]
    """

    names: tuple[str, ...]
    values: _F64
    covariance: _F64
    covariance_noise: _F64
    q_values: _F64
    q_covariance: _F64
    fourier: FourierFit
    quality: FitQuality
    harmonic_residuals: dict[str, float]

    def value(self, name: str) -> float:
        """Return the coefficient `name` (SI)."""
        return float(self.values[self.names.index(name)])

    def std(self, name: str) -> float:
        """Its standard uncertainty (Birge-scaled on a misfit)."""
        i = self.names.index(name)
        return float(math.sqrt(self.covariance[i, i]))

    def std_noise(self, name: str) -> float:
        """Its noise-only standard uncertainty."""
        i = self.names.index(name)
        return float(math.sqrt(self.covariance_noise[i, i]))


def _p_of_q(names: Sequence[str], q: _F64) -> tuple[_F64, _F64]:
    """p(q) of (T.7) and J = ∂p/∂q: K1 = q_K1, every other p = q/q_K1 (K0: q_K0/q_K1 …)."""
    k = names.index("K1")
    p = q / q[k]
    p[k] = q[k]
    J = np.diag(np.full(q.size, 1.0 / q[k]))
    J[:, k] = -q / q[k] ** 2
    J[k, :] = 0.0
    J[k, k] = 1.0
    return p, J


def invert_coefficients(fourier: FourierFit, gravity_mps2: float,
                        coefficients: Sequence[str], *, n_positions: int | None = None,
                        group: str = "tumble") -> TumbleFit:
    """Invert the Fourier coefficients to the accelerometer's coefficients, (T.6)–(T.7).

    The Fourier fit's coefficients ĥ (covariance C_h) are ĥ = G·q, G = P·D: q̂ by GLS,
    C_q = (GᵀC_h⁻¹G)⁻¹; p = p(q̂), C_p = J·C_q·Jᵀ. The χ² of the GLS (the harmonics left
    unexplained) and of the Fourier fit are pooled, ν = M − p; on a misfit (the 99 % quantile)
    C_p is scaled by the Birge ratio squared (:func:`~imucalib.models.fit_quality.assess_fit`).

    Parameters
    ----------
    fourier : FourierFit
        From :func:`fit_fourier` or :func:`fourier_dft`.
    gravity_mps2 : float
        Local gravity. [m/s²]
    coefficients : sequence of str
        Names of :data:`COEFFICIENTS` to estimate; those left out are taken as zero.
    n_positions : int, optional
        N when the positions are nominally equally spaced (measured angles a little off): the
        aliasing rule of (T.8) applies; inferred from the angles (within 1 µrad) when omitted.

    Raises
    ------
    InsufficientExcitationError
        Coefficients the positions cannot resolve (named).
    """
    names = tuple(sorted(coefficients, key=COEFFICIENTS.index))
    th = fourier.theta_rad
    n_pos = n_positions or (th.size if equally_spaced(th, tol_rad=1e-6) else None)
    check_identifiable(names, n_positions=n_pos, theta_rad=th, gravity_mps2=gravity_mps2)
    cols = [COEFFICIENTS.index(c) for c in names]
    G = fourier.operator @ physical_design(th, gravity_mps2)[:, cols]
    gls = solve_weighted_lsq(G, fourier.values, covariance=fourier.covariance, param_names=names,
                             group=group, context=f"Fourier terms {list(fourier.names)}",
                             advice=f"they cannot resolve {list(names)}: fit more harmonics")
    q, Cq = gls.estimate, gls.covariance_noise
    # the harmonics left unexplained and the series' own residuals, pooled: one χ², Eq. (6) of
    # estimation.linear on ν = M − p
    quality = assess_fit(group, gls.chi2 + fourier.chi2, fourier.dof + gls.dof)
    p, J = _p_of_q(names, q)
    Cp = J @ Cq @ J.T
    resid = fourier.values - G @ q
    return TumbleFit(names=names, values=p, covariance=Cp * quality.sigma_scale**2,
                     covariance_noise=Cp, q_values=q, q_covariance=Cq, fourier=fourier,
                     quality=quality,
                     harmonic_residuals={n: float(v) for n, v in zip(fourier.names, resid,
                                                                     strict=True)})


def closed_form_precision(sigma_mps2: float, n_positions: int, gravity_mps2: float
                          ) -> dict[str, float]:
    """Return the noise-limited σ of (T.9): N equally spaced positions, equal σ, no Koq.

    σ(A0) = σ/√N; σ(A_n) = σ(B_n) = σ·√(2/N); σ(δ) = √(2/N)·σ/g; σ(K2−Kpp) = σ(Kip) =
    2√(2/N)·σ/g²; σ(K3) = 4√(2/N)·σ/g³. SI.
    """
    r = math.sqrt(2.0 / n_positions) * sigma_mps2
    g = gravity_mps2
    return {"A0": sigma_mps2 / math.sqrt(n_positions), "A_n": r, "delta": r / g,
            "K2": 2 * r / g**2, "Kip": 2 * r / g**2, "K3": 4 * r / g**3}
