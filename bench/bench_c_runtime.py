"""C99 runtime benchmark: time per corrected sample in C against Python's ``correct_imu``.

For three calibrations — a triad without temperature models, a triad whose every parameter is a
cubic in temperature with rate and leg terms, a per-axis model with the same — the runtime is
generated (``imucalib export --format c-runtime``), compiled with the system C compiler at
``-O2`` together with the test driver of ``tests/exports/test_c_runtime.py`` (its results and
driver are loaded from that file, so the bench times exactly what the test checks), and run over
10⁵ random samples (5 repeats, its own clock); Python's vectorised ``correct_imu`` corrects the
same samples in this process (best of 3). Printed per case: ns per sample for C double, C float
and Python, and Python's time over C's (docs/c-runtime.md, "Time per sample").

Run:  .venv/bin/python bench/bench_c_runtime.py
"""

from __future__ import annotations

import importlib.util
import tempfile
import time
from pathlib import Path

import numpy as np

from imucalib.models.correct import correct_imu

ROOT = Path(__file__).resolve().parents[1]


def _test_module():
    spec = importlib.util.spec_from_file_location(
        "c_runtime_cases", ROOT / "tests" / "exports" / "test_c_runtime.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _python_ns(result, samples: np.ndarray) -> float:
    kwargs = {}
    if result.temperature_models:
        kwargs = {"temperature_degc": samples[:, 6], "temperature_rate_degc_ps": samples[:, 7],
                  "leg": samples[:, 8]}
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        correct_imu(samples[:, :3], samples[:, 3:6], result, **kwargs)
        best = min(best, time.perf_counter() - t0)
    return best / len(samples) * 1e9


def main() -> None:
    cases = _test_module()
    rng = np.random.default_rng(11)
    results = {"triad, no temperature model": cases.triad_result(rng),
               "triad, temperature models": cases.temperature_result(rng),
               "per-axis, temperature models": cases.temperature_result(rng, model="per-axis")}
    print(f"{'calibration':32s} {'C double':>10s} {'C float':>10s} {'Python':>10s} "
          f"{'Python/C':>9s}")
    for label, result in results.items():
        samples = cases._samples(rng)
        with tempfile.TemporaryDirectory() as tmp:
            _, (ns_d, ns_f) = cases._run_c(result, Path(tmp), samples)
        ns_py = _python_ns(result, samples)
        print(f"{label:32s} {ns_d:8.0f}ns {ns_f:8.0f}ns {ns_py:8.0f}ns {ns_py / ns_d:8.1f}×")


if __name__ == "__main__":
    main()
