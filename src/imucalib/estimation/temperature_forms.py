"""A fitted temperature model in the forms others hold: the twin's and a result's.

:mod:`imucalib.estimation.temperature_model` fits a :class:`TemperaturePolynomial` (Eq. (1)
there); this module converts it, without refitting, to the twin's
:class:`~imucalib.models.temperature.TemperatureDependence` and back, and to the record a
:class:`~imucalib.models.result.CalibrationResult` carries
(:class:`~imucalib.models.temperature_record.ParameterTemperatureModel`, docs/p2.md).

Contents
--------
:func:`to_temperature_dependence`, :func:`from_temperature_dependence`,
:func:`to_parameter_record`
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from imucalib._checks import check_finite_scalar
from imucalib.errors import InvalidInputError
from imucalib.estimation.temperature_model import (
    HeldOutCheck,
    TemperatureModelFit,
    TemperaturePolynomial,
)
from imucalib.models.temperature import TemperatureDependence
from imucalib.models.temperature_record import HeldOutOutcome, ParameterTemperatureModel

__all__ = ["from_temperature_dependence", "to_parameter_record", "to_temperature_dependence"]


def to_temperature_dependence(
    models: Mapping[str, TemperaturePolynomial],
) -> tuple[TemperatureDependence, dict[str, float]]:
    """Return the twin's form of fitted models: (TemperatureDependence, {name: p0 = c_0}).

    :func:`imucalib.models.temperature.evaluate_parameter` with that p0 then gives Eq. (1)
    without the leg term.

    Raises
    ------
    InvalidInputError
        Models with different T0, or one with a hysteresis term (which that form cannot hold).
    """
    t0s = {m.reference_temperature_degc for m in models.values()}
    if len(t0s) > 1:
        raise InvalidInputError(
            f"all models must share one reference temperature; got {sorted(t0s)}")
    coeffs: dict[str, NDArray[np.float64]] = {}
    rates: dict[str, NDArray[np.float64]] = {}
    base: dict[str, float] = {}
    for name, model in models.items():
        if model.leg_coefficient is not None:
            raise InvalidInputError(
                f"model {name!r} has a hysteresis (leg) term, which TemperatureDependence "
                "cannot hold")
        base[name] = model.coefficients[0]
        if model.order >= 1:
            coeffs[name] = np.array(model.coefficients[1:])
        if model.rate_coefficient is not None:
            rates[name] = np.array(model.rate_coefficient)
    t0 = t0s.pop() if t0s else 25.0
    dep = TemperatureDependence(reference_temperature_degc=t0, coefficients=coeffs,
                                rate_coefficients=rates)
    return dep, base


def from_temperature_dependence(dep: TemperatureDependence, name: str,
                                base: float) -> TemperaturePolynomial:
    """Return scalar parameter `name` of `dep` (p0 = `base`) as a :class:`TemperaturePolynomial`.

    Raises
    ------
    InvalidInputError
        A non-scalar parameter in `dep`.
    """
    p0 = check_finite_scalar(base, "base")
    poly = dep.coefficients.get(name)
    rate = dep.rate_coefficients.get(name)
    for arr, what in ((poly, "coefficients"), (rate, "rate_coefficients")):
        if arr is not None and arr.reshape(arr.shape[0] if what == "coefficients" else 1,
                                           -1).shape[1] != 1:
            raise InvalidInputError(f"`{what}[{name!r}]` must be of a scalar parameter")
    cs = (p0,) if poly is None else (p0, *(float(c) for c in poly.reshape(-1)))
    return TemperaturePolynomial(
        reference_temperature_degc=dep.reference_temperature_degc, coefficients=cs,
        rate_coefficient=None if rate is None else float(rate.reshape(-1)[0]),
    )


def to_parameter_record(fit: TemperatureModelFit, *,
                        temperature_range_degc: tuple[float, float] | None = None,
                        held_out: HeldOutCheck | None = None) -> ParameterTemperatureModel:
    """Return a fit as the record a CalibrationResult carries (σ Birge-scaled for a misfit).

    The record's covariance is :attr:`TemperatureModelFit.covariance_scaled`, so what a result
    reports is the uncertainty that owns up to a misfit (docs/processing-estimation.md).
    """
    outcome = None
    if held_out is not None:
        outcome = HeldOutOutcome(
            max_abs_z=float(np.max(np.abs(held_out.normalised_residuals))),
            chi2=float(held_out.chi2), dof=int(held_out.dof),
            p_value=float(held_out.p_value), consistent=bool(held_out.consistent))
    m = fit.model
    return ParameterTemperatureModel(
        name=fit.name, reference_temperature_degc=m.reference_temperature_degc,
        coefficients=tuple(float(c) for c in m.coefficients),
        covariance=np.asarray(fit.covariance_scaled, dtype=np.float64), chi2=float(fit.chi2),
        dof=int(fit.dof), order_criterion=fit.criterion, rate_coefficient=m.rate_coefficient,
        leg_coefficient=m.leg_coefficient, temperature_range_degc=temperature_range_degc,
        held_out=outcome)
