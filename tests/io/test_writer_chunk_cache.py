"""The writer's HDF5 chunk cache is bounded (memory of a long run; docs/web.md, "Measured").

HDF5 2's default chunk cache is 8 MiB a dataset: a writer left at the default keeps every
chunk it wrote, never read again, until 8 MiB a column — about 220 MiB for a P2 run's columns
at 1 kHz. The writer asks for :data:`~imucalib.io.recording.WRITE_CHUNK_CACHE_BYTES`, when it
creates the file and when it reopens it to resume.
"""

from __future__ import annotations

import math

import numpy as np

from imucalib.io.recording import WRITE_CHUNK_CACHE_BYTES, ColumnSpec, RecordingWriter, StreamSpec


def _cache_bytes(writer: RecordingWriter) -> set[int]:
    f = writer._file  # the open file: its datasets' chunk caches are what a long run keeps
    sizes: set[int] = set()

    def visit(_name: str, obj: object) -> None:
        if getattr(obj, "chunks", None) is not None:  # a chunked dataset (streams, steps, log)
            sizes.add(int(obj.id.get_access_plist().get_chunk_cache()[1]))

    f.visititems(visit)
    return sizes


def test_the_writer_caches_one_mib_a_dataset_written_and_reopened(tmp_path):
    spec = StreamSpec("imu", "u1", {"x": ColumnSpec("rad/s")})
    path = tmp_path / "r.h5"
    rows = {"time_s": np.arange(1000) * 1e-3, "x": np.zeros(1000)}
    with RecordingWriter(path, streams=[spec], flush_interval_s=math.inf) as writer:
        writer.append("imu", "u1", rows)
        assert _cache_bytes(writer) == {WRITE_CHUNK_CACHE_BYTES}
    assert WRITE_CHUNK_CACHE_BYTES <= 1 << 20
    with RecordingWriter.reopen(path, flush_interval_s=math.inf) as again:  # a resumed run
        again.append("imu", "u1", {"time_s": 1.0 + rows["time_s"], "x": rows["x"]})
        assert _cache_bytes(again) == {WRITE_CHUNK_CACHE_BYTES}
