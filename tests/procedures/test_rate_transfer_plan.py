"""The rate-transfer and installation plans: steps, roles, tags, rates and refusals."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import ConfigurationError
from imucalib.plan.schema import OperatorCheckStep, RateStep
from imucalib.procedures import registry
from imucalib.procedures.installation.plan import generate_installation_plan
from imucalib.procedures.installation.roles import INSTALLATION_RATE, INSTALLATION_REMOUNT
from imucalib.procedures.rate_transfer.plan import DEFAULT_RATES_DPS, generate_rate_transfer_plan
from imucalib.procedures.rate_transfer.roles import RATE_TRANSFER_RATE, RATE_TRANSFER_REMOUNT


def test_default_plan_has_the_chapter_rates_about_each_axis() -> None:
    plan = registry.get("rate-transfer").generate_plan()
    assert plan.procedure == "rate-transfer"
    remounts = [s for s in plan.steps if isinstance(s, OperatorCheckStep) and s.remount]
    assert [(s.remount, s.role, s.tags) for s in remounts] == [
        ("+x", RATE_TRANSFER_REMOUNT, ("axis=x",)), ("+y", RATE_TRANSFER_REMOUNT, ("axis=y",)),
        ("+z", RATE_TRANSFER_REMOUNT, ("axis=z",))]
    turns = [s for s in plan.steps if isinstance(s, RateStep)]
    assert len(turns) == 3 * 2 * len(DEFAULT_RATES_DPS)
    assert all(s.role == RATE_TRANSFER_RATE and s.revolutions == 2 and s.axis == 0
               for s in turns)
    x_rates = [s.rate_dps for s in turns if "axis=x" in s.tags]
    assert x_rates == [s * r for r in DEFAULT_RATES_DPS for s in (1, -1)]
    assert plan.twin is not None and plan.twin.table.kind == "single-axis"
    assert plan.twin.table.grade == "high" and plan.twin.fixture.kind == "hexahedral"


def test_log_spaced_rates() -> None:
    plan = generate_rate_transfer_plan(log_spaced=(1.0, 100.0, 5), axes=("z",))
    rates = [s.rate_dps for s in plan.steps if isinstance(s, RateStep)]
    assert rates[::2] == pytest.approx([1.0, np.sqrt(10), 10.0, np.sqrt(1000), 100.0])
    assert rates[1::2] == pytest.approx([-r for r in rates[::2]])


def test_installation_plan() -> None:
    plan = registry.get("installation").generate_plan()
    turns = [s for s in plan.steps if isinstance(s, RateStep)]
    assert [(s.rate_dps, s.tags[0]) for s in turns] == [
        (r, f"axis={a}") for a in "xyz" for r in (30.0, -30.0)]
    assert all(s.role == INSTALLATION_RATE for s in turns)
    assert sum(isinstance(s, OperatorCheckStep) and s.role == INSTALLATION_REMOUNT
               for s in plan.steps) == 3


@pytest.mark.parametrize(("options", "match"), [
    ({"rates_dps": (10.0, 10.0)}, "distinct"),
    ({"rates_dps": (0.0, 10.0)}, "> 0"),
    ({"log_spaced": (10.0, 1.0, 4)}, "min < max"),
    ({"axes": ("x", "w")}, "axes must be among"),
    ({"axes": ("x", "x")}, "distinct axes"),
    ({"revolutions": 1}, "revolutions"),
    ({"rates_dps": (500.0,), "grade": "navigation"}, r"500 °/s reaches the gyro range ±400"),
])
def test_bad_options_are_refused(options: dict[str, object], match: str) -> None:
    with pytest.raises(ConfigurationError, match=match):
        generate_rate_transfer_plan(**options)  # type: ignore[arg-type]


def test_installation_refuses_a_rate_beyond_the_range() -> None:
    with pytest.raises(ConfigurationError, match="2500 °/s reaches the gyro range ±2000"):
        generate_installation_plan(rate_dps=2500.0, grade="consumer")


def test_cli_writes_a_rate_transfer_plan_with_its_rates(tmp_path):
    from typer.testing import CliRunner

    from imucalib.cli import app
    from imucalib.plan.io import load_plan

    path = tmp_path / "rt.toml"
    res = CliRunner().invoke(app, ["plan", "new", "rate-transfer", "-o", str(path),
                                   "--rates", "5,10,20,40"])
    assert res.exit_code == 0, res.output
    plan = load_plan(path)
    rates = {abs(s.rate_dps) for s in plan.steps if s.role == "rate-transfer.rate"}
    assert rates == {5.0, 10.0, 20.0, 40.0}
    res = CliRunner().invoke(app, ["plan", "new", "p1", "-o", str(tmp_path / "x.toml"),
                                   "--log-spaced", "5,50,4"])
    assert res.exit_code == 2 and "plan new rate-transfer --log-spaced" in res.output
