"""Bad inputs get typed errors whose messages say what was expected and what was found."""

from __future__ import annotations

import json

import numpy as np
import pytest

from imucalib.analysis import (
    DeviationResult,
    SamplingCheck,
    check_uniform_sampling,
    compute_deviation,
    compute_oadev,
    resolve_averaging_factors,
)
from imucalib.errors import InvalidInputError


def test_nan_gap_is_refused_with_its_position() -> None:
    y = np.ones(1000)
    y[400:410] = np.nan
    with pytest.raises(InvalidInputError,
                       match=r"10 NaN or infinite sample\(s\), the first at index 400 "
                             r"\(t = 4 s\); an Allan sum across a gap is not defined"):
        compute_oadev(y, 100.0)
    y[400:410] = np.inf
    with pytest.raises(InvalidInputError, match="the first at index 400"):
        compute_oadev(y, 100.0)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"data": np.zeros((10, 3))}, r"`data` must be 1-D \(one channel\); got shape \(10, 3\)"),
    ({"data": ["a", "b"]}, "`data` must be numeric; got list"),
    ({"sample_rate_hz": 0.0}, "`sample_rate_hz` must be > 0; got 0.0"),
    ({"data_type": "phase"}, "`data_type` must be 'rate' or 'angle'; got 'phase'"),
    ({"kind": "xdev"}, r"unknown deviation kind 'xdev'; expected one of \['adev'"),
    ({"data": np.zeros(2)}, "data too short: `oadev` needs at least 3 samples; got 2"),
    ({"taus": "weekly"}, "`taus` must be 'octave', 'decade', 'all', an int or τ values"),
    ({"taus": 0}, "`taus` per decade must be ≥ 1; got 0"),
    ({"taus": [0.001]}, r"τ = 0.001 s is shorter than the sample interval 0.01 s"),
    ({"taus": [1.0, 3.0]},
     r"τ = 3 s is too long for `oadev` on 500 samples at 100 Hz \(the longest τ is 2.49 s\)"),
    ({"taus": [[1.0]]}, "`taus` values must be a non-empty 1-D finite array"),
    ({"confidence": 0.0}, r"`confidence` must be in \(0, 1\); got 0.0"),
])
def test_bad_arguments(kwargs: dict, message: str) -> None:
    args = {"kind": "oadev", "data": np.random.default_rng(0).standard_normal(500),
            "sample_rate_hz": 100.0}
    args.update(kwargs)
    kind, data, rate = args.pop("kind"), args.pop("data"), args.pop("sample_rate_hz")
    with pytest.raises(InvalidInputError, match=message):
        compute_deviation(kind, data, rate, **args)


def test_too_short_for_every_estimator() -> None:
    for kind, need in [("hdev", 4), ("ohdev", 4), ("mdev", 3), ("totdev", 3), ("adev", 3)]:
        with pytest.raises(InvalidInputError, match=f"`{kind}` needs at least {need} samples"):
            compute_deviation(kind, np.zeros(need - 1), 1.0)
    with pytest.raises(InvalidInputError, match="data too short: `hdev` needs at least 4 samples "
                                                "for one τ; got 2"):
        resolve_averaging_factors("octave", 3, 1.0, "hdev")


def test_uniform_sampling_check() -> None:
    t = np.arange(1000) / 200.0
    assert check_uniform_sampling(t) == pytest.approx(200.0)
    jitter = t + np.random.default_rng(0).normal(0, 1e-6, t.size)
    assert check_uniform_sampling(jitter) == pytest.approx(200.0, rel=1e-5)
    gap = np.delete(t, np.arange(300, 305))
    with pytest.raises(InvalidInputError, match=r"non-uniform sampling: a gap of 0.03 s \(nominal "
                                                r"interval 0.005 s\) after t = 1.495000 s"):
        check_uniform_sampling(gap)
    bad = t.copy()
    bad[500] += 0.0002
    with pytest.raises(InvalidInputError, match=r"the interval after t = 2.495000 s is 0.0052 s, "
                                                r"4.00% off the nominal 0.005 s"):
        check_uniform_sampling(bad)
    with pytest.raises(InvalidInputError, match=r"strictly increasing; 0.05 s follows 0.05 s"):
        check_uniform_sampling(np.concatenate([t[:11], t[10:]]))
    with pytest.raises(InvalidInputError, match=r"`time_s` must be 1-D with ≥ 2 stamps"):
        check_uniform_sampling([1.0])


def test_sampling_check_in_chunks() -> None:
    t = np.arange(10_000) / 1000.0
    chk = SamplingCheck()
    for a in range(0, t.size, 777):
        chk.update(t[a:a + 777])
    assert chk.n_samples == t.size
    assert chk.sample_rate_hz() == pytest.approx(1000.0)
    chk = SamplingCheck()
    chk.update(t[:5000])
    with pytest.raises(InvalidInputError, match=r"a gap of 0.011 s \(nominal interval 0.001 s\) "
                                                r"after t = 4.999000 s"):
        chk.update(t[5010:])
    with pytest.raises(InvalidInputError, match="need at least 2 time stamps; got 0"):
        SamplingCheck().sample_rate_hz()


def test_result_round_trip_and_noise_names() -> None:
    res = compute_oadev(np.random.default_rng(2).standard_normal(4000), 50.0, unit="rad/s")
    back = DeviationResult.from_dict(json.loads(json.dumps(res.to_dict())))
    for name in ("taus_s", "deviation", "edf", "ci_low", "ci_high", "noise_alpha", "n_terms",
                 "averaging_factors"):
        np.testing.assert_array_equal(getattr(back, name), getattr(res, name))
    assert back.noise_id_method == res.noise_id_method and back.unit == "rad/s"
    assert res.noise_types[0].startswith("white rate")
    np.testing.assert_allclose(res.variance, res.deviation**2)
    assert np.all(res.ci_low < res.deviation) and np.all(res.deviation < res.ci_high)
    with pytest.raises(InvalidInputError,
                       match=r"deviation result is missing \['averaging_factors', 'ci_high'"):
        DeviationResult.from_dict({"kind": "oadev"})
