"""Shared fixtures of the estimation tests: a known-orientation accelerometer triad on P1's plan."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from imucalib import units
from imucalib.estimation.designs import SIX_POSITION_UP_B
from imucalib.models.triad import TriadModel, apply_triad

G = units.G0_MPS2
#: Standard deviation of one position mean: 150 µg/√Hz over 5 s (docs/equations.md §12 example).
SIGMA_MPS2 = 67.1 * units.UG


def make_truth(seed: int = 7) -> TriadModel:
    """A tactical-grade accelerometer triad: 1 mg biases, 300 ppm scale, 0.5 mrad misalignment."""
    rng = np.random.default_rng(seed)
    M = rng.normal(0.0, 0.5e-3, (3, 3))
    M[np.diag_indices(3)] = rng.normal(0.0, 300e-6, 3)
    return TriadModel(kind="accel", bias=rng.normal(0.0, 1.0 * units.MG, 3), scale_misalignment=M)


def truth_vector(model: TriadModel) -> np.ndarray:
    """The 12 parameters in TRIAD_PARAMETER_NAMES order."""
    return np.concatenate([model.bias, model.scale_misalignment.ravel()])


def observations(model: TriadModel, up_b: np.ndarray, rng: np.random.Generator,
                 sigma: float = SIGMA_MPS2) -> tuple[np.ndarray, np.ndarray]:
    """Noisy position means y_k − x_k, flattened (row 3k + i), and the inputs x_k = g·u_k."""
    x = G * np.asarray(up_b, dtype=float)
    y = apply_triad(model, x) + rng.normal(0.0, sigma, x.shape)
    return (y - x).ravel(), x


@pytest.fixture
def truth() -> TriadModel:
    return make_truth()


@pytest.fixture
def six_up() -> np.ndarray:
    return np.array(SIX_POSITION_UP_B)


@pytest.fixture
def kit() -> SimpleNamespace:
    """The helpers above, for tests (conftest modules are not importable under importlib mode)."""
    return SimpleNamespace(G=G, SIGMA=SIGMA_MPS2, make_truth=make_truth, truth_vector=truth_vector,
                           observations=observations)
