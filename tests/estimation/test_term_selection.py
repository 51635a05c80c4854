"""Choosing optional model terms (imucalib.estimation.term_selection, Eqs. (TS.1)–(TS.4)):
each criterion against a linear model with a known answer, forced and ruled terms, a candidate
the design cannot resolve, the over-dispersion rule, and the model choice's uncertainty."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation.linear import solve_weighted_lsq
from imucalib.estimation.term_selection import choose_terms, model_choice_std, parse_terms

X = np.linspace(-1.0, 1.0, 40)
COLUMNS = {"lin": X, "quad": X**2, "cub": X**3}


def _fitter(z, sigma):
    def fit(terms):
        names = ["c", *sorted(terms)]
        h = np.column_stack([np.ones_like(X), *(COLUMNS[t] for t in sorted(terms))])
        return solve_weighted_lsq(h, z, param_names=names, sigma=sigma)
    return fit


def _stats(f):
    return float(f.chi2), int(f.dof), int(f.estimate.size)


@pytest.mark.parametrize("criterion", ["aicc", "bic", "lrt"])
def test_a_strong_term_is_chosen_and_an_absent_one_is_not(criterion):
    rng = np.random.default_rng(1)
    z = 1.0 + 0.8 * X + 0.01 * rng.standard_normal(X.size)   # lin strong, quad and cub absent
    choice, fit, largest = choose_terms("demo", ("lin", "quad", "cub"), _fitter(z, 0.01),
                                        _stats, criterion=criterion)
    assert choice.chosen == ("lin",) and choice.largest == ("cub", "lin", "quad")
    assert list(fit.param_names) == ["c", "lin"] and largest.estimate.size == 4
    assert len(choice.candidates) == 8 and choice.c_hat == 1.0
    assert "by " in choice.summary() and "lin" in choice.summary()
    doc = choice.to_dict()
    assert doc["chosen"] == ["lin"] and {c["n_params"] for c in doc["candidates"]} == {1, 2, 3, 4}


def test_aicc_and_bic_are_their_formulas():
    rng = np.random.default_rng(2)
    z = 1.0 + 0.01 * rng.standard_normal(X.size)
    for criterion in ("aicc", "bic"):
        choice, _, _ = choose_terms("demo", ("lin",), _fitter(z, 0.01), _stats,
                                    criterion=criterion)
        for c in choice.candidates:
            q, m = c.n_params, c.dof + c.n_params
            want = (c.chi2 + 2 * q + 2 * q * (q + 1) / (m - q - 1) if criterion == "aicc"
                    else c.chi2 + q * math.log(m))
            assert c.score == pytest.approx(want, rel=1e-12)


def test_the_lrt_adds_a_term_at_its_level_and_not_below():
    rng = np.random.default_rng(3)
    noise = rng.standard_normal(X.size)
    # a quadratic term whose Δχ² is about 9: in at α = 0.05 (3.84), out at α = 0.001 (10.8)
    z = 1.0 + 3.0 / np.sqrt(np.sum((X**2 - np.mean(X**2)) ** 2)) * X**2 + noise
    fit = _fitter(z, 1.0)
    small, large = fit(frozenset()), fit(frozenset({"quad"}))
    drop = small.chi2 - large.chi2
    for level, expect in ((0.05, drop > 3.84), (0.001, drop > 10.83)):
        choice, _, _ = choose_terms("demo", ("quad",), fit, _stats, criterion="lrt",
                                    level=level)
        assert choice.has("quad") == expect


def test_forced_and_ruled_terms_are_held_and_named():
    z = 1.0 + 0.5 * X
    choice, _, _ = choose_terms("demo", ("lin", "quad"), _fitter(z, 0.01), _stats,
                                forced={"lin": False}, ruled={"quad": True})
    assert choice.chosen == ("quad",) and len(choice.candidates) == 1
    assert "forced -lin" in choice.summary() and "by rule +quad" in choice.summary()
    with pytest.raises(InvalidInputError, match="no optional term cub"):
        choose_terms("demo", ("lin",), _fitter(z, 0.01), _stats, forced={"cub": True})


def test_a_candidate_the_design_cannot_resolve_is_listed_not_chosen():
    def fit(terms):
        if "quad" in terms:
            raise InsufficientExcitationError(["quad"], "the poses cannot see it")
        return _fitter(1.0 + 0.5 * X, 0.01)(terms)
    choice, _, _ = choose_terms("demo", ("lin", "quad"), fit, _stats)
    assert choice.chosen == ("lin",)
    bad = [c for c in choice.candidates if not c.identifiable]
    assert len(bad) == 2 and all("cannot see" in c.note for c in bad)


def test_a_misfit_of_every_candidate_is_not_taken_for_evidence():
    # noise 3× what the fit is told: every χ² is ~9ν; divided by ĉ they select as white noise
    rng = np.random.default_rng(5)
    z = 1.0 + 0.03 * rng.standard_normal(X.size)
    choice, _, _ = choose_terms("demo", ("lin", "quad", "cub"), _fitter(z, 0.01), _stats,
                                criterion="lrt")
    assert choice.c_hat > 4.0 and choice.chosen == ()


def test_the_model_choice_uncertainty_is_ts4():
    std = model_choice_std(["a", "b"], [1.0, 2.0], [0.1, 0.2], ["a", "b", "k"],
                           [1.3, 2.0, 5.0], [0.5, 0.1, 1.0])
    assert std["a"] == pytest.approx(math.sqrt(0.3**2 + 0.5**2 - 0.1**2))
    assert std["b"] == pytest.approx(0.0)  # no shift, and the larger model no less sure
    assert model_choice_std(["a"], [1.0], [0.1], ["a"], [1.0], [0.1]) == {}


@pytest.mark.parametrize(("spec", "message"), [
    ("k2", "a sign"), ("+k9", "unknown term 'k9'"), ("+k2,-k2", "given twice"), ("+", "a sign")])
def test_bad_term_lists_are_named(spec, message):
    with pytest.raises(InvalidInputError, match=message):
        parse_terms(spec, ("k2", "drift", "g"))
    assert parse_terms(" +k2, -drift ,", ("k2", "drift", "g")) == {"k2": True, "drift": False}
