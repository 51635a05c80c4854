"""The residual figure of a P1 calibration: written by write_outputs, one panel per triad."""

from __future__ import annotations

from imucalib.exports.outputs import write_outputs
from imucalib.procedures.p1.analysis import P1Options, analyze_p1


def test_p1_outputs_include_the_residual_figure(consumer_run, tmp_path):
    analysis = analyze_p1(consumer_run, options=P1Options(model="per-axis",
                                                          hash_recording=False))
    written = write_outputs(analysis, tmp_path, name="c")
    png = tmp_path / f"c.{analysis.unit}.p1.residuals.png"
    assert png in written
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000
