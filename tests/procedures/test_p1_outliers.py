"""P1's default outlier rule leaves the twin's Gaussian noise alone and says where it cut.

On tests/data/p1_v1.h5 (23 windows, 9 400 rows of 6 channels) three passes of the robust 3σ
rule, P1's former default, flagged 53 values (0.094 %); the robust rule flags 11 (0.020 %), at
most the α = 0.01 per window and channel its threshold allows plus a few at the edges of the
fast rate windows, where gravity turns through the accelerometers.
"""

from __future__ import annotations

from pathlib import Path

from imucalib.io import open_recording
from imucalib.procedures.p1.observations import P1Processing, extract_p1_observations
from imucalib.procedures.p1.window_reduction import OUTLIER_TIMES_KEPT

V1_FILE = Path(__file__).parents[1] / "data" / "p1_v1.h5"


def test_default_rule_flags_almost_nothing_and_says_where() -> None:
    assert P1Processing().outlier_test == "robust"
    with open_recording(V1_FILE) as rec:
        obs = extract_p1_observations(rec)
    values = 6 * sum(w.n_samples for w in obs.windows)
    flagged = sum(w.n_outliers for w in obs.windows)
    assert flagged / values < 5e-4, f"{flagged} of {values} values flagged"
    for w in obs.windows:
        assert len(w.outliers_per_channel) == 6 and sum(w.outliers_per_channel) == w.n_outliers
        n_times = len(w.outlier_times_s)  # rows: one row may hold several flagged channels
        assert (1 <= n_times <= min(OUTLIER_TIMES_KEPT, w.n_outliers)) == (w.n_outliers > 0)
        assert list(w.outlier_times_s) == sorted(w.outlier_times_s)
    assert flagged > 0  # the report has something to say where


def test_none_reports_no_channels() -> None:
    with open_recording(V1_FILE) as rec:
        obs = extract_p1_observations(rec, processing=P1Processing(outlier_test="none"))
    assert all(w.n_outliers == 0 and w.outliers_per_channel == () for w in obs.windows)
