"""The Allan figure: files written, panels and lines present, matplotlib imported lazily."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from imucalib.analysis import compute_oadev, fit_noise_terms
from imucalib.errors import InvalidInputError
from imucalib.models.noise import NoiseModel
from imucalib.models.noise_generator import simulate_noise
from imucalib.procedures import ChannelNoise, NoiseCharacterization, SegmentNoise
from imucalib.procedures.allan.figures import plot_allan_triad, save_allan_figures


def segment() -> SegmentNoise:
    rate = 100.0
    gyro = simulate_noise(NoiseModel(white_density=1e-3, random_walk=2e-4), 1 << 14, 0.01, rng=1)
    accel = simulate_noise(NoiseModel(white_density=5e-4, bias_instability=2e-4,
                                      bias_instability_corner_hz=10.0), 1 << 14, 0.01, rng=2)
    chans = []
    for sensor, data in (("gyro", gyro), ("accel", accel)):
        for i, ax in enumerate("xyz"):
            dev = compute_oadev(data[:, i], rate)
            fit = fit_noise_terms(dev, sensor=sensor)
            name = f"{sensor}_{ax}_{'rps' if sensor == 'gyro' else 'mps2'}"
            chans.append(ChannelNoise(name, sensor, {"oadev": dev}, fit, 0.0))
    return SegmentNoise("static", 1, 0.0, 163.83, 1 << 14, rate, 23.5, tuple(chans))


def test_triad_figure_has_band_fit_and_term_lines(tmp_path: Path) -> None:
    seg = segment()
    fig = plot_allan_triad(seg, "gyro", path=tmp_path / "gyro.png")
    assert (tmp_path / "gyro.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    axes = fig.get_axes()
    assert [a.get_title() for a in axes] == ["gyro_x", "gyro_y", "gyro_z"]
    for ax, ch in zip(axes, seg.channels[:3], strict=True):
        assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
        labels = [t.get_text() for t in ax.get_legend().get_texts()]
        assert any(lbl.startswith("N = ") and lbl.endswith("°/√h") for lbl in labels)
        n_label = next(lbl for lbl in labels if lbl.startswith("N = "))
        # value ± u, u to two significant digits and the value to the same place (GUM 7.2.6)
        m = re.fullmatch(r"N = \(?\d+\.?(\d*) ± (\d+\.?(\d*))\)?(e-?\d+)? °/√h", n_label)
        assert m and len(m.group(1)) == len(m.group(3)), n_label
        assert len(m.group(2).replace(".", "").lstrip("0")) == 2, n_label
        shown = {lbl.split(" = ")[0] for lbl in labels if " = " in lbl}
        detected = {t.name for t in ch.fit.terms if t.detected}
        assert ("K" in shown) == ("random_walk" in detected)
        assert any("no 0.664" in lbl for lbl in labels)
        assert len(ax.collections) >= 1  # the confidence band
        points = ax.get_lines()[0].get_ydata()  # measured points in °/h
        np.testing.assert_allclose(points, ch.oadev.deviation / 4.84813681109536e-06, rtol=1e-12)
    fig = plot_allan_triad(seg, "accel", path=tmp_path / "accel.pdf")
    assert (tmp_path / "accel.pdf").read_bytes()[:5] == b"%PDF-"
    assert "µg" in fig.get_axes()[0].get_ylabel()


def test_save_all_figures_and_bad_arguments(tmp_path: Path) -> None:
    result = NoiseCharacterization("r.h5", "imu", "IMU-1", (segment(),))
    files = save_allan_figures(result, tmp_path / "figs", fmt="svg")
    assert [f.name for f in files] == ["allan_0_gyro.svg", "allan_0_accel.svg"]
    assert all(f.stat().st_size > 1000 for f in files)
    with pytest.raises(InvalidInputError, match="`sensor` must be 'gyro' or 'accel'; got 'mag'"):
        plot_allan_triad(segment(), "mag")
    with pytest.raises(InvalidInputError, match=r"figure file must end in \.png, \.pdf or \.svg"):
        plot_allan_triad(segment(), "gyro", path=tmp_path / "x.jpg")
    with pytest.raises(InvalidInputError, match="`fmt` must be 'png', 'pdf' or 'svg'; got 'bmp'"):
        save_allan_figures(result, tmp_path, fmt="bmp")


def test_matplotlib_is_not_imported_with_imucalib() -> None:
    code = ("import sys, imucalib, imucalib.analysis, imucalib.report, imucalib.procedures; "
            "print('matplotlib' in sys.modules, 'numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]
