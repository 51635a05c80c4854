"""The example's own checks: the fit on known numbers, the plan's shape, the result contract.

Run with the package importable, e.g. ``PYTHONPATH=examples/imucalib-scale-factor/src pytest
examples/imucalib-scale-factor/tests`` from imucalib's checkout, or after installing it.
"""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import ConfigurationError, InsufficientExcitationError
from imucalib.models.reported import ReportedParameter
from imucalib.plan.schema import RateStep
from imucalib.procedures.common.procedure import Procedure, ProcedureResult
from imucalib_scale_factor.analysis import ScaleFactorResult, fit_scale_factor
from imucalib_scale_factor.plan import ROLE_RATE, generate_scale_factor_plan
from imucalib_scale_factor.procedure import PROCEDURE


def test_the_fit_recovers_a_line_and_scales_a_misfit() -> None:
    x = np.array([0.5, -0.5, 1.0, -1.0, 1.5, -1.5])
    est, cov, res, q = fit_scale_factor(x, 1.001 * x + 2e-4, np.full(6, 1e-5))
    assert est == pytest.approx([1.001, 2e-4], rel=0, abs=1e-12)
    assert np.allclose(res, 0.0, atol=1e-12) and q.dof == 4 and not q.misfit
    # σ_K1 of a weighted line through ±x: σ / √Σx² (known noise, no misfit)
    assert np.sqrt(cov[0, 0]) == pytest.approx(1e-5 / np.sqrt(np.sum(x**2)), rel=1e-9)
    noisy = 1.001 * x + 2e-4 + np.array([1, -1, -1, 1, 1, -1]) * 1e-3
    _, cov2, _, q2 = fit_scale_factor(x, noisy, np.full(6, 1e-5))
    assert q2.misfit and np.sqrt(cov2[0, 0]) > 50 * np.sqrt(cov[0, 0])  # Birge-scaled
    with pytest.raises(InsufficientExcitationError):
        fit_scale_factor([1.0, 1.0], [1.0, 1.0], [1e-3, 1e-3])


def test_the_plan_turns_about_z_both_ways_and_satisfies_the_protocol() -> None:
    assert isinstance(PROCEDURE, Procedure)
    plan = generate_scale_factor_plan(rates_dps=(30.0, 60.0), sample_rate_hz=50.0)
    assert plan.procedure == "scale-factor" and plan.twin is not None
    turns = [s for s in plan.steps if isinstance(s, RateStep)]
    assert [s.rate_dps for s in turns] == [30.0, -30.0, 60.0, -60.0]
    assert {s.role for s in turns} == {ROLE_RATE} and all("axis=z" in s.tags for s in turns)
    with pytest.raises(ConfigurationError, match="gyro range"):
        generate_scale_factor_plan(rates_dps=(5000.0,))
    result = ScaleFactorResult(unit="U", k1=1.0, k1_std=1e-6, bias_rps=0.0, bias_std_rps=1e-6,
                               correlation=0.0, input_rps=np.zeros(2), output_rps=np.zeros(2),
                               se_rps=np.ones(2), residuals_rps=np.zeros(2),
                               quality=(fit_scale_factor([1.0, -1.0, 2.0], [1.0, -1.0, 2.0],
                                                         [1.0, 1.0, 1.0])[3],))
    assert isinstance(result, ProcedureResult)
    rows = result.parameter_rows()
    assert all(isinstance(r, ReportedParameter) for r in rows)
    assert [r.name for r in rows] == ["gyro_K1_z", "gyro_bias_z"]
    assert [(r.std, r.std_noise) for r in rows] == [(1e-6, 1e-6)] * 2  # no misfit: equal
    # no acceptance limits: an explicit no decision; no triad model, no triad parameters
    assert result.passed is None and result.decision.verdict == "NO DECISION"
    assert result.calibration is None and result.triad_parameters()[0] == []
