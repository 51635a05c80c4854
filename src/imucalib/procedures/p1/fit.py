"""P1 estimation: the accelerometer and gyro models fitted to window observations.

Models (``model`` argument)
---------------------------
``"per-axis"`` — the procedure's own model (docs/p1.md, steps 1 and 3), cross-coupling
neglected, per axis i:
    accelerometer  a_out,i = K_i·(a_ref,i + b_i), from the six positions;
    gyro           ω_out,i = K_i·(ω_ref,i + b_i), from the rate points turning about axis i and the
    static windows (whose reference is the Earth-rate projection, so b_i excludes Earth rate).
    Each axis is the straight-line fit y = K·x + c with c = K·b (weighted least squares), and
    (K, b) with covariance J·C·Jᵀ, J = ∂(K, b)/∂(K, c) = [[1, 0], [−c/K², 1/K]].
``"triad"`` — the full linear triad model of :class:`~imucalib.models.triad.TriadModel`:
    accelerometer  y = b + (I + M)·f (+ K2⊙f⊙f)  (12 parameters, 15 with K2; six positions)
    gyro           y = b + (I + M)·ω (+ G·f)     (21 parameters with g-sensitivity, else 12)
    as z = y − x = b + M·x (+ K2⊙x⊙x) (+ G·f), rows ordered by window then axis, built by
    :func:`~imucalib.estimation.designs.build_design` (docs/p1.md). The optional terms
    (:data:`TERMS`: the accelerometer's K2, Eq. (P1.K2) of docs/p1.md, and the gyro's G) are
    chosen per triad by the data (:func:`choose_triad_terms`,
    :func:`~imucalib.estimation.term_selection.choose_terms`, Eqs. (TS.1)–(TS.4)) unless
    forced; the chosen model's covariance as reported (:attr:`P1Fit.covariance`) carries the
    model choice's Type B of (TS.4).

Observations are window means weighted by their standard errors (correlated noise included), so
the covariance is not rescaled by the residuals (known noise); the fit's χ² then tests the model.
The estimates and covariances come from
:func:`~imucalib.estimation.linear.solve_weighted_lsq` (rank and conditioning checked: a design
that cannot determine a parameter raises InsufficientExcitationError naming it).

Contents
--------
:func:`fit_p1`, :func:`fit_triad`, :func:`choose_triad_terms`, :class:`P1Fit`,
:class:`TriadFit`, :func:`predict_outputs`, :data:`TERMS`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from imucalib import units
from imucalib.conventions import AXES
from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation import compute_window_mean_covariance, solve_weighted_lsq
from imucalib.estimation.designs import build_design
from imucalib.estimation.term_selection import TermChoice, choose_terms
from imucalib.models.noise import NoiseModel
from imucalib.models.result import triad_parameter_names
from imucalib.procedures.p1.windows import P1Observations, WindowObservation

__all__ = [
    "MIN_EXCITATION",
    "TERMS",
    "P1Fit",
    "TriadFit",
    "choose_triad_terms",
    "fit_p1",
    "fit_triad",
    "gyro_windows",
    "observation_covariance",
    "predict_outputs",
]

_F64 = NDArray[np.float64]

#: The optional terms of P1's triad fits (docs/p1.md, "Model terms"), per triad: the
#: accelerometer's quadratic scale factor K2 (P1.K2), the gyro's g-sensitivity G.
OPTIONAL_TERMS: dict[str, tuple[str, ...]] = {"accel": ("k2",), "gyro": ("g",)}
#: Every optional term, as ``terms="+k2,-g"`` names them.
TERMS = ("k2", "g")
#: The groups of :func:`choose_triad_terms`, as the notes and ``model_selection`` name them.
_GROUPS = {"accel": "accel (six positions)", "gyro": "gyro (rate points and statics)"}


@dataclass(frozen=True, eq=False)
class TriadFit:
    """One triad's fit: names, estimate, covariance, design blocks and the fit's χ².

    ``covariance`` is the fit's own (the noise's); ``choice``, when the terms were chosen
    (:func:`choose_triad_terms`), the choice with the model-choice σ of (TS.4) per parameter,
    which :attr:`model_variance` returns in parameter order.
    """

    triad: str
    model: str
    param_names: tuple[str, ...]
    estimate: _F64
    covariance: _F64
    chi2: float
    dof: int
    H: _F64
    z: _F64
    sigma: _F64
    windows: tuple[WindowObservation, ...]
    choice: TermChoice | None = None

    @property
    def model_variance(self) -> _F64:
        """u²_model of (TS.4) per parameter (zeros without a choice or where it adds none)."""
        std = {} if self.choice is None else self.choice.model_std
        return np.array([std.get(n, 0.0) ** 2 for n in self.param_names])


@dataclass(frozen=True, eq=False)
class P1Fit:
    """Both triads' fits of one set of windows (one repetition or all)."""

    model: str
    accel: TriadFit
    gyro: TriadFit

    @property
    def param_names(self) -> tuple[str, ...]:
        """Accelerometer names, then gyro names."""
        return (*self.accel.param_names, *self.gyro.param_names)

    @property
    def estimate(self) -> _F64:
        """All estimates, in :attr:`param_names` order (the accelerometer's K2 as (P1.K2′))."""
        return np.concatenate([_k2_on_output(self.accel)[0], self.gyro.estimate])

    @property
    def covariance(self) -> _F64:
        """Block-diagonal covariance (the triads' fits are independent), with (TS.4)'s u²_model.

        The model choice's Type B (:attr:`TriadFit.model_variance`) is added on the diagonal:
        a term the data left out leaves the parameters it shares with the larger model the σ
        of that model (docs/p1.md, "Model terms").
        """
        na, ng = self.accel.estimate.size, self.gyro.estimate.size
        cov = np.zeros((na + ng, na + ng))
        cov[:na, :na] = _k2_on_output(self.accel)[1] + np.diag(self.accel.model_variance)
        cov[na:, na:] = self.gyro.covariance + np.diag(self.gyro.model_variance)
        return cov

    @property
    def selection(self) -> tuple[TermChoice, ...]:
        """Each triad's choice of optional terms (empty for the per-axis model)."""
        return tuple(t.choice for t in (self.accel, self.gyro) if t.choice is not None)


def _k2_on_output(fit: TriadFit) -> tuple[_F64, _F64]:
    """Return the accelerometer's estimate and covariance with K2 as the result means it.

    The design (:func:`~imucalib.estimation.designs.build_design`) fits K2 on the input,
    K2ᵢ·fᵢ² (P1.K2); the result's model (:class:`~imucalib.models.triad.TriadModel`, the
    correction) applies it to the scaled input u = (I + M)·f, K2ᵢ·uᵢ². At the positions that
    see K2 (axis i up and down) uᵢ = (1 + M_ii)·fᵢ, so

        K2ᵢ(u) = K2ᵢ(f) / (1 + M_ii)²                                              (P1.K2′)

    with the covariance carried by its Jacobian (∂/∂K2ᵢ = (1 + M_ii)⁻², ∂/∂M_ii =
    −2·K2ᵢ/(1 + M_ii)³). Left as fitted, a consumer unit's K2 (10³ µg/g², M_ii ~ 10⁻²) sat
    2 % off: z RMS 1.28 over 200 twin seeds, 0.97 with it. Other fits: unchanged.
    """
    names = fit.param_names
    if f"{fit.triad}_K2_x" not in names:
        return fit.estimate, fit.covariance
    est = fit.estimate.copy()
    jac = np.eye(est.size)
    for a in AXES:
        k, m = names.index(f"{fit.triad}_K2_{a}"), names.index(f"{fit.triad}_M_{a}{a}")
        scale = 1.0 + fit.estimate[m]
        est[k] = fit.estimate[k] / scale**2
        jac[k, k] = 1.0 / scale**2
        jac[k, m] = -2.0 * fit.estimate[k] / scale**3
    return est, jac @ fit.covariance @ jac.T


def observation_covariance(windows: Sequence[WindowObservation], noise: NoiseModel | None
                           ) -> _F64 | None:
    """Return the covariance of the window means per axis, shape (3, K, K), or None.

    With a noise model, flicker and random-walk noise shared by windows that follow each other
    correlate their means (:func:`~imucalib.estimation.compute_window_mean_covariance`); the
    slowly varying flicker state common to all windows is included, so a fitted bias carries
    it in its uncertainty.
    """
    if noise is None or not windows:
        return None
    starts = np.array([w.t_start_s for w in windows])
    durations = np.maximum(np.array([w.duration_s for w in windows]), 1e-3)
    order = np.argsort(starts, kind="stable")
    ref = float(starts.min())
    cov = np.empty((3, len(windows), len(windows)))
    sorted_cov = compute_window_mean_covariance(noise, starts[order], durations[order],
                                                reference_time_s=ref)
    inv = np.argsort(order)
    for i in range(3):
        cov[i] = sorted_cov[i][np.ix_(inv, inv)]
    return cov


def _stack_covariance(cov: _F64) -> _F64:
    """(3, K, K) per-axis covariances → (3K, 3K) for rows ordered window, then axis."""
    k = cov.shape[1]
    full = np.zeros((3 * k, 3 * k))
    for i in range(3):
        full[i::3, i::3] = cov[i]
    return full


def _per_axis_fit(triad: str, x: _F64, y: _F64, se: _F64, masks: Sequence[NDArray[np.bool_]],
                  windows: tuple[WindowObservation, ...], obs_cov: _F64 | None) -> TriadFit:
    names = triad_parameter_names(triad, "per-axis")
    est = np.zeros(6)
    cov = np.zeros((6, 6))
    chi2, dof = 0.0, 0
    H_all, z_all, s_all = [], [], []
    for i, axis in enumerate(AXES):
        sel = masks[i]
        if np.count_nonzero(sel) < 2 or np.ptp(x[sel, i]) == 0.0:
            raise InsufficientExcitationError(
                (f"{triad}_K_{axis}", f"{triad}_b_{axis}"),
                f"the per-axis {triad} model needs at least two different inputs on axis "
                f"{axis}; the windows give {np.count_nonzero(sel)}: {triad}_K_{axis} and "
                f"{triad}_b_{axis} are unobservable")
        H = np.column_stack([x[sel, i], np.ones(np.count_nonzero(sel))])
        sol = solve_weighted_lsq(
            H, y[sel, i], param_names=(f"K_{axis}", f"c_{axis}"), scale_covariance=False,
            covariance=None if obs_cov is None else obs_cov[i][np.ix_(sel, sel)],
            sigma=se[sel, i] if obs_cov is None else None)
        k, c = sol.estimate
        J = np.array([[1.0, 0.0], [-c / k**2, 1.0 / k]])
        est[i], est[3 + i] = k, c / k
        c2 = J @ sol.covariance @ J.T
        cov[np.ix_([i, 3 + i], [i, 3 + i])] = c2
        chi2 += sol.chi2
        dof += sol.dof
        H_all.append(H)
        z_all.append(y[sel, i])
        s_all.append(se[sel, i])
    return TriadFit(triad, "per-axis", names, est, cov, chi2, dof, np.zeros((0, 0)),
                    np.concatenate(z_all), np.concatenate(s_all), windows)


def _triad_fit(triad: str, x: _F64, y: _F64, se: _F64, f: _F64 | None,
               windows: tuple[WindowObservation, ...], cov: _F64 | None,
               k2: bool = False) -> TriadFit:
    terms = ["bias", "scale_misalignment"]
    if f is not None:
        terms.append("g_sensitivity")
    if k2:  # after G: the result's order (models.result.triad_parameter_names)
        terms.append("k2")
    design = build_design(x, terms, specific_force_b=f)
    H = np.array(design.H)
    names = [f"{triad}_{n}" for n in design.param_names]
    z = (y - x).ravel()
    sigma = se.ravel()
    sol = solve_weighted_lsq(H, z, param_names=names, scale_covariance=False,
                             covariance=None if cov is None else _stack_covariance(cov),
                             sigma=sigma if cov is None else None)
    return TriadFit(triad, "triad", tuple(names), np.asarray(sol.estimate),
                    np.asarray(sol.covariance), float(sol.chi2), int(sol.dof), H, z, sigma,
                    windows)


def gyro_windows(obs: P1Observations, role: str, repetitions: Sequence[int] | None
                 ) -> list[WindowObservation]:
    """Rate points and static windows (six positions, bias record) of a role."""
    out = []
    for w in obs.select(role=role):
        if repetitions is not None and w.repetition not in repetitions:
            continue
        if w.kind == "rate" or "six-position" in w.tags or "gyro-bias" in w.tags:
            out.append(w)
    return out


#: Least input an axis must see for the parameters that multiply it to count as excited:
#: half a g for an accelerometer, 1 °/s for a gyro (Earth rate alone, 0.004 °/s, is not enough).
MIN_EXCITATION = {"accel": 0.5 * units.G0_MPS2, "gyro": 1.0 * units.DEG}


def _check_excitation(triad: str, model: str, x: _F64) -> None:
    """Refuse a design whose inputs never reach an axis (the parameters would rest on noise)."""
    if x.shape[0] == 0:
        raise InsufficientExcitationError(
            triad_parameter_names(triad, model),
            f"no {triad} calibration windows: every {triad} parameter is unobservable")
    peak = np.abs(x).max(axis=0)
    limit = MIN_EXCITATION[triad]
    weak = [j for j in range(3) if peak[j] < limit]
    if not weak:
        return
    if model == "per-axis":
        names = [n for j in weak for n in (f"{triad}_K_{AXES[j]}", f"{triad}_b_{AXES[j]}")]
    else:
        names = [f"{triad}_M_{i}{AXES[j]}" for j in weak for i in AXES]
    unit, scale = ("g", units.G0_MPS2) if triad == "accel" else ("°/s", units.DEG)
    detail = ", ".join(f"{AXES[j]}: {peak[j] / scale:.3g} {unit}" for j in weak)
    raise InsufficientExcitationError(
        names, f"the windows never excite the {triad} input axis/axes {detail} (at least "
        f"{limit / scale:g} {unit} needed); {', '.join(names)} are unobservable"
        + (" — add rate points about that axis (the P1 plan's z_rates)" if triad == "gyro"
           else " — add the positions that put that axis up and down"))


def fit_triad(triad: Literal["accel", "gyro"], windows: Sequence[WindowObservation], *,
              model: str = "triad", noise: NoiseModel | None = None,
              g_sensitivity: bool = False, k2: bool = False) -> TriadFit:
    """Fit one triad's model to windows (module docstring).

    Parameters
    ----------
    triad : {"accel", "gyro"}
    windows : sequence of WindowObservation
        Accelerometer: static windows (reference specific force). Gyro: rate points and static
        windows (reference rate incl. Earth rate; specific force for G).
    model : {"triad", "per-axis"}
    noise : NoiseModel, optional
        With it the window means are weighted with their full covariance; else with their
        standard errors alone.
    g_sensitivity : bool
        Gyro triad model: estimate G.
    k2 : bool
        Accelerometer triad model: estimate K2 (P1.K2 of docs/p1.md).

    Raises
    ------
    InsufficientExcitationError
        If the windows cannot determine a parameter; the message names it.
    InvalidInputError
        An unknown model, or K2 asked of the gyro or of the per-axis model.
    """
    w = tuple(windows)
    accel = triad == "accel"
    if k2 and (not accel or model != "triad"):
        raise InvalidInputError("K2 is a term of the accelerometer's triad model only "
                                "(docs/p1.md, \"Model terms\")")
    x = np.array([o.force_b_mps2 if accel else o.rate_b_rps for o in w]).reshape(-1, 3)
    y = np.array([o.accel_mean_mps2 if accel else o.gyro_mean_rps for o in w]).reshape(-1, 3)
    se = np.array([o.accel_se_mps2 if accel else o.gyro_se_rps for o in w]).reshape(-1, 3)
    f = np.array([o.force_b_mps2 for o in w]).reshape(-1, 3)
    cov = observation_covariance(w, noise)
    _check_excitation(triad, model, x)
    if model == "per-axis":
        if accel:
            masks = [np.ones(len(w), dtype=bool)] * 3
        else:
            kinds = np.array([o.kind for o in w])
            masks = []
            for i in range(3):
                along = np.abs(x[:, i]) > 0.99 * np.linalg.norm(x, axis=1)
                masks.append((kinds == "static") | ((kinds == "rate") & along))
        return _per_axis_fit(triad, x, y, se, masks, w, cov)
    if model != "triad":
        raise InvalidInputError(f"`model` must be 'triad' or 'per-axis'; got {model!r}")
    return _triad_fit(triad, x, y, se, f if (g_sensitivity and not accel) else None, w, cov,
                      k2=k2)


def choose_triad_terms(triad: Literal["accel", "gyro"], windows: Sequence[WindowObservation],
                       *, noise: NoiseModel | None = None,
                       forced: Mapping[str, bool] | None = None,
                       ruled: Mapping[str, bool] | None = None, criterion: str = "lrt",
                       level: float = 0.05) -> TriadFit:
    """Fit one triad's triad model with the optional terms the data choose (docs/p1.md).

    Every candidate of :data:`OPTIONAL_TERMS` (``triad``'s: K2 for the accelerometer, G for the
    gyro) not in `forced` is fitted with :func:`fit_triad` and one is chosen by `criterion`
    (:func:`~imucalib.estimation.term_selection.choose_terms`: (TS.1)–(TS.3)); a candidate the
    windows cannot resolve is listed as not identifiable. The returned fit carries the choice
    (``choice``) with the model choice's σ of (TS.4) per parameter.

    Parameters
    ----------
    triad : {"accel", "gyro"}
    windows : sequence of WindowObservation
        As :func:`fit_triad`.
    noise : NoiseModel, optional
        As :func:`fit_triad`.
    forced : mapping of str to bool, optional
        Terms forced in (True) or out (False); those of the other triad are ignored.
    ruled : mapping of str to bool, optional
        Terms the analysis's rule holds in or out unless forced (listed apart; the gyro's G,
        docs/p1.md "Model terms").
    criterion : {"lrt", "aicc", "bic"}
    level : float
        α of (TS.3).

    Raises
    ------
    InsufficientExcitationError
        The windows cannot determine even the smallest candidate.
    InvalidInputError
        An unknown criterion, or a level outside (0, 1).
    """
    optional = OPTIONAL_TERMS[triad]

    def fit(terms: frozenset[str]) -> TriadFit:
        return fit_triad(triad, windows, model="triad", noise=noise,
                         g_sensitivity="g" in terms, k2="k2" in terms)

    choice, chosen, _ = choose_terms(
        _GROUPS[triad], optional, fit, lambda f: (f.chi2, f.dof, int(f.estimate.size)),
        forced={k: v for k, v in (forced or {}).items() if k in optional},
        ruled={k: v for k, v in (ruled or {}).items() if k in optional},
        criterion=criterion, level=level,
        estimates=lambda _t, f: (f.param_names, f.estimate, np.sqrt(np.diag(f.covariance))))
    return replace(chosen, choice=choice)


def fit_p1(obs: P1Observations, *, model: str = "triad", g_sensitivity: bool | None = True,
           repetitions: Sequence[int] | None = None, correlated: bool = True,
           k2: bool | None = False, criterion: str = "lrt", level: float = 0.05,
           ruled: Mapping[str, bool] | None = None) -> P1Fit:
    """Fit the accelerometer and gyro models to the calibration windows.

    Parameters
    ----------
    obs : P1Observations
    model : {"triad", "per-axis"}
        Module docstring.
    g_sensitivity : bool or None
        Triad model only: estimate the gyro g-sensitivity G (True), not (False), or let the
        data choose (None; :func:`choose_triad_terms`).
    repetitions : sequence of int, optional
        Use only these repetitions' windows (all when omitted).
    correlated : bool
        Weight with the full covariance of the window means (flicker and random walk shared
        between windows) when the observations carry a noise model; else each window's standard
        error alone.
    k2 : bool or None
        Triad model only: the accelerometer's K2 (P1.K2 of docs/p1.md), as `g_sensitivity`.
    criterion : {"lrt", "aicc", "bic"}
        How the data choose a term left to them (None above).
    level : float
        α of the likelihood-ratio test (TS.3).
    ruled : mapping of str to bool, optional
        Terms held in or out by the analysis's rule unless `g_sensitivity` or `k2` force them
        (:func:`choose_triad_terms`).

    Raises
    ------
    InsufficientExcitationError
        If the windows cannot determine a parameter (a missing position, no rate about an
        axis …); the message names the parameters.
    """
    accel_w = tuple(w for w in obs.select(kind="static", role="calibration", tag="six-position")
                    if repetitions is None or w.repetition in repetitions)
    if len(accel_w) < 6 and model == "triad":
        raise InsufficientExcitationError(
            triad_parameter_names("accel", "triad"),
            f"the accelerometer triad fit needs the six P1 positions; the recording has "
            f"{len(accel_w)} completed six-position window(s), so the accelerometer biases and "
            "scale/misalignment cannot all be determined")
    gyro_w = tuple(gyro_windows(obs, "calibration", repetitions))
    noise_a = obs.noise.get("accel") if correlated else None
    noise_g = obs.noise.get("gyro") if correlated else None
    if model != "triad":
        accel = fit_triad("accel", accel_w, model=model, noise=noise_a)
        gyro = fit_triad("gyro", gyro_w, model=model, noise=noise_g)
        return P1Fit(model, accel, gyro)
    forced = {name: v for name, v in (("k2", k2), ("g", g_sensitivity)) if v is not None}
    accel = choose_triad_terms("accel", accel_w, noise=noise_a, forced=forced, ruled=ruled,
                               criterion=criterion, level=level)
    gyro = choose_triad_terms("gyro", gyro_w, noise=noise_g, forced=forced, ruled=ruled,
                              criterion=criterion, level=level)
    return P1Fit(model, accel, gyro)


def predict_outputs(fit: P1Fit, w: WindowObservation) -> tuple[_F64, _F64]:
    """Return the fitted models' (gyro, accel) output for a window's reference inputs, SI."""
    a, g = fit.accel, fit.gyro
    if fit.model == "per-axis":
        accel = a.estimate[:3] * (w.force_b_mps2 + a.estimate[3:])
        gyro = g.estimate[:3] * (w.rate_b_rps + g.estimate[3:])
        return gyro, accel
    accel = a.estimate[:3] + (np.eye(3) + a.estimate[3:12].reshape(3, 3)) @ w.force_b_mps2
    if "accel_K2_x" in a.param_names:
        k = a.param_names.index("accel_K2_x")
        accel = accel + a.estimate[k:k + 3] * w.force_b_mps2**2
    gyro = g.estimate[:3] + (np.eye(3) + g.estimate[3:12].reshape(3, 3)) @ w.rate_b_rps
    if "gyro_G_xx" in g.param_names:
        k = g.param_names.index("gyro_G_xx")
        gyro = gyro + g.estimate[k:k + 9].reshape(3, 3) @ w.force_b_mps2
    return gyro, accel
