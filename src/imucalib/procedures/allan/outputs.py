"""The output formats a noise characterisation writes itself: :data:`NOISE_WRITERS`.

``imucalib.exports.outputs.write_outputs`` writes the formats every result has (result JSON,
parameters CSV, reports) and asks the result's procedure for its own
(:meth:`~imucalib.procedures.common.procedure.Procedure.output_writers`). A noise
characterisation's (docs/noise.md, docs/exports.md):

=================  =============================  ================================================
format             file                           content
=================  =============================  ================================================
``noise-json``     ``….json``                     the versioned noise characterisation
``kalibr-yaml``    ``…[.k].kalibr.yaml``          Kalibr ``imu.yaml``, per static record k
``openvins-yaml``  ``…[.k].openvins.yaml``        OpenVINS ``kalibr_imu_chain.yaml``, per record
``noise-table``    ``…[.k].table.md``             the datasheet-style noise table, per record
``figures``        ``….figures/``                 Allan deviation figures (PNG)
=================  =============================  ================================================

The record index ``.k`` appears only when the characterisation holds more than one record.

Contents
--------
:data:`NOISE_WRITERS`
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from imucalib.errors import InvalidInputError

__all__ = ["NOISE_WRITERS"]

_Writer = Callable[[Any, Path, str], list[Path]]


def _noise(result: Any, fmt: str) -> Any:
    from imucalib.procedures.allan.analysis import NoiseCharacterization

    if not isinstance(result, NoiseCharacterization):
        raise InvalidInputError(f"output {fmt!r} needs a noise characterisation (its Allan "
                                f"curves); a {result.procedure} result read back from its "
                                "file holds none: write it from the recording")
    return result


def _noise_json(result: Any, folder: Path, stem: str) -> list[Path]:
    return [_noise(result, "noise-json").save(folder / f"{stem}.json")]


def _per_record(fmt: str, write: Callable[[Path, Any], Path], suffix: str) -> _Writer:
    def writer(result: Any, folder: Path, stem: str) -> list[Path]:
        segments = _noise(result, fmt).segments
        written = []
        for i, seg in enumerate(segments):
            index = "" if len(segments) == 1 else f".{i}"
            written.append(write(folder / f"{stem}{index}{suffix}", seg))
        return written

    return writer


def _kalibr(path: Path, seg: Any) -> Path:
    from imucalib.procedures.allan.noise_exports import write_kalibr_yaml

    return write_kalibr_yaml(path, seg.noise_parameters())


def _openvins(path: Path, seg: Any) -> Path:
    from imucalib.procedures.allan.noise_exports import write_openvins_yaml

    return write_openvins_yaml(path, seg.noise_parameters())


def _table(path: Path, seg: Any) -> Path:
    from imucalib.procedures.allan.noise_exports import format_noise_table

    path.write_text(format_noise_table(seg.fits(), fmt="markdown") + "\n", encoding="utf-8")
    return path


def _figures(result: Any, folder: Path, stem: str) -> list[Path]:
    from imucalib.procedures.allan.figures import save_allan_figures

    return list(save_allan_figures(_noise(result, "figures"), folder / f"{stem}.figures"))


#: A noise characterisation's own output formats → writer(result, folder, stem).
NOISE_WRITERS: Mapping[str, _Writer] = {
    "noise-json": _noise_json,
    "kalibr-yaml": _per_record("kalibr-yaml", _kalibr, ".kalibr.yaml"),
    "openvins-yaml": _per_record("openvins-yaml", _openvins, ".openvins.yaml"),
    "noise-table": _per_record("noise-table", _table, ".table.md"),
    "figures": _figures,
}
