"""The shared procedure code: the triad design builder, reference inputs, window statistics."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from imucalib.conventions import AXES
from imucalib.errors import InvalidInputError, MissingSegmentError
from imucalib.estimation import build_triad_design
from imucalib.estimation.designs import TRIAD_TERMS, build_design
from imucalib.procedures.common.noise import FLICKER_FACTOR, estimate_noise, window_mean_se
from imucalib.procedures.common.reference import (
    rate_inputs_b,
    spin_axis_b,
    static_inputs_b,
    table_rotation,
)
from imucalib.procedures.common.windows import (
    RunningMoments,
    counter_times,
    harmonic_residual_std,
    whole_revolutions,
)


def _p1_design_before(x: np.ndarray, f: np.ndarray | None) -> np.ndarray:
    """P1's design matrix as p1_fit built it by hand before the builder (the reference)."""
    H = np.array(build_triad_design(x).H)
    if f is not None:
        G = np.zeros((H.shape[0], 9))
        for k in range(x.shape[0]):
            for i in range(3):
                G[3 * k + i, 3 * i:3 * i + 3] = f[k]
        H = np.hstack([H, G])
    return H


@pytest.mark.parametrize("k", [1, 6, 23])
def test_builder_reproduces_p1_designs_exactly(k):
    rng = np.random.default_rng(k)
    x, f = rng.normal(size=(k, 3)) * 9.8, rng.normal(size=(k, 3)) * 9.8
    accel = build_design(x, ("bias", "scale_misalignment"))
    np.testing.assert_array_equal(accel.H, _p1_design_before(x, None))
    assert accel.param_names == build_triad_design(x).param_names
    gyro = build_design(x, ("bias", "scale_misalignment", "g_sensitivity"), specific_force_b=f)
    np.testing.assert_array_equal(gyro.H, _p1_design_before(x, f))
    assert gyro.param_names[12:] == tuple(f"G_{i}{j}" for i in AXES for j in AXES)


def test_builder_other_terms_against_a_hand_computed_case():
    # one observation: x = (1, 2, 3), ω = (0, 0, 2) rad/s, ω̇ = (1, 0, 0) rad/s²
    x = [[1.0, 2.0, 3.0]]
    d = build_design(x, ("k2", "lever_arm", "bias"), rate_b=[[0.0, 0.0, 2.0]],
                     angular_accel_b=[[1.0, 0.0, 0.0]])
    assert d.param_names == ("K2_x", "K2_y", "K2_z",
                             *(f"L_{i}{j}" for i in AXES for j in AXES),
                             "bias_x", "bias_y", "bias_z")
    # K2: x_i² on sensor i's row
    np.testing.assert_array_equal(d.H[:, :3], np.diag([1.0, 4.0, 9.0]))
    # lever arm: C = [ω̇]× + [ω]×² = [[0,0,0],[0,0,-1],[0,1,0]] + [[-4,0,0],[0,-4,0],[0,0,0]]
    C = np.array([[-4.0, 0.0, 0.0], [0.0, -4.0, -1.0], [0.0, 1.0, 0.0]])
    expected = np.zeros((3, 9))
    for i in range(3):
        expected[i, 3 * i:3 * i + 3] = C[i]
    np.testing.assert_array_equal(d.H[:, 3:12], expected)
    np.testing.assert_array_equal(d.H[:, 12:], np.eye(3))
    # the lever-arm rows predict the size effect: r_i = (0.1, 0, 0) for every sensor
    r = np.array([0.1, 0.0, 0.0])
    w, dw = np.array([0.0, 0.0, 2.0]), np.array([1.0, 0.0, 0.0])
    feel = np.cross(dw, r) + np.cross(w, np.cross(w, r))
    np.testing.assert_allclose(d.H[:, 3:12] @ np.tile(r, 3), feel)


def test_builder_refuses_what_it_cannot_build():
    with pytest.raises(InvalidInputError, match="distinct names of"):
        build_design([[1.0, 0, 0]], ("bias", "bias"))
    with pytest.raises(InvalidInputError, match="distinct names of"):
        build_design([[1.0, 0, 0]], ("size",))
    with pytest.raises(InvalidInputError, match="needs `specific_force_b`"):
        build_design([[1.0, 0, 0]], ("g_sensitivity",))
    with pytest.raises(InvalidInputError, match="needs `rate_b`"):
        build_design([[1.0, 0, 0]], ("lever_arm",))
    assert set(TRIAD_TERMS) == {"bias", "scale_misalignment", "k2", "g_sensitivity",
                                "lever_arm"}


def test_static_inputs_follow_p1s_formula():
    g, earth_t = 9.8, np.array([1e-5, 0.0, 5e-5])
    for pitch, roll in [(0.0, 0.0), (90.0, 0.0), (30.0, 120.0), (-45.0, 270.0)]:
        th, ph = math.radians(pitch), math.radians(roll)
        rate_b, force_b = static_inputs_b(("pitch", "roll"), [th, ph], g, earth_t)
        np.testing.assert_allclose(
            force_b, g * np.array([math.sin(th), math.sin(ph) * math.cos(th),
                                   math.cos(th) * math.cos(ph)]), atol=1e-12)
        rot = table_rotation(("pitch", "roll"), [th, ph])
        np.testing.assert_allclose(rot.apply(rate_b), earth_t, atol=1e-18)


def test_rate_inputs_keep_the_components_along_the_turning_axis():
    g, earth_t = 9.8, np.array([2e-5, -1e-5, 5e-5])
    angles = np.radians([0.0, 90.0])  # roll 90°: pitch turns the IMU about z
    a_b = spin_axis_b(("pitch", "roll"), 0, angles)
    np.testing.assert_allclose(np.abs(a_b), [0.0, 0.0, 1.0], atol=1e-12)
    rate_b, force_b = rate_inputs_b(("pitch", "roll"), 0, angles, 1.0, g, earth_t)
    a_t = table_rotation(("pitch", "roll"), angles).apply(a_b)
    np.testing.assert_allclose(rate_b, (1.0 + earth_t @ a_t) * a_b)
    np.testing.assert_allclose(force_b, g * a_t[2] * a_b, atol=1e-12)


def test_running_moments_equal_the_whole_window():
    rng = np.random.default_rng(3)
    raw = rng.normal(5.0, 1.0, size=(1000, 2))
    filt = raw * 0.5 + 2.5
    acc = RunningMoments()
    for block in np.array_split(np.arange(1000), 7):
        acc.add(raw[block], filt[block])
    assert acc.n == 1000
    np.testing.assert_allclose(acc.mean, raw.mean(axis=0), rtol=1e-13)
    np.testing.assert_allclose(acc.std, filt.std(axis=0, ddof=1), rtol=1e-10)


def test_harmonic_residual_removes_the_once_per_revolution_term():
    rng = np.random.default_rng(4)
    angle = np.linspace(0.0, 4 * math.pi, 20000)
    noise = rng.normal(0.0, 0.01, size=(angle.size, 1))
    values = 1.0 + 0.5 * np.sin(angle + 0.3)[:, None] + noise
    assert harmonic_residual_std(values, angle)[0] == pytest.approx(0.01, rel=0.03)


def test_noise_model_of_window_means_from_the_longest_static_record():
    fit = np.zeros((3, 6))
    fit[0] = 1e-4  # white only: σ(τ) = N/√τ
    windows = [SimpleNamespace(kind="static", duration_s=300.0, allan_fit=fit),
               SimpleNamespace(kind="static", duration_s=3600.0, allan_fit=fit * 2),
               SimpleNamespace(kind="rate", duration_s=9999.0, allan_fit=fit * 3),
               SimpleNamespace(kind="static", duration_s=60.0, allan_fit=None)]
    noise = estimate_noise(windows)
    np.testing.assert_allclose(noise["gyro"].white_density, 2e-4)
    gyro, accel = window_mean_se(noise, 100.0)
    np.testing.assert_allclose(gyro, 2e-5, rtol=1e-12)
    np.testing.assert_allclose(accel, 2e-5, rtol=1e-12)
    assert estimate_noise(windows[:1], min_duration_s=600.0) == {}


def test_counter_times_and_whole_revolutions():
    """The shared window checks: dropouts, a backwards counter, the revolutions of a turn."""
    counter = np.arange(1000)
    t_rx = counter / 100.0
    t, period, lost = counter_times("w", counter, t_rx, max_lost_fraction=0.01, max_gap_s=0.5,
                                    reconstruct=False)
    assert lost == 0 and abs(period - 0.01) < 1e-12
    holed = np.delete(counter, np.s_[100:180])  # 0.8 s lost
    with pytest.raises(MissingSegmentError, match=r"80 of 1000 samples lost to dropouts"):
        counter_times("w", holed, holed / 100.0, max_lost_fraction=0.1, max_gap_s=0.5,
                      reconstruct=False)
    with pytest.raises(InvalidInputError, match="repeats or goes backwards"):
        counter_times("w", counter[::-1], t_rx, max_lost_fraction=0.01, max_gap_s=0.5,
                      reconstruct=False)
    # 10 s at 90 °/s: 2.5 revolutions; a once-per-revolution term averages out
    rate = np.radians(90.0)
    angle = rate * t
    values = np.column_stack([1.0 + 0.5 * np.cos(angle), np.full(t.size, 2.0)])
    turn = whole_revolutions("w", t, values, t, angle, commanded_revolutions=2)
    assert turn.n_revolutions == 2 and abs(turn.rate_rps - rate) < 1e-9
    np.testing.assert_allclose(turn.mean, [1.0, 2.0], atol=1e-3)
    assert np.abs(turn.residual).max() < 1e-9
    with pytest.raises(MissingSegmentError,
                       match=r"holds 2 whole revolution\(s\) of the 4 commanded"):
        whole_revolutions("w", t, values, t, angle, commanded_revolutions=4)


def test_noise_model_pools_the_records_about_as_long_as_the_longest():
    """Several equally long records (P1's repetitions) are averaged, not picked by rounding."""
    a, b = np.zeros((3, 6)), np.zeros((3, 6))
    a[0], b[0] = 1e-4, 3e-4  # white densities N
    a[1], b[1] = 4e-10, 2e-10  # flicker plateaus C_B
    a[2], b[2] = 0.0, 2e-6  # random-walk densities K

    def model(d_a, d_b, short=None):
        short = np.zeros((3, 6)) if short is None else short
        return estimate_noise([SimpleNamespace(kind="static", duration_s=d_a, allan_fit=a),
                               SimpleNamespace(kind="static", duration_s=d_b, allan_fit=b),
                               SimpleNamespace(kind="static", duration_s=250.0,
                                               allan_fit=short)])

    one, other = model(600.0, np.nextafter(600.0, 0.0)), model(np.nextafter(600.0, 0.0), 600.0)
    for triad in ("gyro", "accel"):
        np.testing.assert_allclose(one[triad].white_density, np.sqrt((1e-8 + 9e-8) / 2),
                                   rtol=1e-12)
        np.testing.assert_allclose(one[triad].bias_instability,
                                   np.sqrt(3e-10 / FLICKER_FACTOR), rtol=1e-12)
        np.testing.assert_allclose(one[triad].random_walk, np.sqrt(2e-12), rtol=1e-12)
        np.testing.assert_allclose(one[triad].white_density, other[triad].white_density,
                                   rtol=1e-12)
    # a record shorter than half the longest stays out; weights follow the durations
    uneven = model(900.0, 600.0, short=np.full((3, 6), 1.0))
    np.testing.assert_allclose(uneven["gyro"].white_density, np.sqrt(0.6e-8 + 0.4 * 9e-8),
                               rtol=1e-12)
