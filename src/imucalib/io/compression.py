"""The compression filters of a Recording's stream columns: names, HDF5 settings, copies.

Contents
--------
:data:`COMPRESSIONS`
    The names :class:`~imucalib.io.recording.RecordingWriter` accepts.
:data:`DEFAULT_COMPRESSION`
    ``"blosc-lz4"``: Blosc with LZ4 after a bit-shuffle, the default of new recordings.
:func:`column_filter_kwargs`
    The ``h5py`` ``create_dataset`` keywords of a compression name.
:func:`copy_filter_kwargs`
    The keywords that give a new dataset the filters of an existing one (recovery's copies).
:func:`compression_of`
    The compression name of an existing dataset.
:func:`needs_plugin`
    Whether a compression name needs the ``hdf5plugin`` filters to be read.

The choice was measured on the twin's IMU output (``bench/bench_recording.py``; the table is in
``docs/recording-format.md``, *Size and compression*). Blosc (Alted 2010, "Why modern CPUs are
starving and what can be done about it", Computing in Science & Engineering 12(2)) splits a
chunk into blocks, applies a bit-shuffle (Masui et al. 2015, "A compression scheme for radio
data in high performance computing", Astronomy and Computing 12) that groups the bits of equal
significance, then LZ4: integer counts of noisy sensor output compress about 2.3× at several
hundred MB/s both ways, time stamps and counters 30× or more. The filters are registered by
importing ``hdf5plugin`` (https://hdf5plugin.readthedocs.io), which this module does; other HDF5
tools (MATLAB, HDFView) need the HDF5 Blosc plugin installed to read such files, or the file
written with ``compression="gzip"`` (HDF5's own shuffle + deflate), which every HDF5 reads.
"""

from __future__ import annotations

from typing import Any, Final

import h5py
import hdf5plugin

__all__ = [
    "COMPRESSIONS",
    "DEFAULT_COMPRESSION",
    "column_filter_kwargs",
    "compression_of",
    "copy_filter_kwargs",
    "needs_plugin",
]

#: Compression names of stream columns: ``None`` (uncompressed), ``"lzf"``, ``"gzip"`` (HDF5's
#: byte shuffle + deflate level 1, readable by every HDF5), ``"blosc-lz4"`` (Blosc, bit-shuffle,
#: LZ4; needs the plugin) and ``"blosc-zstd"`` (Blosc, bit-shuffle, Zstandard level 1: smaller,
#: slower; needs the plugin).
COMPRESSIONS: Final = (None, "lzf", "gzip", "blosc-lz4", "blosc-zstd")
DEFAULT_COMPRESSION: Final = "blosc-lz4"
_PLUGIN: Final = frozenset({"blosc-lz4", "blosc-zstd"})


def needs_plugin(compression: str | None) -> bool:
    """Return whether `compression` is read only where the HDF5 Blosc filter is registered."""
    return compression in _PLUGIN


def column_filter_kwargs(compression: str | None) -> dict[str, Any]:
    """Return the ``h5py`` ``create_dataset`` keywords of a compression name.

    Parameters
    ----------
    compression : str or None
        One of :data:`COMPRESSIONS` (checked by the caller).
    """
    if compression is None:
        return {}
    if compression == "lzf":
        return {"compression": "lzf"}
    if compression == "gzip":
        return {"compression": "gzip", "compression_opts": 1, "shuffle": True}
    bits = hdf5plugin.Blosc.BITSHUFFLE
    if compression == "blosc-lz4":
        return dict(hdf5plugin.Blosc(cname="lz4", clevel=5, shuffle=bits))
    return dict(hdf5plugin.Blosc(cname="zstd", clevel=1, shuffle=bits))


def compression_of(ds: h5py.Dataset) -> str | None:
    """Return the name in :data:`COMPRESSIONS` of a dataset's compression (None: none known).

    Blosc with another compressor than LZ4 counts as ``"blosc-zstd"``.
    """
    filters = ds._filters
    if "32001" in filters or 32001 in filters:
        opts = filters.get("32001", filters.get(32001, ()))
        return "blosc-lz4" if len(opts) > 6 and opts[6] == 1 else "blosc-zstd"
    if ds.compression in ("gzip", "lzf"):
        return str(ds.compression)
    return None


def copy_filter_kwargs(src: h5py.Dataset) -> dict[str, Any]:
    """Return ``create_dataset`` keywords that give a new dataset the filters of `src`.

    HDF5's own filters (deflate, LZF, shuffle, Fletcher-32) are copied by name; a plugin filter
    (Blosc) by its registered number and options. A dataset with more than one plugin filter is
    not written by imucalib; its first plugin filter is kept.
    """
    kwargs: dict[str, Any] = {}
    if src.compression in ("gzip", "lzf"):
        kwargs.update(compression=src.compression, compression_opts=src.compression_opts)
    if src.shuffle:
        kwargs["shuffle"] = True
    if src.fletcher32:
        kwargs["fletcher32"] = True
    if "compression" not in kwargs:
        known = {str(h5py.h5z.FILTER_DEFLATE), str(h5py.h5z.FILTER_LZF),
                 str(h5py.h5z.FILTER_SHUFFLE), str(h5py.h5z.FILTER_FLETCHER32),
                 "gzip", "lzf", "shuffle", "fletcher32"}
        for fid, opts in src._filters.items():
            if str(fid) not in known and str(fid).isdigit():
                kwargs.update(compression=int(fid), compression_opts=tuple(opts),
                              allow_unknown_filter=True)
                break
    return kwargs
