"""Draw a result's figure once per process: :func:`png_once`.

A result written with both its figure file (``residuals-png``, ``temperature-png``) and its
report (which embeds the same figure) would otherwise be drawn twice; a P2 unit's 36-panel
temperature figure takes about 2 s to draw. The PNG bytes are kept while the result object
lives (a weak reference drops them with it), keyed by the object and the figure's kind.
"""

from __future__ import annotations

import tempfile
import weakref
from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = ["png_once"]

_CACHE: dict[tuple[int, str], bytes] = {}


def png_once(owner: Any, kind: str, draw: Callable[[Path], Any]) -> bytes:
    """Return the PNG bytes `draw(path)` writes for `owner`, drawing only the first time.

    Parameters
    ----------
    owner : object
        The result the figure shows; an object that takes no weak reference is drawn every
        time (nothing would clear its entry).
    kind : str
        The figure's name (one owner may have several figures).
    draw : callable
        Writes the figure as PNG to the path it is given.
    """
    key = (id(owner), kind)
    hit = _CACHE.get(key)
    if hit is not None:
        return hit
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "figure.png"
        draw(path)
        data = path.read_bytes()
    try:
        weakref.finalize(owner, _CACHE.pop, key, None)
    except TypeError:  # no weak reference: do not keep it
        return data
    _CACHE[key] = data
    return data
