"""Rate transfer and installation errors through the whole flow on the twin.

plan → SimStation + run_plan → Recording → analysis, against the twin's truth.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imucalib.errors import ConfigurationError, MissingSegmentError, SaturationError
from imucalib.io.opening import open_recording
from imucalib.plan.schema import GuardConfig
from imucalib.procedures import registry
from imucalib.procedures.common.reference import site_vectors
from imucalib.procedures.installation.plan import generate_installation_plan
from imucalib.procedures.rate_transfer.plan import generate_rate_transfer_plan

from ._rate_twin import gyro_truth, run, with_unit

ASYM, K2 = 2e-3, 4e-3
ERRORS = {"gyro.scale_asymmetry": (ASYM, -ASYM, ASYM), "gyro.k2": (K2, K2, -K2),
          "gyro.k3": (0.0, 0.0, 0.0), "gyro.koq": (0.0, 0.0, 0.0)}


def rt_plan(seed: int, **options: object):  # type: ignore[no-untyped-def]
    plan = generate_rate_transfer_plan(rates_dps=(20.0, 45.0, 90.0), sample_rate_hz=50.0,
                                       seed=seed, **options)  # type: ignore[arg-type]
    return with_unit(plan, errors=ERRORS, seed=seed)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_rate_transfer_closed_loop(seed: int, tmp_path: Path) -> None:
    path = run(rt_plan(seed), tmp_path / "rt.h5")
    result = registry.get("rate-transfer").analyze(path)
    truth = gyro_truth(path)
    g, _ = site_vectors(float(truth["latitude_deg"]), 0.0, None)
    m, gs, b = truth["scale_misalignment"], truth["g_sensitivity"], truth["bias"]
    for k, axis in enumerate("xyz"):
        t = result.axis(axis).transfer
        assert t is not None
        e = 1.0 + m[k, k]
        z = [(t.params[1] - e) / t.std(1),                          # E′ = 1 + M_kk
             (t.asymmetry[0] - truth["scale_asymmetry"][k]) / t.asymmetry[1],  # = a_k
             (t.params[3] - truth["k2"][k] * e ** 2) / t.std(3),    # E2 = K2 (1 + M)²
             (t.params[0] - b[k] - gs[k, k] * g) / t.std(0)]        # E0′ = b + G_kk g
        assert np.all(np.abs(z) < 4.0), (axis, z)
    names, values, cov = result.triad_parameters()
    assert names == ["gyro_M_xx", "gyro_M_yy", "gyro_M_zz"]
    assert values.shape == (3,) and cov.shape == (3, 3)
    assert np.all(np.abs((values - np.diag(m)) / np.sqrt(np.diag(cov))) < 4.0)
    json.dumps(result.to_dict(), allow_nan=True)
    assert {r[0] for r in result.parameter_rows()} >= {"gyro_scale_factor_x", "gyro_asymmetry_z"}


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_installation_closed_loop(seed: int, tmp_path: Path) -> None:
    plan = with_unit(generate_installation_plan(rate_dps=(30.0, 60.0), sample_rate_hz=50.0,
                                                seed=seed), seed=seed)
    path = run(plan, tmp_path / "in.h5")
    result = registry.get("installation").analyze(path)
    m = gyro_truth(path)["scale_misalignment"]
    assert np.max(np.abs(result.lsq.matrix - m) / result.lsq.std) < 4.0
    assert np.max(np.abs(result.closed_form.matrix - m) / result.closed_form.std) < 4.0
    assert result.agreement_sigma < 0.05
    names, _, cov = result.triad_parameters()
    assert len(names) == 6 and "gyro_M_xy" in names and cov.shape == (6, 6)
    json.dumps(result.to_dict())


def test_plan_refuses_a_rate_beyond_the_gyro_range() -> None:
    with pytest.raises(ConfigurationError, match="1200 °/s reaches the gyro range ±1000"):
        generate_rate_transfer_plan(rates_dps=(10.0, 1200.0))
    with pytest.raises(ConfigurationError, match="revolutions"):
        generate_installation_plan(revolutions=1)


def test_analysis_refuses_saturated_samples(tmp_path: Path) -> None:
    plan = with_unit(generate_installation_plan(rate_dps=60.0, axes=("z",), sample_rate_hz=50.0),
                     gyro_range_dps=50.0)
    plan = plan.model_copy(update={"guards": GuardConfig(**{**plan.guards.model_dump(),
                                                            "trip_on_saturation": False})})
    path = run(plan, tmp_path / "sat.h5")
    with pytest.raises(SaturationError, match="saturated"):
        registry.get("installation").analyze(path)


def test_missing_turn_and_short_revolutions(tmp_path: Path) -> None:
    plan = with_unit(generate_installation_plan(axes=("z",), sample_rate_hz=50.0))
    no_minus = plan.model_copy(update={"steps": plan.steps[:-1]})
    path = run(no_minus, tmp_path / "missing.h5")
    with pytest.raises(MissingSegmentError, match="−30 °/s turn is missing"):
        registry.get("installation").analyze(path)
    path = run(plan, tmp_path / "short.h5")
    with open_recording(path) as rec:
        steps = list(rec.steps)
    import dataclasses

    from imucalib.io import reader
    from imucalib.procedures.installation.analysis import analyze_installation

    cut = [dataclasses.replace(s, commanded={**s.commanded, "revolutions": 4})
           if s.role == "installation.rate" and s.commanded.get("rate_dps", 0) < 0 else s
           for s in steps]
    with open_recording(path) as rec, pytest.MonkeyPatch.context() as mp:
        mp.setattr(reader.Recording, "steps", property(lambda self: cut))
        with pytest.raises(MissingSegmentError, match=r"2 whole revolution.* of the 4 commanded"):
            analyze_installation(rec)


@pytest.mark.slow
def test_twin_sigma_matches_the_spread(tmp_path: Path) -> None:
    """RMS of the z-scores of E′, asymmetry, E2 and E0′ over 12 seeds × 3 axes: 1 ± 15 %."""
    zs = []
    for seed in range(300, 312):
        path = run(rt_plan(seed), tmp_path / f"mc{seed}.h5")
        result = registry.get("rate-transfer").analyze(path)
        truth = gyro_truth(path)
        g, _ = site_vectors(float(truth["latitude_deg"]), 0.0, None)
        for k, axis in enumerate("xyz"):
            t = result.axis(axis).transfer
            assert t is not None
            e = 1.0 + truth["scale_misalignment"][k, k]
            zs += [(t.params[1] - e) / t.std(1),
                   (t.asymmetry[0] - truth["scale_asymmetry"][k]) / t.asymmetry[1],
                   (t.params[3] - truth["k2"][k] * e ** 2) / t.std(3),
                   (t.params[0] - truth["bias"][k] - truth["g_sensitivity"][k, k] * g)
                   / t.std(0)]
    rms = float(np.sqrt(np.mean(np.square(zs))))
    assert 0.85 < rms < 1.15, rms
