"""The tumble on the twin: plan → SimStation run → Recording → analysis, against the truth.

A dual-axis high-grade table (1″ encoder error, 1″ wobble, 2″ non-orthogonality), a
navigation-grade IMU with white noise (a bias that does not wander) and K3, Koq injected; every
coefficient of every (head axis, accelerometer) and every triad parameter within 4σ of the
twin's truth, over three seeds. The twin's triad has no cross-coupling: Kip = Kpp = 0.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imucalib.errors import (
    InsufficientExcitationError,
    InvalidInputError,
    MissingSegmentError,
    RecordingError,
)
from imucalib.io.opening import open_recording
from imucalib.plan.schema import Plan
from imucalib.procedures import registry
from imucalib.procedures.tumble.analysis import TumbleOptions, TumbleResult, analyze_tumble
from imucalib.procedures.tumble.plan import UNIT_NAME, generate_tumble_plan
from imucalib.station.runner import RunOptions, run_plan
from imucalib.station.sim import SimStation

K3 = (2e-6, -1.5e-6, 1.5e-6)  # [1/(m/s²)²]: 190, −140, 140 µg/g³
KOQ = (4e-5, -3e-5, 2.5e-5)  # [1/(m/s²)]: 390, −290, 245 µg/g²
AXES = "xyz"


def tumble_plan(seed: int, **options: Any) -> Plan:
    """A short tumble plan (24 positions, 20 s at 50 Hz); the twin: white noise, K3, Koq."""
    opts = {"n_positions": 24, "record_s": 20.0, "settle_s": 3.0, "sample_rate_hz": 50.0,
            **options}
    plan = generate_tumble_plan(seed=seed, **opts)
    assert plan.twin is not None
    imus = tuple(i.model_copy(update={"noise": "white",
                                      "errors": {"accel.k3": K3, "accel.koq": KOQ}})
                 for i in plan.twin.imus)
    return plan.model_copy(update={"twin": plan.twin.model_copy(update={"imus": imus})})


def run(plan: Plan, path: Path) -> Path:
    assert plan.twin is not None
    station = SimStation(plan.twin)
    summary = run_plan(plan, station, path, options=RunOptions(tick_s=5.0, truth=station.truth))
    assert summary.status == "done", summary.reason
    return path


def truth_of(path: Path) -> dict[str, np.ndarray]:
    with open_recording(path) as rec:
        accel = rec.truth["imu_models"][UNIT_NAME]["accel"]
    return {k: np.asarray(accel[k], dtype=float) for k in ("bias", "scale_misalignment", "k2",
                                                           "k3", "koq")}


def coefficient_z(result: TumbleResult, truth: dict[str, np.ndarray]) -> dict[str, float]:
    """z of every fitted coefficient against the twin's, in the IEEE form (T.1)/(T.12)."""
    M = truth["scale_misalignment"]
    out = {}
    for a in result.accelerometers:
        i, p = AXES.index(a.sensor), AXES.index(a.pendulous_axis)
        k1 = 1.0 + M[i, i]
        want = {"K0": truth["bias"][i] / k1, "K1": k1, "delta": M[i, p] / k1,
                "K2": truth["k2"][i] * k1, "Kip": 0.0, "K3": truth["k3"][i] * k1**2,
                "Koq": truth["koq"][i] * k1}
        for c in a.fit.names:
            out[f"{c}_{a.key}"] = (a.fit.value(c) - want[c]) / a.fit.std(c)
    names, values, cov = result.triad_parameters()
    for n, v, s in zip(names, values, np.sqrt(np.diag(cov)), strict=True):
        kind, axes = n.split("_")[1], n.split("_")[2]
        i = AXES.index(axes[0])
        if kind == "M":
            want_t = M[i, AXES.index(axes[-1])]
        else:
            want_t = truth["bias" if kind == "bias" else "k2"][i]
        out[n] = (v - want_t) / s
    return out


@pytest.fixture(scope="module", params=[0, 1, 2])
def twin_run(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
             ) -> tuple[Path, TumbleResult]:
    path = run(tumble_plan(request.param),
               tmp_path_factory.mktemp("tumble") / f"t{request.param}.h5")
    return path, analyze_tumble(path)


def test_every_coefficient_within_4_sigma_of_the_truth(twin_run: tuple[Path, TumbleResult]
                                                       ) -> None:
    path, result = twin_run
    z = coefficient_z(result, truth_of(path))
    assert len(result.accelerometers) == 6  # two accelerometers about each of three head axes
    assert len(z) == 6 * 7 + 15  # 7 coefficients each, then b (3), M (9), K2 (3)
    worst = max(z, key=lambda k: abs(z[k]))
    assert abs(z[worst]) < 4.0, (worst, z[worst])
    # the injected K3 and Koq are seen: the estimate of each is many σ from zero
    for a in result.accelerometers:
        assert abs(a.fit.value("Koq")) > 3 * a.fit.std("Koq"), a.key
        assert abs(a.fit.value("K3")) > 3 * a.fit.std("K3"), a.key


def test_result_rows_triad_and_fit_quality(twin_run: tuple[Path, TumbleResult]) -> None:
    _, result = twin_run
    assert result.procedure == "tumble" and result.unit == UNIT_NAME and result.passed is None
    names, _, cov = result.triad_parameters()
    assert names[:3] == ["accel_bias_x", "accel_bias_y", "accel_bias_z"]
    assert {f"accel_M_{i}{j}" for i in AXES for j in AXES} <= set(names)
    assert cov.shape == (15, 15) and np.all(np.linalg.eigvalsh(cov) > 0)
    rows = {r[0]: r for r in result.parameter_rows()}
    assert rows["K1_x_head_z"][3] == "1" and rows["accel_K2_z"][3] == "1/(m/s^2)"
    for a in result.accelerometers:
        assert a.fit.quality.dof == 24 - 7
        assert a.fit.quality.reduced_chi2 < a.fit.quality.expected_high * 1.5
    data = result.to_dict()
    assert data["procedure"] == "tumble" and len(data["accelerometers"]) == 6


def test_dft_form_agrees_with_least_squares(twin_run: tuple[Path, TumbleResult]) -> None:
    path, lsq = twin_run
    dft = analyze_tumble(path, options=TumbleOptions(method="dft"))
    for a, b in zip(lsq.accelerometers, dft.accelerometers, strict=True):
        assert b.fit.fourier.method == "dft"
        for c in a.fit.names:
            # the DFT takes the commanded angles, LSQ the measured: apart by the encoder error
            # (1″ ≈ 4.8 µg of g per position, the σ's Type B share, Eq. (T.13))
            assert abs(a.fit.value(c) - b.fit.value(c)) < 3.0 * a.fit.std(c), (a.key, c)


def test_registry_identifies_and_analyses(twin_run: tuple[Path, TumbleResult]) -> None:
    path, _ = twin_run
    with open_recording(path) as rec:
        assert registry.identify(rec) == "tumble"
    result = registry.get("tumble").analyze(path, options={"coefficients": "K0,K1,delta,K2"})
    assert all(a.fit.names == ("K0", "K1", "delta", "K2") for a in result.accelerometers)


# --- bad inputs -----------------------------------------------------------------------------

def test_a_missing_position_is_named(tmp_path: Path) -> None:
    plan = tumble_plan(5, axes=("z",), record_s=5.0)
    steps = tuple(s for s in plan.steps if "angle=150" not in s.tags)
    path = run(plan.model_copy(update={"steps": steps}), tmp_path / "missing.h5")
    with pytest.raises(MissingSegmentError,
                       match=r"head axis z: the 24-position sequence lacks the position\(s\) at "
                             "150°"):
        analyze_tumble(path)


def test_recording_without_tumble_roles(tmp_path: Path) -> None:
    plan = tumble_plan(6, axes=("z",), n_positions=4, record_s=5.0)
    steps = tuple(s.model_copy(update={"role": ""}) for s in plan.steps)
    path = run(plan.model_copy(update={"steps": steps}), tmp_path / "noroles.h5")
    with pytest.raises(RecordingError, match="no step has a tumble role"):
        analyze_tumble(path)


def test_dft_needs_equally_spaced_positions_and_lsq_does_not(tmp_path: Path) -> None:
    plan = tumble_plan(7, axes=("z",), record_s=5.0)
    steps = []
    for s in plan.steps:
        if s.role:
            tags = tuple(t for t in s.tags if not t.startswith("positions="))
            if "angle=90" in tags:
                tags = tuple("angle=95" if t == "angle=90" else t for t in tags)
                s = s.model_copy(update={"angles_deg": (95.0, s.angles_deg[1])})
            s = s.model_copy(update={"tags": tags})
        steps.append(s)
    path = run(plan.model_copy(update={"steps": tuple(steps)}), tmp_path / "uneven.h5")
    with pytest.raises(InvalidInputError, match="the DFT form needs N positions equally spaced"):
        analyze_tumble(path, options=TumbleOptions(method="dft"))
    result = analyze_tumble(path)
    assert result.accelerometers[0].fit.fourier.method == "lsq"


def test_asking_for_what_four_positions_cannot_resolve(tmp_path: Path) -> None:
    path = run(tumble_plan(8, axes=("z",), n_positions=4, record_s=5.0), tmp_path / "four.h5")
    result = analyze_tumble(path)
    assert result.accelerometers[0].fit.names == ("K0", "K1", "delta", "K2")
    with pytest.raises(InsufficientExcitationError, match="cannot resolve") as info:
        analyze_tumble(path, options=TumbleOptions(
            coefficients=("K0", "K1", "delta", "K2", "Kip", "K3")))
    assert list(info.value.unobservable) == ["Kip", "K3"]


def test_its_report_prints_every_row_with_its_expanded_uncertainty(
        twin_run: tuple[Path, TumbleResult]) -> None:
    """A procedure without a report module of its own: the generic content (docs/reporting.md)."""
    from imucalib.exports.report import build_report
    from imucalib.report.console import display_unit
    from imucalib.report.document import SECTION_TITLES

    from ..report._gum import expected_cells

    path, result = twin_run
    doc = build_report(result, recording=path)
    assert [s.title for s in doc.sections] == list(SECTION_TITLES)
    table = doc.section("5.").tables[0]  # then the checks, the certificate's budget
    rows = {r[0]: r[1:] for r in table.rows}
    assert len(rows) == len(result.parameter_rows()) == 6 * 7 + 15
    for name, value, std, unit, _ in result.parameter_rows():
        # every row in the display unit of its kind; a scale factor (K1, K) as K − 1
        shown_unit, scale = display_unit(name, unit)
        is_scale = unit == "1" and (name.startswith("K1_") or name.split("_")[1] == "K")
        shown = value - 1.0 if is_scale else value
        assert rows[name] == (*expected_cells(shown / scale, 2.0 * std / scale), shown_unit)
    assert "(docs/tumble.md)" in doc.section("4.").paragraphs[0]
    assert doc.section("6.").paragraphs[0].startswith("Decision: no conformity decision")
