"""The compression filters of a Recording's stream columns: names, HDF5 settings, copies.

Contents
--------
:data:`COMPRESSIONS`
    The names :class:`~imucalib.io.recording.RecordingWriter` accepts.
:data:`DEFAULT_COMPRESSION`
    ``"gzip"``: HDF5's byte shuffle + deflate level 1, the default of new recordings, which
    every HDF5 library and tool reads.
:func:`column_filter_kwargs`
    The ``h5py`` ``create_dataset`` keywords of a compression name.
:func:`copy_filter_kwargs`
    The keywords that give a new dataset the filters of an existing one (recovery's copies).
:func:`compression_of`
    The compression name of an existing dataset.
:func:`needs_plugin`
    Whether a compression name needs the ``hdf5plugin`` filters to be read.
:func:`ensure_plugin`, :func:`register_plugin_filters`
    Register the ``hdf5plugin`` filters (Blosc) when they are needed, and only then.

The choice was measured on the twin's output (``bench/bench_recording.py --codecs FILE``; the
tables are in ``docs/recording-format.md``, *Size and compression*). HDF5's shuffle + deflate
(``"gzip"``, level 1) is built into every HDF5 library (h5py, MATLAB ``h5read``, HDFView,
Octave, ``h5dump``), so a recording opens anywhere; on a P1 run of the twin it made a file
about 10 % smaller than Blosc LZ4, for a close about twice as long (seconds, once per run)
and a read about three times as long. Blosc (Alted 2010, "Why modern CPUs are starving and what
can be done about it", Computing in Science & Engineering 12(2)) splits a chunk into blocks,
applies a bit-shuffle (Masui et al. 2015, "A compression scheme for radio data in high performance
computing", Astronomy and Computing 12) that groups the bits of equal significance, then LZ4
(``"blosc-lz4"``) or Zstandard (``"blosc-zstd"``): it writes and reads several times faster,
but only where the HDF5 Blosc filter is installed (in Python: ``import hdf5plugin``,
https://hdf5plugin.readthedocs.io). LZF (``"lzf"``) is h5py's own filter, missing from MATLAB.

``hdf5plugin`` takes about 0.2 s to import, so it is imported only when needed
(:func:`ensure_plugin`): to write a Blosc compression, and when a file whose columns use a
filter HDF5 lacks is opened (:func:`register_plugin_filters`, called by
:func:`~imucalib.io.opening.open_recording`).
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, Any, Final

if TYPE_CHECKING:  # h5py is imported where a file is touched: `plan show` needs none
    import h5py

from imucalib.errors import InvalidInputError, RecordingError

__all__ = [
    "BLOSC_FILTER_ID",
    "COMPRESSIONS",
    "COMPRESSION_NAMES",
    "DEFAULT_COMPRESSION",
    "column_filter_kwargs",
    "compression_from_name",
    "compression_of",
    "copy_filter_kwargs",
    "ensure_plugin",
    "needs_plugin",
    "register_plugin_filters",
]

#: Compression names of stream columns: ``None`` (uncompressed), ``"lzf"`` (h5py's LZF, not in
#: MATLAB's HDF5), ``"gzip"`` (HDF5's byte shuffle + deflate level 1, readable by every HDF5; the
#: default), ``"blosc-lz4"`` (Blosc, bit-shuffle, LZ4; needs the plugin) and ``"blosc-zstd"``
#: (Blosc, bit-shuffle, Zstandard level 1: smaller, slower; needs the plugin).
COMPRESSIONS: Final = (None, "lzf", "gzip", "blosc-lz4", "blosc-zstd")
DEFAULT_COMPRESSION: Final = "gzip"
#: The registered HDF5 filter number of Blosc (``hdf5plugin.BLOSC_ID``).
BLOSC_FILTER_ID: Final = 32001
#: The names the command line takes (``--compression``): those of :data:`COMPRESSIONS`, the
#: default first, and ``"none"`` for None.
COMPRESSION_NAMES: Final = ("gzip", "blosc-lz4", "blosc-zstd", "lzf", "none")
_PLUGIN: Final = frozenset({"blosc-lz4", "blosc-zstd"})
_STREAM_GROUPS: Final = ("streams", "truth/streams")  # _schema's STREAMS_GROUP, TRUTH_STREAMS_GROUP


def needs_plugin(compression: str | None) -> bool:
    """Return whether `compression` is read only where the HDF5 Blosc filter is registered."""
    return compression in _PLUGIN


def compression_from_name(name: str, what: str = "`compression`") -> str | None:
    """Return the compression of a name of :data:`COMPRESSION_NAMES` (``"none"``: None).

    Raises
    ------
    InvalidInputError
        For any other name; the message names `what` (e.g. ``"--compression"``).
    """
    if name not in COMPRESSION_NAMES:
        raise InvalidInputError(f"{what} must be one of {', '.join(COMPRESSION_NAMES)}; "
                                f"got {name!r}")
    return None if name == "none" else name


def ensure_plugin() -> None:
    """Register ``hdf5plugin``'s filters (Blosc among them) with HDF5 in this process.

    Imports ``hdf5plugin`` (about 0.2 s the first time; nothing afterwards).

    Raises
    ------
    RecordingError
        If ``hdf5plugin`` cannot be imported.
    """
    if sys.modules.get("hdf5plugin") is not None:
        return
    try:
        import hdf5plugin  # noqa: F401  (registers its filters on import)
    except ImportError as exc:
        raise RecordingError(
            f"the Blosc compression (HDF5 filter {BLOSC_FILTER_ID}) needs the hdf5plugin "
            f"package, which cannot be imported ({exc}); install it (pip install hdf5plugin), "
            "or convert the file where it is installed: `imucalib compact FILE --compression "
            "gzip`") from exc


def _lacks_filter(ds: h5py.Dataset) -> bool:
    """Whether a dataset's pipeline holds a filter this process's HDF5 does not have."""
    import h5py

    plist = ds.id.get_create_plist()
    return any(not h5py.h5z.filter_avail(plist.get_filter(i)[0])
               for i in range(plist.get_nfilters()))


def register_plugin_filters(f: h5py.File) -> bool:
    """Register ``hdf5plugin``'s filters if a stream column of `f` uses one HDF5 lacks.

    Looks at the filter pipeline of the columns under ``/streams`` and ``/truth/streams``
    (about 1 ms for twenty columns) and calls :func:`ensure_plugin` at the first filter that
    HDF5 does not have (Blosc, in a file closed with ``"blosc-lz4"`` or ``"blosc-zstd"``). A
    file whose groups cannot all be walked (damaged) gets the plugin too, so that recovery
    reads what it can. Returns whether the plugin is registered.

    Raises
    ------
    RecordingError
        If the plugin is needed and ``hdf5plugin`` cannot be imported.
    """
    if sys.modules.get("hdf5plugin") is not None:
        return True
    import h5py

    found: list[Any] = []

    def visit(_: str, obj: Any) -> Any:
        if isinstance(obj, h5py.Dataset) and _lacks_filter(obj):
            found.append(obj)
            return True  # stop the walk
        return None

    try:
        for base in _STREAM_GROUPS:
            group = f.get(base)
            if isinstance(group, h5py.Group) and group.visititems(visit):
                break
    except (OSError, LookupError, RuntimeError, ValueError, TypeError):
        found.append(None)
    if found:
        ensure_plugin()
    return bool(found)


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
    ensure_plugin()
    import hdf5plugin

    bits = hdf5plugin.Blosc.BITSHUFFLE
    if compression == "blosc-lz4":
        return dict(hdf5plugin.Blosc(cname="lz4", clevel=5, shuffle=bits))
    return dict(hdf5plugin.Blosc(cname="zstd", clevel=1, shuffle=bits))


def compression_of(ds: h5py.Dataset) -> str | None:
    """Return the name in :data:`COMPRESSIONS` of a dataset's compression (None: none known).

    Blosc with another compressor than LZ4 counts as ``"blosc-zstd"``.
    """
    filters = ds._filters
    blosc = str(BLOSC_FILTER_ID)
    if blosc in filters or BLOSC_FILTER_ID in filters:
        opts = filters.get(blosc, filters.get(BLOSC_FILTER_ID, ()))
        return "blosc-lz4" if len(opts) > 6 and opts[6] == 1 else "blosc-zstd"
    if ds.compression in ("gzip", "lzf"):
        return str(ds.compression)
    return None


def copy_filter_kwargs(src: h5py.Dataset) -> dict[str, Any]:
    """Return ``create_dataset`` keywords that give a new dataset the filters of `src`.

    HDF5's own filters (deflate, LZF, shuffle, Fletcher-32) are copied by name; a plugin filter
    (Blosc) by its registered number and options, after registering ``hdf5plugin``'s filters
    (:func:`ensure_plugin`: the copy is written with it). A dataset with more than one plugin
    filter is not written by imucalib; its first plugin filter is kept.
    """
    kwargs: dict[str, Any] = {}
    if src.compression in ("gzip", "lzf"):
        kwargs.update(compression=src.compression, compression_opts=src.compression_opts)
    if src.shuffle:
        kwargs["shuffle"] = True
    if src.fletcher32:
        kwargs["fletcher32"] = True
    if "compression" not in kwargs:
        import h5py

        known = {str(h5py.h5z.FILTER_DEFLATE), str(h5py.h5z.FILTER_LZF),
                 str(h5py.h5z.FILTER_SHUFFLE), str(h5py.h5z.FILTER_FLETCHER32),
                 "gzip", "lzf", "shuffle", "fletcher32"}
        for fid, opts in src._filters.items():
            if str(fid) not in known and str(fid).isdigit():
                ensure_plugin()
                kwargs.update(compression=int(fid), compression_opts=tuple(opts),
                              allow_unknown_filter=True)
                break
    return kwargs
