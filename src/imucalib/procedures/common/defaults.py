"""What a procedure inherits when it has nothing of its own to say: :class:`ProcedureDefaults`.

The generic report and terminal hooks (:class:`~imucalib.procedures.common.reporting.
GenericReporting`), and ``analyze_many`` refused: the procedure analyses one recording at a time
(only a procedure that calibrates a lot, P2, overrides it). The built-in procedures and a plug-in
may inherit it (docs/plugins.md).

Contents
--------
:class:`ProcedureDefaults`
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from imucalib.errors import InvalidInputError
from imucalib.procedures.common.reporting import GenericReporting

if TYPE_CHECKING:
    from imucalib.io.reader import Recording

__all__ = ["ProcedureDefaults"]


class ProcedureDefaults(GenericReporting):
    """The generic report, console and summary hooks, and one recording at a time."""

    def output_writers(self) -> Mapping[str, Callable[[Any, Path, str], list[Path]]]:
        """Return no output format of its own: the shared ones serve."""
        return {}

    def batch_outputs(self, batch: Any, folder: Path, stem: str) -> list[Path]:
        """Write nothing: the procedure makes no batch."""
        return []

    def analyze_many(self, recordings: Sequence[Recording | str | os.PathLike[str]], *,
                     units: Sequence[str] | None = None,
                     options: Mapping[str, Any] | None = None,
                     progress: Callable[[float], None] | None = None) -> Any:
        """Refuse: this procedure analyses one recording at a time.

        Raises
        ------
        InvalidInputError
            Always (the message names the recordings and the procedure).
        """
        first = recordings[0] if recordings else "?"
        raise InvalidInputError(f"several recordings are calibrated together only by a "
                                f"procedure that calibrates a lot (P2); {first} is a "
                                f"{self.name} recording, analysed one at a time")
