"""P1's observation extraction (and so `calibrate`) reports its progress over the steps."""

from __future__ import annotations

import itertools

from imucalib.io import open_recording
from imucalib.procedures.p1.observations import extract_p1_observations


def test_extraction_progress_fractions_increase_to_one(consumer_run):
    fractions: list[float] = []
    with open_recording(consumer_run) as rec:
        obs = extract_p1_observations(rec, progress=fractions.append)
    assert len(fractions) >= len(obs.windows)
    assert all(0.0 <= f <= 1.0 for f in fractions)
    assert all(b > a for a, b in itertools.pairwise(fractions))
    assert fractions[-1] == 1.0


def test_procedure_analyze_passes_progress_on(consumer_run):
    from imucalib.procedures import registry

    fractions: list[float] = []
    registry.get("p1").analyze(consumer_run, progress=fractions.append)
    assert fractions and fractions[-1] == 1.0
