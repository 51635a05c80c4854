"""The C99 runtime of a calibration: compiled and run against correct_imu on random samples.

The error of a corrected sample is measured against Python's, relative to that triad's
sample magnitude (its largest component, docs/c-runtime.md): double ≤ 1e-12, float ≤ 1e-6.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.exports.c_runtime import MAX_TEMPERATURE_ORDER, write_c_runtime
from imucalib.exports.outputs import OUTPUT_FORMATS
from imucalib.models.correct import correct_imu
from imucalib.models.result import (
    CalibrationResult,
    ParameterTemperatureModel,
    triad_parameter_names,
)

N = 100_000
T0 = 20.0
T_RANGE = (-40.0, 85.0)
CFLAGS = ["-std=c99", "-O2", "-Wall", "-Wextra", "-pedantic", "-Werror"]
#: σ of a drawn K3 [1/(m/s²)²]: K3·u³ up to ≈ 1 m/s² at 20 m/s², h still monotonic on ±20 m/s².
K3_SCALE = 5e-5

#: The test driver: samples (g, a, T, Ṫ, ℓ) from in.bin → per sample rc_d, g_d, a_d, rc_f, g_f,
#: a_f to out.bin (doubles); prints the legs of four rates (double, float), then the time per
#: sample of each precision. [ns]
DRIVER = r"""
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "imucal_params.h"

#define REPEAT 5

int main(int argc, char **argv)
{
    FILE *in, *out;
    double head, *s, *o;
    float *sf;
    long n, i, k;
    int r;
    clock_t c0, c1, c2;
    if (argc != 3 || !(in = fopen(argv[1], "rb")) || fread(&head, sizeof head, 1, in) != 1) {
        return 2;
    }
    n = (long)head;
    s = malloc((size_t)n * 9 * sizeof *s);
    sf = malloc((size_t)n * 9 * sizeof *sf);
    o = malloc((size_t)n * 14 * sizeof *o);
    if (!s || !sf || !o || fread(s, sizeof *s, (size_t)n * 9, in) != (size_t)n * 9) {
        return 3;
    }
    fclose(in);
    for (k = 0; k < n * 9; ++k) {
        sf[k] = (float)s[k];
    }
    c0 = clock();
    for (r = 0; r < REPEAT; ++r) {
        for (i = 0; i < n; ++i) {
            const double *x = s + 9 * i;
            o[14 * i] = imucal_correct_d(imucal_get_d(), x, x + 3, x[6], x[7], (int)x[8],
                                         o + 14 * i + 1, o + 14 * i + 4);
        }
    }
    c1 = clock();
    for (r = 0; r < REPEAT; ++r) {
        for (i = 0; i < n; ++i) {
            const float *x = sf + 9 * i;
            float g[3], a[3];
            o[14 * i + 7] = imucal_correct_f(imucal_get_f(), x, x + 3, x[6], x[7],
                                             (int)x[8], g, a);
            for (k = 0; k < 3; ++k) {
                o[14 * i + 8 + k] = g[k];
                o[14 * i + 11 + k] = a[k];
            }
        }
    }
    c2 = clock();
    printf("%d %d %d %d %d %d %d %d\n", imucal_temperature_leg_d(0.0021),
           imucal_temperature_leg_d(0.002), imucal_temperature_leg_d(-0.0021),
           imucal_temperature_leg_d(0.0), imucal_temperature_leg_f(0.0021f),
           imucal_temperature_leg_f(0.002f), imucal_temperature_leg_f(-0.0021f),
           imucal_temperature_leg_f(0.0f));
    printf("%.6g %.6g\n", 1e9 * (double)(c1 - c0) / CLOCKS_PER_SEC / (double)(REPEAT * n),
           1e9 * (double)(c2 - c1) / CLOCKS_PER_SEC / (double)(REPEAT * n));
    if (!(out = fopen(argv[2], "wb")) || fwrite(o, sizeof *o, (size_t)n * 14, out)
        != (size_t)n * 14) {
        return 4;
    }
    fclose(out);
    free(s);
    free(sf);
    free(o);
    return 0;
}
"""


def _cc() -> str:
    cc = shutil.which("cc")
    if cc is None:
        pytest.fail("no C compiler `cc` on PATH: the C runtime test needs one (CI has it)")
    return cc


def _run_c(result: CalibrationResult, folder: Path, samples: np.ndarray
           ) -> tuple[np.ndarray, tuple[float, float]]:
    """Generate, compile and run the driver; return its (n, 14) output and ns/sample (d, f)."""
    write_c_runtime(result, folder)
    (folder / "driver.c").write_text(DRIVER, encoding="utf-8")
    exe = folder / "driver"
    build = subprocess.run([_cc(), *CFLAGS, "-I", str(folder), str(folder / "driver.c"),
                            str(folder / "imucalib_runtime.c"), "-lm", "-o", str(exe)],
                           capture_output=True, text=True, check=False)
    assert build.returncode == 0, build.stderr
    (folder / "in.bin").write_bytes(np.concatenate([[float(len(samples))],
                                                    samples.ravel()]).tobytes())
    run = subprocess.run([str(exe), str(folder / "in.bin"), str(folder / "out.bin")],
                         capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr
    legs, times = run.stdout.splitlines()
    assert legs.split() == ["1", "0", "-1", "0"] * 2  # the dead band of temperature_leg
    ns_d, ns_f = (float(v) for v in times.split())
    out = np.fromfile(folder / "out.bin", dtype=np.float64).reshape(len(samples), 14)
    return out, (ns_d, ns_f)


def _samples(rng: np.random.Generator, n: int = N) -> np.ndarray:
    """(g [rad/s], a [m/s²], T [°C] inside the fitted range, Ṫ [°C/s], ℓ) per row."""
    return np.column_stack([rng.uniform(-5.0, 5.0, (n, 3)), rng.uniform(-20.0, 20.0, (n, 3)),
                            rng.uniform(*T_RANGE, n), rng.normal(0.0, 0.01, n),
                            rng.integers(-1, 2, n).astype(float)])


def _relative_error(c: np.ndarray, py: np.ndarray) -> float:
    """max |c − py| / ‖py‖∞ per sample (the sample's magnitude as the floor for small values)."""
    scale = np.max(np.abs(py), axis=1, keepdims=True)
    return float(np.max(np.abs(c - py) / scale))


def _check_against_python(result: CalibrationResult, tmp_path: Path, seed: int) -> None:
    samples = _samples(np.random.default_rng(seed))
    out, _ = _run_c(result, tmp_path, samples)
    kwargs = {}
    if result.temperature_models:
        kwargs = {"temperature_degc": samples[:, 6], "temperature_rate_degc_ps": samples[:, 7],
                  "leg": samples[:, 8]}
    gyro, accel = correct_imu(samples[:, :3], samples[:, 3:6], result, **kwargs)
    assert gyro is not None and accel is not None
    assert np.all(out[:, 0] == 0) and np.all(out[:, 7] == 0)
    for cols, ref in ((slice(1, 4), gyro), (slice(4, 7), accel)):
        assert _relative_error(out[:, cols], ref) <= 1e-12
    for cols, ref in ((slice(8, 11), gyro), (slice(11, 14), accel)):
        assert _relative_error(out[:, cols], ref) <= 1e-6
    # the correction is not the identity: the comparison has something to find
    assert np.max(np.abs(accel - samples[:, 3:6])) > 1e-3


def _result(names: list[str], values: np.ndarray, *, model: str = "triad",
            temperature_models: tuple[ParameterTemperatureModel, ...] = ()) -> CalibrationResult:
    k = len(names)
    return CalibrationResult(sensor_id='IMU "7"/ü*/', procedure="p2", model=model,
                             param_names=tuple(names), values=values,
                             covariance=np.eye(k) * 1e-20, units=dict.fromkeys(names, "1"),
                             temperature_models=temperature_models)


def triad_result(rng: np.random.Generator, *, k3: bool = False) -> CalibrationResult:
    """Gyro bias, M, G; accelerometer bias, M, K2 (and K3); no temperature model."""
    gyro = triad_parameter_names("gyro", "triad", g_sensitivity=True)
    accel = triad_parameter_names("accel", "triad", k2=True, k3=k3)
    values = np.concatenate([rng.normal(size=3) * 1e-2, rng.normal(size=9) * 2e-3,
                             rng.normal(size=9) * 1e-4, rng.normal(size=3) * 0.05,
                             rng.normal(size=9) * 2e-3, rng.normal(size=3) * 1e-4,
                             rng.normal(size=3 if k3 else 0) * K3_SCALE])
    return _result([*gyro, *accel], values)


def temperature_result(rng: np.random.Generator, *, model: str = "triad",
                       order: int = 3, k3: bool = False) -> CalibrationResult:
    """Every parameter (K2, K3 included) a polynomial of `order` in T − T0; some with rate, leg."""
    if model == "triad":
        names = [*triad_parameter_names("gyro", "triad", g_sensitivity=True),
                 *triad_parameter_names("accel", "triad", k2=True, k3=k3)]
    else:
        names = [*triad_parameter_names("gyro", "per-axis"),
                 *triad_parameter_names("accel", "per-axis")]

    scales = [{"bias": 0.02, "b": 0.02, "M": 2e-3, "G": 1e-4, "K": 2e-3,
               "K2": 1e-4, "K3": K3_SCALE}[n.split("_")[1]]
              for n in names]
    values = np.array([(1.0 if n.split("_")[1] == "K" else 0.0) + float(rng.normal()) * s
                       for n, s in zip(names, scales, strict=True)])
    records = []
    for i, (name, value, scale) in enumerate(zip(names, values, scales, strict=True)):
        # c_j·(T − T0)^j of about 0.3·scale at the ends of the range
        coeffs = (float(value), *(float(rng.normal()) * 0.3 * scale / 60.0 ** j
                                  for j in range(1, order + 1)))
        d = float(rng.normal()) * 10.0 * scale if i % 2 == 0 else None
        h = float(rng.normal()) * 0.1 * scale if i % 3 == 0 else None
        q = len(coeffs) + (d is not None) + (h is not None)
        records.append(ParameterTemperatureModel(
            name=name, reference_temperature_degc=T0, coefficients=coeffs, rate_coefficient=d,
            leg_coefficient=h, covariance=np.eye(q) * 1e-20, chi2=1.0, dof=4,
            order_criterion="fixed", temperature_range_degc=T_RANGE))
    return _result(names, values, model=model, temperature_models=tuple(records))


def test_triad_bias_m_g_k2_matches_python(tmp_path: Path) -> None:
    _check_against_python(triad_result(np.random.default_rng(1)), tmp_path, seed=11)


def test_temperature_models_match_python(tmp_path: Path) -> None:
    _check_against_python(temperature_result(np.random.default_rng(2)), tmp_path, seed=12)


def test_per_axis_temperature_models_match_python(tmp_path: Path) -> None:
    _check_against_python(temperature_result(np.random.default_rng(3), model="per-axis"),
                          tmp_path, seed=13)


def test_header_carries_identity_and_hash(tmp_path: Path) -> None:
    import hashlib

    result = temperature_result(np.random.default_rng(4))
    paths = write_c_runtime(result, tmp_path, name="unit7")
    assert [p.name for p in paths] == ["unit7_params.h", "imucalib_runtime.h",
                                       "imucalib_runtime.c"]
    text = paths[0].read_text(encoding="utf-8")
    sha = hashlib.sha256(result.to_json().encode("utf-8")).hexdigest()
    assert f'static const char unit7_result_sha256[] = "{sha}";' in text
    assert "#define UNIT7_FORMAT_VERSION 3" in text
    # the sensor id's quote, slash-star and non-ASCII bytes are escaped, not pasted
    assert 'unit7_sensor_id[] = "IMU \\0427\\042\\057\\303\\274\\052\\057";' in text


def test_unsupported_results_are_refused(tmp_path: Path) -> None:
    result = temperature_result(np.random.default_rng(5), order=MAX_TEMPERATURE_ORDER + 1)
    with pytest.raises(InvalidInputError, match=r"up to order 7; the model of 'gyro_bias_x' "
                                                r"has order 8"):
        write_c_runtime(result, tmp_path)
    with pytest.raises(InvalidInputError, match="`name` must be a C identifier"):
        write_c_runtime(triad_result(np.random.default_rng(6)), tmp_path, name="9-lives")
    assert not list(tmp_path.iterdir())


def test_output_format_registered(tmp_path: Path) -> None:
    from imucalib.models.result_document import stored_from_calibration

    holder = stored_from_calibration(triad_result(np.random.default_rng(7)))
    paths = OUTPUT_FORMATS["c-runtime"](holder, tmp_path, "rec.U1.p2")
    assert {p.relative_to(tmp_path).as_posix() for p in paths} == {
        "rec.U1.p2.c/imucal_params.h", "rec.U1.p2.c/imucalib_runtime.h",
        "rec.U1.p2.c/imucalib_runtime.c"}


def test_runtime_reports_errors(tmp_path: Path) -> None:
    """A singular I + M and a NaN input give error codes, not numbers."""
    names = list(triad_parameter_names("accel", "triad"))
    values = np.zeros(len(names))
    values[names.index("accel_M_xx")] = -1.0  # row x of I + M is zero
    samples = _samples(np.random.default_rng(8), n=4)
    samples[1, 0] = np.nan
    out, _ = _run_c(_result(names, values), tmp_path, samples)
    assert out[0, 0] == 2 and out[0, 7] == 2  # IMUCAL_ERR_SINGULAR
    assert out[1, 0] == 1 and out[1, 7] == 1  # IMUCAL_ERR_INPUT



def test_triad_with_k3_matches_python(tmp_path: Path) -> None:
    """K3 (C3′) in both precisions; without it the C correction would be off by K3·u³."""
    result = triad_result(np.random.default_rng(21), k3=True)
    _check_against_python(result, tmp_path, seed=22)
    samples = _samples(np.random.default_rng(22))
    out, _ = _run_c(result, tmp_path, samples)
    _, without = correct_imu(None, samples[:, 3:6], triad_result(np.random.default_rng(21)))
    assert without is not None and np.max(np.abs(out[:, 4:7] - without)) > 0.05


def test_temperature_models_with_k3_match_python(tmp_path: Path) -> None:
    _check_against_python(temperature_result(np.random.default_rng(23), k3=True), tmp_path,
                          seed=24)


def test_k3_zero_is_exactly_the_k2_code_path(tmp_path: Path) -> None:
    """A result whose K3 slots are 0 gives the same bits as the result without K3 names."""
    plain = triad_result(np.random.default_rng(25))
    names = (*plain.param_names, "accel_K3_x", "accel_K3_y", "accel_K3_z")
    zero_k3 = _result(list(names), np.concatenate([plain.values, np.zeros(3)]))
    samples = _samples(np.random.default_rng(26), n=2000)
    a, _ = _run_c(plain, tmp_path / "a", samples)
    b, _ = _run_c(zero_k3, tmp_path / "b", samples)
    np.testing.assert_array_equal(a, b)


def test_k3_outside_its_branch_is_an_error_code(tmp_path: Path) -> None:
    """u + K3·u³ with K3 < 0 peaks at ≈ 12 m/s² (K3 = −1e-3): 15 m/s² has no root there."""
    names = list(triad_parameter_names("accel", "triad", k3=True))
    values = np.zeros(len(names))
    values[names.index("accel_K3_x")] = -1e-3
    samples = _samples(np.random.default_rng(27), n=2)
    samples[:, 3:6] = [[15.0, 0.0, 0.0], [5.0, 1.0, -1.0]]
    out, _ = _run_c(_result(names, values), tmp_path, samples)
    assert out[0, 0] == 4 and out[0, 7] == 4  # IMUCAL_ERR_K3_RANGE
    assert out[1, 0] == 0 and out[1, 7] == 0
    with pytest.raises(InvalidInputError, match="cannot invert"):
        correct_imu(None, samples[:1, 3:6], _result(names, values))


def test_slot_layout_matches_the_header() -> None:
    """_OFFSETS, the slot names and imucalib_runtime.h's macros agree (layout version 2)."""
    import re
    from importlib import resources

    from imucalib.exports import c_runtime

    header = resources.files("imucalib.exports").joinpath("c", "imucalib_runtime.h").read_text(
        encoding="utf-8")
    macros = {m: int(v) for m, v in re.findall(r"#define (IMUCAL_\w+) (\d+)\b", header)}
    assert macros["IMUCAL_LAYOUT_VERSION"] == c_runtime.LAYOUT_VERSION == 2
    assert macros["IMUCAL_TRIAD_SLOTS"] == 33 and macros["IMUCAL_N_SLOTS"] == 66
    for symbol, offset in c_runtime._OFFSETS.items():
        macro = {"bias": "IMUCAL_BIAS", "b": "IMUCAL_B"}.get(symbol, f"IMUCAL_{symbol}")
        assert macros[macro] == offset
        first = "xx" if symbol in ("M", "G") else "x"
        for t, triad in enumerate(("gyro", "accel")):
            assert c_runtime._SLOTS.index(f"{triad}_{symbol}_{first}") == 33 * t + offset
