"""Choosing a fit's optional model terms by what the data support (docs/field.md, "Model terms").

A triad fit has core terms (bias, scale, misalignment) and optional ones (the accelerometer's
K2, a bias drift over the session, the gyro's g-sensitivity G, K3) that the data may or may not
support. Fixing them either way costs: a term the unit lacks adds variance and moves the other
estimates (a K2 the data barely see changes what "the bias" means), a term it has and the model
lacks biases them. This module fits every candidate term set of one group and chooses among
them by a stated criterion, keeping the evidence.

Equations
---------
Each candidate T (a subset of the optional terms, with every term forced in and none forced
out) is a generalised least-squares fit with known noise: χ²(T) on ν(T) = m − q(T) degrees of
freedom (m observations, q(T) parameters). When even the largest candidate does not fit (its
χ² above the 99 % quantile of χ²_ν, the misfit rule of
:func:`~imucalib.models.fit_quality.assess_fit`: coloured noise, a missing term outside the
candidates), every χ² is divided by its over-dispersion ĉ = χ²_max/ν_max (Burnham & Anderson,
*Model Selection and Multimodel Inference*, 2nd ed., 2002, §6.2: the quasi-likelihood form;
ĉ = 1 otherwise), so that a misfit does not pass for evidence of extra terms:

    AICc(T) = χ²(T)/ĉ + 2q + 2q(q + 1)/(m − q − 1)      (∞ when m − q − 1 ≤ 0)        (TS.1)
    BIC(T)  = χ²(T)/ĉ + q·ln m                                                        (TS.2)

(Akaike 1974; Hurvich & Tsai 1989; Schwarz 1978); the smallest is chosen. The likelihood-ratio
test (Wilks 1938) instead adds terms forward: from the smallest candidate, the term whose
addition lowers χ² most is added while

    Δχ²/ĉ > χ²_{Δq}(1 − α)                                                             (TS.3)

(Δq the added term's parameters, α the stated level). A candidate whose design is singular
(the poses cannot resolve it) is listed as not identifiable and never chosen.

A term the data left out is not thereby zero: it is only too small for these data to tell, and
the other estimates, conditional on its absence, can sit far from those of the model that
holds it (a K2 correlates with the biases: left out on a tactical unit of the twin, the biases
moved by 8.6 of their conditional σ). The chosen model's parameters therefore carry a Type B
uncertainty of the model choice: the shift to the largest candidate the data allowed, and what
that candidate's σ exceed theirs by (Burnham & Anderson 2002, §4.3, the unconditional
variance with the larger model's weight taken as 1, its bound), so that a parameter is never
known better than the data know it without the assumption that the term is absent:

    u²_model(θ_i) = (θ̂_i,chosen − θ̂_i,largest)² + max(0, σ²_i,largest − σ²_i,chosen)   (TS.4)

for every parameter the two share (σ² = u² + σ²_chosen ≥ σ²_largest). What leaving the term out
buys is a model other tools can hold and estimates that do not move with a term the data
cannot see; not precision. A term the user forced out is the user's assumption (a datasheet's,
a fixture's) and adds nothing.

Contents
--------
:class:`Candidate`, :class:`TermChoice`, :func:`choose_terms`, :func:`parse_terms`,
:func:`model_choice_std`, :data:`CRITERIA`.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Final, Generic, TypeVar

import numpy as np
import scipy.stats
from numpy.typing import ArrayLike

from imucalib.errors import CalibrationError, InvalidInputError
from imucalib.models.fit_quality import MISFIT_QUANTILE

__all__ = ["CRITERIA", "Candidate", "TermChoice", "choose_terms", "model_choice_std",
           "parse_terms"]

#: The criteria :func:`choose_terms` knows.
CRITERIA: Final = ("aicc", "bic", "lrt")

_Fit = TypeVar("_Fit")


@dataclass(frozen=True)
class Candidate:
    """One candidate term set of a group, fitted and scored.

    Attributes
    ----------
    terms : tuple of str
        The optional terms it holds (sorted).
    chi2 : float
        χ² of its fit (NaN when not identifiable).
    dof : int
        ν = m − q.
    n_params : int
        q.
    score : float
        AICc or BIC of (TS.1)/(TS.2) (with the LRT: AICc, for the table). ∞ when not
        identifiable or ν too small.
    note : str
        Why it could not be fitted ("" when it was).
    """

    terms: tuple[str, ...]
    chi2: float
    dof: int
    n_params: int
    score: float
    note: str = ""

    @property
    def identifiable(self) -> bool:
        """Whether its fit succeeded."""
        return not self.note

    def to_dict(self) -> dict[str, Any]:
        """Return the candidate as JSON-ready data."""
        return {"terms": list(self.terms), "chi2": _finite_or_none(self.chi2),
                "dof": self.dof, "n_params": self.n_params,
                "reduced_chi2": _finite_or_none(self.chi2 / self.dof if self.dof > 0
                                                else math.nan),
                "score": _finite_or_none(self.score), "note": self.note}


@dataclass(frozen=True)
class TermChoice:
    """The choice of one group's optional terms and the evidence for it.

    Attributes
    ----------
    group : str
        What is fitted (``"accel"``, ``"gyro (static poses)"`` …).
    criterion : str
        ``"aicc"``, ``"bic"`` or ``"lrt"``.
    level : float
        α of (TS.3) (the LRT only).
    optional : tuple of str
        The terms the data chose among.
    forced : dict of str to bool
        Terms forced in (True) or out (False) by the user.
    ruled : dict of str to bool
        Terms the fit's own rule put in or out (not the data's choice; the caller says why).
    largest : tuple of str
        The largest candidate the data could fit (what (TS.4) compares with).
    model_std : dict of str to float
        u_model of (TS.4) per parameter, when the caller added it (:func:`model_choice_std`).
    chosen : tuple of str
        The optional and forced-in terms of the chosen candidate.
    c_hat : float
        ĉ, the over-dispersion the χ² were divided by (1: the largest candidate fits).
    candidates : tuple of Candidate
    """

    group: str
    criterion: str
    level: float
    optional: tuple[str, ...]
    forced: dict[str, bool]
    chosen: tuple[str, ...]
    c_hat: float
    candidates: tuple[Candidate, ...]
    ruled: dict[str, bool] = field(default_factory=dict)
    largest: tuple[str, ...] = ()
    model_std: dict[str, float] = field(default_factory=dict)

    def has(self, term: str) -> bool:
        """Whether the chosen model holds `term`."""
        return term in self.chosen

    def summary(self) -> str:
        """Return one line: what was chosen, by what, against what."""
        chosen = "+".join(self.chosen) or "no optional term"
        how = {"aicc": "AICc", "bic": "BIC"}.get(self.criterion,
                                                   f"likelihood-ratio test at α = {self.level:g}")
        scored = sorted((c for c in self.candidates if c.identifiable),
                        key=lambda c: c.score)
        table = "; ".join(f"{'+'.join(c.terms) or 'none'}: χ²/ν = {c.chi2 / max(c.dof, 1):.3g}"
                          f", {'AICc' if self.criterion != 'bic' else 'BIC'} {c.score:.4g}"
                          for c in scored)
        widest = max(self.model_std.items(), key=lambda kv: kv[1])[0] if self.model_std else ""
        forced = ", ".join(f"{'+' if v else '-'}{k}" for k, v in sorted(self.forced.items()))
        ruled = ", ".join(f"{'+' if v else '-'}{k}" for k, v in sorted(self.ruled.items()))
        return (f"{self.group} model terms: {chosen} (by {how}"
                f"{'; forced ' + forced if forced else ''}"
                f"{'; by rule ' + ruled if ruled else ''}"
                f"{f'; χ² divided by ĉ = {self.c_hat:.3g}' if self.c_hat > 1.0 else ''}); "
                f"candidates {table}"
                + (f"; left out by the data, so the others carry the model choice's "
                   f"uncertainty (TS.4), largest on {widest}"
                   if self.model_std else ""))

    def to_dict(self) -> dict[str, Any]:
        """Return the choice as JSON-ready data (the result document's ``model_selection``)."""
        return {"group": self.group, "criterion": self.criterion, "level": self.level,
                "optional": list(self.optional), "forced": dict(self.forced),
                "ruled": dict(self.ruled), "largest": list(self.largest),
                "model_std": dict(self.model_std),
                "chosen": list(self.chosen), "c_hat": self.c_hat,
                "candidates": [c.to_dict() for c in self.candidates]}


@dataclass(frozen=True)
class _Scored(Generic[_Fit]):
    candidate: Candidate
    fit: _Fit | None


def _finite_or_none(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def parse_terms(spec: str, known: Sequence[str]) -> dict[str, bool]:
    """Parse ``"+k2,-drift"`` into ``{"k2": True, "drift": False}``.

    Raises
    ------
    InvalidInputError
        An item without its sign, an unknown term, or a term given twice.
    """
    out: dict[str, bool] = {}
    for raw in (s.strip() for s in spec.split(",")):
        if not raw:
            continue
        if raw[0] not in "+-" or len(raw) < 2:
            raise InvalidInputError(f"--terms: expected items like +k2 or -drift (a sign, then "
                                    f"one of {', '.join(known)}); got {raw!r}")
        name = raw[1:].strip().lower()
        if name not in known:
            raise InvalidInputError(f"--terms: unknown term {name!r}; expected one of "
                                    f"{', '.join(known)}")
        if name in out:
            raise InvalidInputError(f"--terms: {name!r} is given twice")
        out[name] = raw[0] == "+"
    return out


def _score(criterion: str, chi2: float, q: int, m: int, c_hat: float) -> float:
    """(TS.1) or (TS.2); the LRT's table shows AICc."""
    if not math.isfinite(chi2):
        return math.inf
    if criterion == "bic":
        return chi2 / c_hat + q * math.log(m)
    if m - q - 1 <= 0:
        return math.inf
    return chi2 / c_hat + 2.0 * q + 2.0 * q * (q + 1) / (m - q - 1)


def choose_terms(
    group: str,
    optional: Sequence[str],
    fit: Callable[[frozenset[str]], _Fit],
    statistics: Callable[[_Fit], tuple[float, int, int]],
    *,
    forced: Mapping[str, bool] | None = None,
    ruled: Mapping[str, bool] | None = None,
    criterion: str = "aicc",
    level: float = 0.05,
    term_params: Mapping[str, int] | None = None,
    estimates: Callable[[frozenset[str], _Fit], tuple[Sequence[str], ArrayLike, ArrayLike]]
    | None = None,
) -> tuple[TermChoice, _Fit, _Fit]:
    """Fit every candidate term set of a group and choose one (module docstring).

    Parameters
    ----------
    group : str
        What is fitted, for the summary.
    optional : sequence of str
        The optional terms of the group.
    fit : callable
        ``fit(terms) -> fit result`` for a frozenset of terms; raises a
        :class:`~imucalib.errors.CalibrationError` when the design cannot resolve them.
    statistics : callable
        ``statistics(fit) -> (χ², ν, q)`` of a fit result.
    forced : mapping of str to bool, optional
        Terms forced in (True) or out (False) by the user; the others are chosen.
    ruled : mapping of str to bool, optional
        Terms the caller's rule puts in or out unless `forced` says otherwise (held like
        forced ones, listed apart).
    criterion : {"aicc", "bic", "lrt"}
    level : float
        α of (TS.3), in (0, 1).
    term_params : mapping of str to int, optional
        The parameters each term adds (Δq of (TS.3)); by default taken from the fits.
    estimates : callable, optional
        ``estimates(terms, fit) -> (names, values, σ)`` of a fit: given, the choice carries
        u_model of (TS.4) (:func:`model_choice_std`, its non-zero entries) in ``model_std``.

    Returns
    -------
    (TermChoice, fit result, fit result)
        The choice, the chosen candidate's fit and the largest fitted candidate's (for
        :func:`model_choice_std`).

    Raises
    ------
    InvalidInputError
        An unknown criterion or forced term, or a level outside (0, 1).
    CalibrationError
        No candidate can be fitted (the error of the smallest one).
    """
    if criterion not in CRITERIA:
        raise InvalidInputError(f"the term criterion must be one of {', '.join(CRITERIA)}; got "
                                f"{criterion!r}")
    if not 0.0 < level < 1.0:
        raise InvalidInputError(f"the term test's level must be in (0, 1); got {level!r}")
    forced = dict(forced or {})
    ruled = {k: v for k, v in (ruled or {}).items() if k not in forced}
    unknown = sorted((set(forced) | set(ruled)) - set(optional))
    if unknown:
        raise InvalidInputError(f"{group}: no optional term {', '.join(unknown)} here; "
                                f"expected {', '.join(optional) or 'none'}")
    held = {**forced, **ruled}
    free = [t for t in optional if t not in held]
    base = frozenset(t for t, v in held.items() if v)
    scored: dict[frozenset[str], _Scored[_Fit]] = {}
    first_error: CalibrationError | None = None
    raw: dict[frozenset[str], tuple[float, int, int]] = {}
    for k in range(len(free) + 1):
        for extra in itertools.combinations(free, k):
            terms = base | frozenset(extra)
            try:
                result = fit(terms)
            except CalibrationError as exc:
                first_error = first_error or exc
                scored[terms] = _Scored(Candidate(tuple(sorted(terms)), math.nan, 0, 0,
                                                  math.inf, str(exc)), None)
                continue
            raw[terms] = statistics(result)
            scored[terms] = _Scored(Candidate(tuple(sorted(terms)), *raw[terms][:2],
                                              raw[terms][2], math.nan), result)
    if not raw:
        assert first_error is not None
        raise first_error
    largest = max(raw, key=lambda t: (raw[t][2], sorted(t)))
    chi2_max, dof_max, _ = raw[largest]
    c_hat = 1.0
    if dof_max > 0 and chi2_max > scipy.stats.chi2.ppf(MISFIT_QUANTILE, dof_max):
        c_hat = chi2_max / dof_max
    m = {t: int(v[1] + v[2]) for t, v in raw.items()}
    table_criterion = "bic" if criterion == "bic" else "aicc"
    for t, (chi2, dof, q) in raw.items():
        c = scored[t].candidate
        scored[t] = _Scored(Candidate(c.terms, chi2, dof, q,
                                      _score(table_criterion, chi2, q, m[t], c_hat)),
                            scored[t].fit)
    if criterion == "lrt":
        chosen = _forward_lrt(base, free, raw, c_hat, level, term_params)
    else:
        chosen = min(raw, key=lambda t: (scored[t].candidate.score, raw[t][2]))
    choice = TermChoice(group, criterion, level, tuple(optional), forced,
                        tuple(sorted(chosen)), c_hat,
                        tuple(scored[t].candidate for t in sorted(scored, key=_order)), ruled,
                        tuple(sorted(largest)))
    fit_chosen, fit_largest = scored[chosen].fit, scored[largest].fit
    assert fit_chosen is not None and fit_largest is not None
    if estimates is not None:
        std = model_choice_std(*estimates(chosen, fit_chosen), *estimates(largest, fit_largest))
        choice = replace(choice, model_std={k: v for k, v in std.items() if v > 0})
    return choice, fit_chosen, fit_largest


def model_choice_std(chosen_names: Sequence[str], chosen_values: ArrayLike,
                     chosen_std: ArrayLike, largest_names: Sequence[str],
                     largest_values: ArrayLike, largest_std: ArrayLike) -> dict[str, float]:
    """Return u_model of (TS.4) for each parameter of the chosen fit the largest one shares.

    Empty when the two are the same model. [the parameters' units]
    """
    if list(chosen_names) == list(largest_names):
        return {}
    other = {n: (v, s) for n, v, s in zip(
        largest_names, np.asarray(largest_values, dtype=float).tolist(),
        np.asarray(largest_std, dtype=float).tolist(), strict=True)}
    out = {}
    for n, v, s in zip(chosen_names, np.asarray(chosen_values, dtype=float).tolist(),
                       np.asarray(chosen_std, dtype=float).tolist(), strict=True):
        if n in other:
            v_l, s_l = other[n]
            out[n] = math.sqrt((v - v_l) ** 2 + max(0.0, s_l**2 - s**2))
    return out


def _order(terms: frozenset[str]) -> tuple[int, list[str]]:
    return len(terms), sorted(terms)


def _forward_lrt(base: frozenset[str], free: list[str],
                 raw: Mapping[frozenset[str], tuple[float, int, int]], c_hat: float,
                 level: float, term_params: Mapping[str, int] | None) -> frozenset[str]:
    """(TS.3): add the most significant term while it passes the test."""
    current = base if base in raw else min(raw, key=lambda t: (raw[t][2], sorted(t)))
    while True:
        best: tuple[float, frozenset[str]] | None = None
        for t in free:
            if t in current or (current | {t}) not in raw:
                continue
            nxt = current | {t}
            dq = (term_params or {}).get(t, raw[nxt][2] - raw[current][2])
            drop = (raw[current][0] - raw[nxt][0]) / c_hat
            if dq > 0 and drop > scipy.stats.chi2.ppf(1.0 - level, dq):
                p = float(scipy.stats.chi2.sf(drop, dq))
                if best is None or p < best[0]:
                    best = (p, nxt)
        if best is None:
            return current
        current = best[1]
