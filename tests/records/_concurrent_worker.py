"""The body of one writer process of test_concurrency (imported by the spawned child)."""

from __future__ import annotations

import time
from multiprocessing.synchronize import Barrier


def write_results(url: str, worker: int, count: int, barrier: Barrier) -> None:
    import numpy as np

    from imucalib.models.result import CalibrationResult, triad_parameter_names
    from imucalib.records import open_records

    names = triad_parameter_names("accel", "per-axis")
    with open_records(url) as rec:
        barrier.wait(timeout=60)
        for i in range(count):
            serial = f"W{worker}-{i % 3}"
            run = rec.record_run(plan_name=f"plan-{worker}", operator=f"worker {worker}")
            res = CalibrationResult(
                sensor_id=serial, procedure="p1", model="per-axis", param_names=names,
                values=np.full(6, worker + i * 1e-3), covariance=np.eye(6) * 1e-8,
                units=dict.fromkeys(names, "1"))
            rid = rec.record_result(run, res, passed=True)
            if i % 10 == 0:
                rec.review(rid, f"worker {worker}", approved=True)
                rec.get_or_create_unit("SHARED")  # both create it: one wins, the other finds it
            time.sleep(0.03)  # give the other writer a turn (SQLite's busy wait backs off;
            # 10 ms let one writer starve the other on a loaded 2-core machine)
