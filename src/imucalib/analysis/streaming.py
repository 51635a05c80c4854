"""Exact Allan-family deviations of arbitrarily long records in bounded memory.

Contents
--------
:class:`AllanStream`
    Feed one channel chunk by chunk (:meth:`~AllanStream.append`), then
    :meth:`~AllanStream.compute` any estimators of :mod:`imucalib.analysis.allan`.
:func:`compute_deviations_streaming`
    The same for an iterable of chunks.
:class:`FilePhase`
    The scratch-file phase source.

Design
------
An overlapping estimator at τ = m·τ0 needs the phase at i, i + m and i + 2m for every i, and
octave τ reach a quarter of the record, so an exact result needs random access to the whole
record. The stream therefore keeps the samples in memory up to `memory_limit_samples` and beyond
that spills them to a **disk-backed scratch file** (float64, 8 bytes per sample, in
`scratch_dir` or the system temporary directory; deleted by :meth:`AllanStream.close`).
:meth:`AllanStream.compute` turns the rates into the phase in place (one sequential pass with a
carried sum), then runs the same block drivers as the in-memory functions, reading superblocks of
2^16 terms: per superblock one read for all windows closer than a superblock and one read per
farther offset (overlapping windows are merged). Memory is bounded by about
``(memory_limit_samples + 2^20 + 2^16·(number of distinct far offsets))·8`` bytes whatever the
record length; reads are ``pread`` calls, so the process does not map the file.

The mean is accumulated over fixed 2^20-sample chunks and the reduction blocks are fixed, so
the streamed result **equals the in-memory one bit for bit** whatever the chunking (tested).
A record held in memory takes those sums from the record itself when it is computed; a spilled
one accumulates them as it is written.
"""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Iterable
from pathlib import Path
from types import TracebackType

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import check_positive
from imucalib.analysis import _allan_engine as eng
from imucalib.analysis._allan_kernels import PHASE_BLOCK, get_kernels
from imucalib.analysis.allan import (
    _MEAN_CHUNK,
    DataType,
    DeviationResult,
    TauSpec,
    deviations_from_source,
    min_samples,
    phase_from_rate,
)
from imucalib.analysis.edf import ONE_SIGMA
from imucalib.errors import InvalidInputError

__all__ = ["AllanStream", "FilePhase", "compute_deviations_streaming"]

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]
_IO_CHUNK = 256 * PHASE_BLOCK  # elements per sequential read/write (about 2^20)
assert _IO_CHUNK % PHASE_BLOCK == 0  # phase kernel calls start at a phase-block boundary


def _pread(fd: int, out: F64, index: int) -> None:
    """Fill `out` with float64 elements index … index + len(out) − 1 of the file."""
    view = memoryview(out.data).cast("B")
    done, offset = 0, index * 8
    while done < view.nbytes:
        got = os.preadv(fd, [view[done:]], offset + done)
        if got <= 0:
            raise OSError(f"short read of the Allan scratch file at byte {offset + done}")
        done += got


class FilePhase:
    """A phase series in a float64 scratch file (optionally with an implicit x_0 = 0)."""

    superblock = 1 << 16

    def __init__(self, fd: int, n_file: int, *, lead_zero: bool) -> None:
        self._fd = fd
        self._lead = 1 if lead_zero else 0
        self._n = n_file + self._lead

    @property
    def n_phase(self) -> int:
        """Number of phase points."""
        return self._n

    def _read_range(self, out: F64, start: int) -> None:
        if out.size == 0:
            return
        pos = 0
        if start < self._lead:
            out[0] = 0.0
            pos = 1
        if out.size > pos:
            _pread(self._fd, out[pos:], start + pos - self._lead)

    def read(self, start: int, stop: int, step: int = 1) -> F64:
        """Return x[start:stop:step] read from the file."""
        count = len(range(start, stop, step))
        out = np.empty(count)
        if count == 0:
            return out
        if step == 1:
            self._read_range(out, start)
        elif step <= 4096:  # sequential pieces, then slice
            per = max(1, _IO_CHUNK // step)
            tmp = np.empty(min(per, count) * step)
            for a in range(0, count, per):
                k = min(per, count - a)
                span = tmp[: (k - 1) * step + 1]
                self._read_range(span, start + a * step)
                out[a:a + k] = span[::step]
        else:  # far apart: one element per read
            one = np.empty(1)
            for a in range(count):
                self._read_range(one, start + a * step)
                out[a] = one[0]
        return out

    def gather(self, start: int, offsets: I64, length: int) -> tuple[F64, I64]:
        """Read the windows x[start+o : start+o+length] (overlapping ones merged)."""
        lo = np.minimum(start + offsets, self._n)
        hi = np.minimum(lo + length, self._n)
        groups: list[tuple[int, int]] = []  # merged [a, b) spans
        owner = np.empty(offsets.size, dtype=np.int64)
        for k in range(offsets.size):
            a, b = int(lo[k]), int(hi[k])
            if groups and a <= groups[-1][1]:
                groups[-1] = (groups[-1][0], max(groups[-1][1], b))
            else:
                groups.append((a, b))
            owner[k] = len(groups) - 1
        sizes = [b - a for a, b in groups]
        base = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        buf = np.empty(int(base[-1]))
        for g, (a, _) in enumerate(groups):
            self._read_range(buf[base[g]:base[g + 1]], a)
        starts = base[owner] + (lo - np.array([groups[g][0] for g in owner], dtype=np.int64))
        return buf, starts.astype(np.int64)


class AllanStream:
    """One channel, fed in chunks, for exact deviations in bounded memory (module docstring).

    Parameters
    ----------
    sample_rate_hz : float
        1/τ0. [Hz]
    data_type : {"rate", "angle"}
        As in :func:`imucalib.analysis.allan.compute_deviation`.
    unit : str
        Rate unit label stored in the results.
    scratch_dir : str or Path, optional
        Folder of the scratch file (default: the system temporary directory).
    memory_limit_samples : int
        Samples kept in memory before spilling to the scratch file (default 2^22, 32 MiB).

    Use it as a context manager (or call :meth:`close`) so that the scratch file is removed.
    """

    def __init__(self, sample_rate_hz: float, *, data_type: DataType = "rate", unit: str = "",
                 scratch_dir: str | os.PathLike[str] | None = None,
                 memory_limit_samples: int = 1 << 22) -> None:
        self.sample_rate_hz = check_positive(sample_rate_hz, "sample_rate_hz")
        if data_type not in ("rate", "angle"):
            raise InvalidInputError(f"`data_type` must be 'rate' or 'angle'; got {data_type!r}")
        if not isinstance(memory_limit_samples, int) or memory_limit_samples < 0:
            raise InvalidInputError(f"`memory_limit_samples` must be an int ≥ 0; got "
                                    f"{memory_limit_samples!r}")
        self.data_type = data_type
        self.unit = unit
        self.scratch_dir = None if scratch_dir is None else Path(scratch_dir)
        self.memory_limit_samples = memory_limit_samples
        self._chunks: list[F64] = []
        self._n = 0
        self._fd: int | None = None
        self._path: Path | None = None
        self._pending = np.empty(0)
        self._pending_n = 0
        self._sum = 0.0
        self._source: eng.PhaseSource | None = None

    # ------------------------------------------------------------------ feeding
    @property
    def n_samples(self) -> int:
        """Samples appended so far."""
        return self._n

    @property
    def scratch_path(self) -> Path | None:
        """The scratch file, once the stream has spilled to disk."""
        return self._path

    def append(self, samples: ArrayLike, *, copy: bool = True) -> float:
        """Append the next samples (1-D, finite) [unit]; return their sum (``np.sum``).

        With ``copy=False`` the stream may keep `samples` itself instead of a copy until it is
        computed (the caller hands over an array it will not change: a chunk just read).

        Raises
        ------
        InvalidInputError
            Non-1-D or non-finite samples (the message gives the global index of the first), or
            a stream that was already computed.
        """
        if self._source is not None:
            raise InvalidInputError("this AllanStream was already computed; it takes no more "
                                    "samples (start a new one)")
        y = np.asarray(samples, dtype=np.float64)
        if y.ndim != 1:
            raise InvalidInputError(f"`samples` must be 1-D; got shape {y.shape}")
        with np.errstate(over="ignore", invalid="ignore"):
            total = float(np.sum(y))  # finite unless a sample is not (or the sum overflows)
        if not math.isfinite(total) and not np.isfinite(y).all():
            i = self._n + int(np.argmax(~np.isfinite(y)))
            raise InvalidInputError(
                f"sample {i} (t = {i / self.sample_rate_hz:g} s from the start) is NaN or "
                "infinite; an Allan sum across a gap is not defined: split the record there")
        if y.size == 0:
            return total
        if self._fd is None and self._n + y.size > self.memory_limit_samples:
            self._spill()
        if self._fd is None:
            # held in memory: the mean is taken from the whole record when it is computed
            kept = np.ascontiguousarray(y)
            self._chunks.append(kept.copy() if copy else kept)
        else:
            y = np.ascontiguousarray(y)
            if self.data_type == "rate":
                self._accumulate_mean(y)
            os.write(self._fd, y.tobytes())
        self._n += y.size
        return total

    def _accumulate_mean(self, y: F64) -> None:
        if self._pending.size == 0:
            self._pending = np.empty(_MEAN_CHUNK)
        a = 0
        while a < y.size:
            k = min(y.size - a, _MEAN_CHUNK - self._pending_n)
            self._pending[self._pending_n:self._pending_n + k] = y[a:a + k]
            self._pending_n += k
            a += k
            if self._pending_n == _MEAN_CHUNK:
                with np.errstate(over="ignore", invalid="ignore"):
                    self._sum += float(np.sum(self._pending))
                self._pending_n = 0

    def _spill(self) -> None:
        if self.scratch_dir is not None:
            self.scratch_dir.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(prefix="imucalib-allan-", suffix=".f64",
                                    dir=self.scratch_dir)
        self._fd, self._path = fd, Path(name)
        for c in self._chunks:
            if self.data_type == "rate":
                self._accumulate_mean(c)
            os.write(fd, c.tobytes())
        self._chunks = []

    # ------------------------------------------------------------------ computing
    def _finalize(self) -> eng.PhaseSource:
        if self._source is not None:
            return self._source
        n_min = min_samples("oadev") + (1 if self.data_type == "angle" else 0)
        if self._n < n_min:
            raise InvalidInputError(f"data too short: need at least {n_min} samples; got "
                                    f"{self._n}")
        y: F64 | None = None
        tail = self._pending[:self._pending_n]
        if self._fd is None:
            y = np.concatenate(self._chunks) if len(self._chunks) > 1 else self._chunks[0]
            self._chunks = []
            if self.data_type == "rate":  # the canonical 2^20-sample sums, in order, in place
                full = y.size - y.size % _MEAN_CHUNK
                with np.errstate(over="ignore", invalid="ignore"):
                    for a in range(0, full, _MEAN_CHUNK):
                        self._sum += float(np.sum(y[a:a + _MEAN_CHUNK]))
                tail = y[full:]
        mean = 0.0
        if self.data_type == "rate":
            with np.errstate(over="ignore", invalid="ignore"):
                mean = (self._sum + float(np.sum(tail))) / self._n
            if not np.isfinite(mean):
                raise InvalidInputError("the samples are too large to sum in float64: rescale "
                                        "them")
        if self._fd is None:
            assert y is not None
            x = phase_from_rate(y, self.sample_rate_hz, mean) if self.data_type == "rate" else y
            self._source = eng.ArrayPhase(x)
        elif self.data_type == "angle":
            self._source = FilePhase(self._fd, self._n, lead_zero=False)
        else:
            phase = get_kernels()["phase"]
            buf, carry, dt = np.empty(_IO_CHUNK), 0.0, 1.0 / self.sample_rate_hz
            for a in range(0, self._n, _IO_CHUNK):
                chunk = buf[: min(_IO_CHUNK, self._n - a)]
                _pread(self._fd, chunk, a)
                carry = phase(chunk.copy(), mean, dt, chunk, carry)
                os.pwrite(self._fd, chunk.tobytes(), a * 8)
            self._source = FilePhase(self._fd, self._n, lead_zero=True)
        self._pending = np.empty(0)
        return self._source

    def compute(self, kinds: Iterable[str] = ("oadev",), *, taus: TauSpec = "octave",
                confidence: float = ONE_SIGMA,
                identify_noise: bool = True) -> dict[str, DeviationResult]:
        """Deviations of everything appended, by estimator name (see ``compute_deviation``).

        Raises
        ------
        InvalidInputError
            Too few samples, or bad `kinds`/`taus`/`confidence`.
        """
        kinds_t = tuple(kinds)
        source = self._finalize()
        return deviations_from_source(source, kinds_t, taus, self.sample_rate_hz,
                                      confidence=confidence, identify_noise=identify_noise,
                                      data_type=self.data_type, unit=self.unit)

    def close(self) -> None:
        """Delete the scratch file (idempotent)."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
        if self._path is not None:
            self._path.unlink(missing_ok=True)
            self._path = None
        self._chunks = []
        self._source = None

    def __enter__(self) -> AllanStream:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # pragma: no cover - interpreter shutdown
            pass


def compute_deviations_streaming(chunks: Iterable[ArrayLike], sample_rate_hz: float, *,
                                 kinds: Iterable[str] = ("oadev",), taus: TauSpec = "octave",
                                 data_type: DataType = "rate", confidence: float = ONE_SIGMA,
                                 identify_noise: bool = True, unit: str = "",
                                 scratch_dir: str | os.PathLike[str] | None = None,
                                 memory_limit_samples: int = 1 << 22
                                 ) -> dict[str, DeviationResult]:
    """Deviations of a record given as an iterable of 1-D chunks, in bounded memory.

    Equivalent to :func:`imucalib.analysis.allan.compute_deviation` on the concatenated chunks
    (bit for bit); see :class:`AllanStream` for the parameters and the memory bound.
    """
    with AllanStream(sample_rate_hz, data_type=data_type, unit=unit, scratch_dir=scratch_dir,
                     memory_limit_samples=memory_limit_samples) as stream:
        for chunk in chunks:
            stream.append(chunk)
        return stream.compute(kinds, taus=taus, confidence=confidence,
                              identify_noise=identify_noise)
