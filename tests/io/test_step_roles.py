"""The role grammar of the file-format layer, and the frozen version 1 mapping's roles."""

from __future__ import annotations

import pytest

from imucalib.io import step_roles
from imucalib.io.step_roles import is_role, role_from_tags, split_role
from imucalib.procedures import registry


@pytest.mark.parametrize(("role", "parts"), [
    ("p1.accel-position", ("p1", "accel-position")),
    ("rate-transfer.rate", ("rate-transfer", "rate")),
    ("scale-factor.rate.fast", ("scale-factor", "rate.fast")),
])
def test_a_role_splits_at_its_first_dot(role, parts):
    assert split_role(role) == parts and is_role(role)


@pytest.mark.parametrize("role", ["", "warm-up", ".rate", "p1.", "p1..rate", "p1.gyro rate",
                                  "p 1.rate", "p1.rate\n", "p1." + "x" * 200])
def test_a_malformed_role_is_refused(role):
    assert not is_role(role)
    with pytest.raises(ValueError, match=r"is not '<procedure>\.<purpose>'"):
        split_role(role)


def test_the_v1_mapping_gives_roles_that_p1_and_allan_still_have():
    """The frozen mapping names its roles itself; they must stay roles of P1 and Allan."""
    kinds = ("position", "static", "rate")
    tag_sets = (("calibration", "six-position"), ("calibration", "gyro-bias"),
                ("calibration", "rate"), ("verification", "rate"), ("verification",),
                ("allan",))
    given = {role_from_tags(k, t, p) for k in kinds for t in tag_sets for p in ("", "p1", "allan")}
    given.discard("")
    assert {split_role(r)[0] for r in given} == {"p1", "allan"}
    registry.check_roles(given)
    assert given == {*registry.get("p1").roles, *registry.get("allan").roles}


def test_io_holds_no_procedure_role_constant():
    """The roles live in their procedures' roles.py; the transitional re-exports are gone."""
    for name in ("TUMBLE_POSITION", "TUMBLE_DRIFT", "RANDOM_DRIFT_POSITION", "P1_GYRO_RATE"):
        with pytest.raises(AttributeError):
            getattr(step_roles, name)
