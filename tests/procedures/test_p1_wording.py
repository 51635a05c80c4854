"""P1's plan description and messages cite the project's own P1 page (docs/p1.md)."""

from __future__ import annotations

import pytest

from imucalib.errors import ConfigurationError
from imucalib.procedures.p1.analysis import P1Options, analyze_p1
from imucalib.procedures.p1.plan import generate_p1_plan


def test_the_plan_description_cites_docs_p1():
    plan = generate_p1_plan(static_s=600.0, repetitions=2)
    assert plan.description == ("P1 (docs/p1.md) on a dual-axis table: six positions, 10 min "
                                "static, 5 rates per axis, held-out checks, 2 repetition(s).")


def test_a_rate_plan_below_the_minimum_cites_p1_step_3():
    with pytest.raises(ConfigurationError,
                       match=r"`rates_dps` needs at least 3 points with both signs and 0 "
                             r"\(procedure P1, docs/p1\.md step 3, uses 5–7\); "
                             r"got \[0\.0, 50\.0\]"):
        generate_p1_plan(rates_dps=(0.0, 50.0))


def test_one_repetition_leaves_repeatability_unassessed_citing_rule_6(p1_tools, tmp_path):
    path = p1_tools.run_twin(p1_tools.p1_plan("tactical", 5), tmp_path / "one.h5")
    checks = {c.name: c for c in analyze_p1(path, options=P1Options(hash_recording=False)).checks}
    rep = checks["repeatability"]
    assert rep.passed is None
    assert rep.summary == ("1 repetition in the recording: repeatability needs at least 2 "
                          "(P1 rule 6 asks for 3, docs/p1.md)")
