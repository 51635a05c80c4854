"""CSV IMU lines: header with units, conversion to SI, malformed lines, streaming."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib import units
from imucalib.drivers.imu_csv import (
    CsvLineDecoder,
    format_header,
    format_lines,
    parse_header,
    parse_lines,
)
from imucalib.drivers.imu_packet import DecodedSamples
from imucalib.errors import InvalidInputError, UnitError

HEADER = ("counter,device_time[ms],gyro_x[deg/s],gyro_y[deg/s],gyro_z[deg/h],accel_x[g],"
          "accel_y[mg],accel_z[m/s^2],temperature[K],saturated")


def test_header_units_and_conversion() -> None:
    layout = parse_header(HEADER)
    assert layout.n_columns == 10 and layout.index["accel_z"] == 7
    samples, bad = parse_lines(["5,10,1,2,3600,1,500,9.8,300.15,0",
                                "6,20,0,0,0,0,0,0,273.15,1"], layout)
    assert bad == 0
    np.testing.assert_array_equal(samples.counter, [5, 6])
    np.testing.assert_allclose(samples.device_time_s, [0.010, 0.020])
    np.testing.assert_allclose(samples.gyro_rps[0],
                               [units.DEG, 2 * units.DEG, 3600 * units.DEG_PER_H])
    np.testing.assert_allclose(samples.accel_mps2[0], [units.G0_MPS2, 0.5 * units.G0_MPS2, 9.8])
    np.testing.assert_allclose(samples.temperature_degc, [27.0, 0.0], atol=1e-12)
    assert samples.saturated.tolist() == [False, True]


@pytest.mark.parametrize("header, error, message", [
    ("gyro_x[deg/s],gyro_y[deg/s],gyro_z[deg/s],accel_x[g],accel_y[g]", InvalidInputError,
     "CSV header lacks column\\(s\\) \\['accel_z'\\]"),
    ("gyro_x[furlong],gyro_y[deg/s],gyro_z[deg/s],accel_x[g],accel_y[g],accel_z[g]", UnitError,
     "unknown unit 'furlong'"),
    ("gyro_x[g],gyro_y[deg/s],gyro_z[deg/s],accel_x[g],accel_y[g],accel_z[g]", UnitError,
     "CSV column 'gyro_x\\[g\\]': unit 'g' is not a rate unit"),
    ("gyro_x,gyro_y[deg/s],gyro_z[deg/s],accel_x[g],accel_y[g],accel_z[g]", UnitError,
     "CSV column 'gyro_x' needs a unit in brackets, e.g. gyro_x\\[deg/s\\]"),
    ("gyro_x[deg/s],gyro_x[deg/s],gyro_z[deg/s],accel_x[g],accel_y[g],accel_z[g]",
     InvalidInputError, "CSV header names 'gyro_x' twice"),
    ("gyro_x[deg/s],gyro_y[deg/s],gyro_z[deg/s],accel_x[g],accel_y[g],accel_z[g],"
     "temperature[rankine]", UnitError, "unknown temperature unit 'rankine'"),
])
def test_header_errors(header: str, error: type[Exception], message: str) -> None:
    with pytest.raises(error, match=message):
        parse_header(header)


def test_malformed_lines_are_dropped_and_counted() -> None:
    layout = parse_header(format_header())
    good = "1,0.001,1,2,3,0,0,1,25.0,0"
    samples, bad = parse_lines([good, "2,0.002,1,#?,3,0,0,1,25.0,0", "3,0.003,1,2", good],
                               layout)
    assert bad == 2 and len(samples) == 2


def test_streaming_decoder_header_comments_gaps() -> None:
    n = 6
    src = DecodedSamples(np.array([0, 1, 2, 4, 5, 6]), np.arange(n) * 0.005,
                         np.full((n, 3), 0.01), np.tile([0.0, 0.0, 9.80665], (n, 1)),
                         np.full(n, 30.0), np.zeros(n, np.uint16))
    text = ("9,0.1,garbage before the header\n# model=CSV-1;serial=X-2\n" + format_header()
            + "\n" + "\n".join(format_lines(src)) + "\n")
    dec = CsvLineDecoder()
    raw = text.encode()
    out = DecodedSamples.concatenate([dec.feed(raw[:50]), dec.feed(raw[50:333]),
                                      dec.feed(raw[333:])])
    assert dec.info == {"model": "CSV-1", "serial": "X-2"}
    assert out.counter.tolist() == [0, 1, 2, 4, 5, 6]
    np.testing.assert_allclose(out.gyro_rps, 0.01, rtol=1e-8)
    np.testing.assert_allclose(out.accel_mps2[:, 2], 9.80665, rtol=1e-8)
    assert (dec.frames_ok, dec.crc_errors, dec.resyncs) == (6, 0, 1)
    assert (dec.counter_gaps, dec.missing_samples) == (1, 1)
