"""P3 runs on the twin, and their truth.

The plan's centrifuge (r_t = 1 m, 20 g, 10 µm of unbalance at the top rate with the 2 kg test
load), navigation-grade units (white noise unless asked: a bias that does not wander, for
checks against the deterministic truth).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from imucalib import units
from imucalib.io.opening import open_recording
from imucalib.plan.schema import Plan
from imucalib.procedures.p3.plan import UNIT_NAMES, generate_p3_plan
from imucalib.station.runner import RunOptions, run_plan
from imucalib.station.sim import SimStation

#: K2 [1/(m/s²)] → g/g²
G_PER_G2 = units.G0_MPS2


def p3_plan(seed: int, *, noise: str = "white", imu: dict[str, Any] | None = None,
            centrifuge: dict[str, Any] | None = None, **options: Any) -> Plan:
    """The default P3 plan with the twin's units' noise (and other fields) changed."""
    plan = generate_p3_plan(seed=seed, **options)
    assert plan.twin is not None
    twin = plan.twin.model_copy(update={
        "imus": tuple(i.model_copy(update={"noise": noise, **(imu or {})})
                      for i in plan.twin.imus),
        "centrifuge": plan.twin.centrifuge.model_copy(update=centrifuge or {})})
    return plan.model_copy(update={"twin": twin})


def run_p3(plan: Plan, path: Path, *, must_finish: bool = True, tick_s: float = 5.0) -> Path:
    """Run `plan` on its twin into `path`."""
    assert plan.twin is not None
    station = SimStation(plan.twin)
    summary = run_plan(plan, station, path, options=RunOptions(tick_s=tick_s, truth=station.truth))
    assert summary.status == "done" or not must_finish, summary.reason
    return path


def p3_truth(path: Path, plan: Plan) -> dict[str, float]:
    """K2 of each unit's x accelerometer as (P3.1) defines it (k2·K1, 1/(m/s²)), c and c′."""
    assert plan.twin is not None
    fuge = plan.twin.centrifuge
    load = max((s.centrifuge_load_kg or 0.0) for s in plan.steps
               if getattr(s, "centrifuge_load_kg", None) is not None)
    with open_recording(path) as rec:
        models = rec.truth["imu_models"]
    out = {}
    for role, key in (("ref-a", "K2_A"), ("ref-b", "K2_B"), ("test", "K2_T")):
        accel = models[UNIT_NAMES[role]]["accel"]
        k1 = 1.0 + float(np.asarray(accel["scale_misalignment"])[0, 0])
        out[key] = float(accel["k2"][0]) * k1
    out["c"] = fuge.unbalance_c0_m_per_rps_sq + fuge.unbalance_c_m_per_rps_sq_per_kg * fuge.load_kg
    out["c_loaded"] = fuge.unbalance_c0_m_per_rps_sq + fuge.unbalance_c_m_per_rps_sq_per_kg * load
    return out


def shared_base(tmp_path_factory: Any) -> Path:
    """The session's own folder, shared by its xdist workers (one level up from a worker's)."""
    base = Path(tmp_path_factory.getbasetemp())
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


def errors_and_z(path: Path, plan: Plan, **options: Any) -> tuple[dict[str, float],
                                                                   np.ndarray, Any]:
    """Analyse a run: (truth, z of K2_A, K2_B, c, c′, K2_T against it, the result)."""
    from imucalib.procedures.p3.analysis import P3Options, analyze_p3
    from imucalib.procedures.p3.roundrobin import PARAMETERS

    result = analyze_p3(path, options=P3Options(**options))
    truth = p3_truth(path, plan)
    est = result.estimate
    z = np.array([(est.value(p) - truth[p]) / est.std(p) for p in PARAMETERS])
    return truth, z, result
