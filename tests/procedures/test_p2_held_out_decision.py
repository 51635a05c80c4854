"""P2 with a held-out inconsistency: the decision names it (docs/p2.md, "The decision").

A synthetic unit (the full sweep, two held-out points) whose gyro x bias at the −10 °C
held-out point is pushed 1 mrad/s (0.06 °/s) off its truth: the error left after compensation
stays within the consumer limit of 0.5 °/s, so the unit passes P2's rule, and its temperature
model of ``gyro_bias_x`` does not predict that point. The decision carries the check
``held-out consistency of the temperature models`` whose rows name it with its z or p-value,
whose verdict is None (not part of the rule) and whose summary and note say so in words; the
batch's decision, the terminal line beside "N of M unit(s) passed", the unit's report (its
decision and its "may be applied") and the summary all say it.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from rich.console import Console

from imucalib.models.result_document import result_document
from imucalib.procedures.p2.analysis import analyze_unit
from imucalib.procedures.p2.batch import P2BatchResult, summary_rows
from imucalib.procedures.p2.console import render_p2
from imucalib.procedures.p2.observations import UnitObservations
from imucalib.procedures.p2.report import content
from imucalib.procedures.p2.result import (
    DECISION_RULE,
    HELD_OUT_ALPHA,
    HELD_OUT_CHECK,
    HELD_OUT_Z_LIMIT,
    P2UnitResult,
)
from imucalib.procedures.p2.summary_report import summary_report

from ._p2_synthetic import draw_truth, unit_observations

#: The push of gyro x's output at the −10 °C held-out point. [rad/s]
PUSH = 1e-3


def _pushed(obs: UnitObservations, temperature_degc: float, push: float) -> UnitObservations:
    """Add `push` to gyro x's mean in every window of the held-out point at `temperature_degc`."""
    windows = tuple(
        dataclasses.replace(w, gyro_mean_rps=w.gyro_mean_rps + np.array([push, 0.0, 0.0]))
        if w.held_out and abs(w.temperature_degc - temperature_degc) < 1.0 else w
        for w in obs.windows)
    return dataclasses.replace(obs, windows=windows)


@pytest.fixture(scope="module")
def units() -> tuple[P2UnitResult, P2UnitResult]:
    """The unit as drawn, and the same unit with its −10 °C held-out point pushed."""
    rng = np.random.default_rng(21)
    obs = unit_observations(draw_truth(rng), rng)
    return analyze_unit(obs), analyze_unit(_pushed(obs, -10.0, PUSH))


def test_the_decision_names_the_inconsistent_model_and_says_it_is_not_in_the_rule(units):
    plain, pushed = units
    assert plain.held_out["gyro_bias_x"].consistent
    assert not pushed.held_out["gyro_bias_x"].consistent
    assert "gyro_bias_x" in pushed.held_out_inconsistent
    # the unit passes P2's rule: the push is far below the 0.5 °/s it allows
    assert pushed.passed is True and pushed.reasons == ()
    decision = pushed.decision
    assert decision.verdict == "PASS" and decision.rule == DECISION_RULE
    assert decision.failed == () and decision.not_assessed == ()
    check = next(c for c in decision.checks if c.name == HELD_OUT_CHECK)
    assert check.passed is None  # reported with the decision, not counted in its verdict
    assert [r.name.split(" ")[0] for r in check.rows] == list(pushed.held_out_inconsistent)
    row = next(r for r in check.rows if r.name.startswith("gyro_bias_x"))
    held = pushed.held_out["gyro_bias_x"]
    z = float(np.max(np.abs(held.normalised_residuals)))
    if z > HELD_OUT_Z_LIMIT:
        assert row.value == pytest.approx(z) and row.limit == HELD_OUT_Z_LIMIT
    else:
        assert row.value == held.p_value and row.limit == HELD_OUT_ALPHA
    assert row.passed is False and f"p = {held.p_value:.2g}" in row.detail
    n_bad, n = len(pushed.held_out_inconsistent), len(pushed.held_out)
    assert check.summary.startswith(f"{n_bad} of {n} temperature models NOT consistent")
    assert "gyro_bias_x" in check.summary and "not part of P2's rule" in check.summary
    (note,) = [x for x in decision.notes if x.startswith(HELD_OUT_CHECK)]
    assert "gyro_bias_x" in note and "not counted in the verdict" in note
    assert "gyro_bias_x" in decision.summary()  # the one-line verdict names it too
    # and the result file keeps it
    stored = result_document(pushed)["decision"]
    held_check = next(c for c in stored["checks"] if c["name"] == HELD_OUT_CHECK)
    assert held_check["passed"] is None and held_check["rows"]
    assert stored["verdict"] == "PASS"


def test_a_unit_whose_models_all_hold_says_so_in_the_same_check(units):
    plain, pushed = units
    # the unit as drawn: one model of 36 inconsistent by chance, within what chance gives
    (note,) = [x for x in plain.decision.notes if x.startswith(HELD_OUT_CHECK)]
    assert plain.held_out_inconsistent == ("accel_M_xz",) and "within what chance gives" in note
    # the pushed one too (two of 36: binomial p 0.11); a unit whose every model holds: no rows
    assert "within what chance gives" in next(x for x in pushed.decision.notes
                                              if x.startswith(HELD_OUT_CHECK))
    holding = dataclasses.replace(plain, held_out={
        n: dataclasses.replace(c, consistent=True) for n, c in plain.held_out.items()})
    check = next(c for c in holding.decision.checks if c.name == HELD_OUT_CHECK)
    assert check.passed is None and check.rows == ()
    assert check.summary.startswith("all 36 temperature models consistent at the held-out points")
    assert "not part of P2's rule" in check.summary
    assert not any(n.startswith(HELD_OUT_CHECK) for n in holding.decision.notes)
    # many inconsistent models: more than chance gives, said in the note
    failing = dataclasses.replace(plain, held_out={
        n: dataclasses.replace(c, consistent=False) for n, c in plain.held_out.items()})
    (note,) = [x for x in failing.decision.notes if x.startswith(HELD_OUT_CHECK)]
    assert "36 of 36 NOT consistent" in note and "more than chance gives" in note
    assert failing.passed is plain.passed  # still not part of the verdict


def test_the_lot_line_the_batch_and_the_summary_count_the_units(units):
    plain, pushed = units
    second = dataclasses.replace(pushed, unit="U2")
    batch = P2BatchResult(recordings=("a.h5",), results=(plain, second))
    decision = batch.decision
    assert decision.verdict == ("PASS" if plain.passed else "FAIL")
    assert [c.name for c in decision.checks] == ["unit U1", "unit U2"]
    assert "NOT consistent at the held-out points" in decision.checks[1].summary
    with_bad = [u.unit for u in batch.results if u.held_out_inconsistent]
    (note,) = decision.notes
    assert note.startswith(f"{len(with_bad)} of 2 unit(s) have temperature models NOT "
                           "consistent") and "U2" in note
    console = Console(record=True, width=240)
    render_p2(console, batch, [])
    text = " ".join(console.export_text().split())
    n_ok = sum(bool(u.passed) for u in batch.results)
    assert (f"({n_ok} of 2 unit(s) passed; {len(with_bad)} of 2 unit(s) with temperature "
            "models NOT consistent at the held-out points") in text
    assert f"note (U2): {HELD_OUT_CHECK}:" in text
    rows = {r["unit"]: r for r in summary_rows(batch)}
    assert "gyro_bias_x" in rows["U2"]["held_out_inconsistent"]
    doc = summary_report(batch)
    results = " ".join(doc.section("5.").paragraphs)
    assert f"{len(with_bad)} of 2 unit(s) have temperature models NOT consistent" in results
    assert "unit(s) with temperature models NOT consistent" in " ".join(
        doc.section("6.").paragraphs)


def test_the_units_report_qualifies_its_pass_and_its_may_be_applied(units):
    _, pushed = units
    report = content(pushed, {})
    assert report is not None and report.passed is True
    n_bad = len(pushed.held_out_inconsistent)
    assert report.decision.startswith("Every check of P2's rule passed.")
    assert f"{n_bad} of 36 temperature models are NOT consistent" in report.decision
    (applied,) = [r for r in report.recommendations if "may be applied" in r]
    assert f"{n_bad} temperature model(s) do not predict the held-out points" in applied
    results = next(s for s in report.sections if s.title.startswith("5."))
    assert any(p.startswith("Not part of the rule: " + HELD_OUT_CHECK)
               for p in results.paragraphs)
