"""P2's per-point evaluations done at once equal the one-window (one-group) calls bit for bit.

docs/performance.md, "P2 and Allan: the fourth pass": ``pooled_standard_errors`` evaluates the
pooled noise model at every window duration of a point in one call; each row must equal
:func:`~imucalib.procedures.common.noise.window_mean_se` of that window, and the windows must
equal ``dataclasses.replace`` of the originals. ``assemble_point`` combines the orientations'
groups of windows in one reduction when they have one size; each must equal ``_combine`` of
that group alone.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from imucalib.models.noise import NoiseModel
from imucalib.procedures.common.noise import FLICKER_FACTOR, window_mean_se
from imucalib.procedures.p2.observations import P2Window, pooled_standard_errors


def _window(rng: np.random.Generator, point: int, i: int, fitted: bool) -> P2Window:
    nan = np.full(3, np.nan)
    fit = np.abs(rng.normal(size=(3, 6))) * np.array([[1e-3], [1e-9], [1e-5]]) if fitted \
        else None
    if fit is not None and i % 5 == 0:
        fit[1, 2] = np.nan  # a column whose fit failed counts as zero
    return P2Window(step_index=10 * point + i, label=f"s{i}", point=point, leg="heating",
                    held_out=False, pose="x", kind="static" if i % 2 else "rate",
                    table_rate_rps=0.0 if i % 2 else 1.0, n_revolutions=0,
                    gyro_mean_rps=rng.normal(size=3), accel_mean_mps2=rng.normal(size=3),
                    gyro_se_rps=nan, accel_se_mps2=nan, temperature_degc=25.0,
                    temperature_rate_degc_ps=0.0, duration_s=float(rng.uniform(0.0005, 30.0)),
                    n_samples=1000, n_lost=0, allan_fit=fit)


def test_pooled_standard_errors_equal_the_one_window_evaluation() -> None:
    rng = np.random.default_rng(4)
    windows = [_window(rng, point, i, fitted=i < 4 or point == 2)
               for point in range(3) for i in range(12)]
    windows.append(_window(rng, 3, 0, fitted=True))  # a point cut short: the unit's pool
    got = pooled_standard_errors(windows)
    every = [np.nan_to_num(w.allan_fit, nan=0.0) for w in windows if w.allan_fit is not None]
    for w, g in zip(windows, got, strict=True):
        mine = [np.nan_to_num(v.allan_fit, nan=0.0) for v in windows
                if v.point == w.point and v.allan_fit is not None]
        fit = np.median(np.array(mine if len(mine) >= 3 else every), axis=0)
        noise = {triad: NoiseModel(white_density=np.maximum(fit[0, cols], 0.0),
                                   bias_instability=np.sqrt(np.maximum(fit[1, cols], 0.0)
                                                            / FLICKER_FACTOR),
                                   random_walk=np.maximum(fit[2, cols], 0.0))
                 for triad, cols in (("gyro", slice(0, 3)), ("accel", slice(3, 6)))}
        gyro, accel = window_mean_se(noise, w.duration_s)
        want = dataclasses.replace(w, gyro_se_rps=gyro, accel_se_mps2=accel)
        for f in dataclasses.fields(P2Window):
            a, b = getattr(g, f.name), getattr(want, f.name)
            if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
                np.testing.assert_array_equal(a, b, err_msg=f.name)
            else:
                assert a == b, f.name


def test_groups_of_one_size_combine_as_each_group_alone() -> None:
    from imucalib.procedures.p2.analysis import _combine, _combine_each

    rng = np.random.default_rng(8)
    for size in range(1, 9):
        for _ in range(200):
            groups = [[_window(rng, 0, i, fitted=False) for i in range(size)] for _ in range(6)]
            for g in groups:
                for w in g:
                    object.__setattr__(w, "gyro_se_rps", np.abs(rng.normal(size=3))
                                       * 10.0 ** rng.uniform(-8, 2))
            got_m, got_se = _combine_each(groups, "gyro_mean_rps", "gyro_se_rps")
            for o, g in enumerate(groups):
                m, se = _combine([w.gyro_mean_rps for w in g], [w.gyro_se_rps for w in g])
                np.testing.assert_array_equal(got_m[o], m)
                np.testing.assert_array_equal(got_se[o], se)
    uneven = [[_window(rng, 0, i, fitted=False) for i in range(1 + o % 2)] for o in range(6)]
    got_m, _ = _combine_each(uneven, "accel_mean_mps2", "accel_se_mps2")
    for o, g in enumerate(uneven):
        np.testing.assert_array_equal(got_m[o], _combine([w.accel_mean_mps2 for w in g],
                                                         [w.accel_se_mps2 for w in g])[0])
