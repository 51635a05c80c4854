"""Tests of imucalib.estimation.observability: rank, conditioning and named weak directions."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation import compute_observability


def test_full_rank_design_is_observable() -> None:
    rng = np.random.default_rng(0)
    rep = compute_observability(rng.normal(size=(20, 4)), list("abcd"))
    assert rep.is_observable and rep.rank == 4
    assert rep.weak_directions.shape == (4, 0)
    assert rep.unobservable == ()
    rep.raise_if_unobservable()  # no exception
    assert "rank 4 of 4" in rep.describe()


def test_zero_column_is_named_alone_with_full_participation() -> None:
    rng = np.random.default_rng(1)
    A = rng.normal(size=(10, 3))
    A[:, 1] = 0.0
    rep = compute_observability(A, ["a", "b", "c"])
    assert rep.rank == 2 and rep.condition_number == np.inf
    np.testing.assert_allclose(rep.participation, [0.0, 1.0, 0.0], atol=1e-12)
    assert rep.unobservable == ("b",)


def test_duplicated_columns_share_the_null_direction() -> None:
    rng = np.random.default_rng(2)
    A = rng.normal(size=(10, 3))
    A[:, 2] = 3.0 * A[:, 0]  # only a + 3c is determined
    rep = compute_observability(A, ["a", "b", "c"])
    np.testing.assert_allclose(rep.participation, [0.5, 0.0, 0.5], atol=1e-12)
    assert rep.unobservable == ("a", "c")
    with pytest.raises(InsufficientExcitationError,
                       match=r"the design cannot determine all parameters \(expected full rank 3 "
                             r"and condition number ≤ 1e\+10; got rank 2 of 3, condition number "
                             r"inf .*\+0\.71·[ac] -0\.71·[ac]\); unobservable: a, c$"):
        rep.raise_if_unobservable()


def test_participation_does_not_depend_on_null_basis() -> None:
    # a two-dimensional null space: any rotation of its basis gives the same participation
    rng = np.random.default_rng(3)
    base = rng.normal(size=(12, 3))
    A = np.column_stack([base, base[:, 0] + base[:, 1], base[:, 2] - base[:, 1]])
    rep = compute_observability(A, list("abcde"))
    assert rep.rank == 3 and rep.weak_directions.shape[1] == 2
    np.testing.assert_allclose(rep.participation.sum(), 2.0, rtol=1e-12)
    assert set(rep.unobservable) == set("abcde")


def test_condition_number_is_unit_invariant() -> None:
    rng = np.random.default_rng(4)
    A = rng.normal(size=(15, 3))
    r1 = compute_observability(A, list("abc"))
    r2 = compute_observability(A * [1e-9, 1.0, 1e9], list("abc"))
    assert r2.condition_number == pytest.approx(r1.condition_number, rel=1e-10)
    assert r2.is_observable


def test_wide_design_reports_missing_rank() -> None:
    rep = compute_observability(np.ones((2, 4)) * [1, 2, 3, 4], list("abcd"))
    assert rep.rank == 1 and rep.singular_values.shape == (4,)
    assert set(rep.unobservable) == set("abcd")


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"cond_limit": 1.0}, r"`cond_limit` must be > 1; got 1.0"),
        ({"cond_limit": -5}, r"`cond_limit` must be > 0; got -5"),
        ({"participation_threshold": 2.0}, r"`participation_threshold` must be in \(0, 1\]; "
                                           r"got 2.0"),
        ({"design": np.zeros((0, 2))}, r"at least one row and one column; got \(0, 2\)"),
        ({"design": [[1.0, np.nan]]}, r"`design` must be finite"),
    ],
)
def test_bad_inputs_raise_with_messages(kwargs: dict, match: str) -> None:
    args = {"design": np.eye(2), "param_names": ["a", "b"]}
    args.update(kwargs)
    with pytest.raises(InvalidInputError, match=match):
        compute_observability(**args)
