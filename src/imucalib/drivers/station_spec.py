"""The station a run drives, named as ``imucalib run --station`` names it: ``sim`` or a file.

:func:`make_station` is shared by ``imucalib run`` and the web page's run worker
(:mod:`imucalib.web.run_worker`), so that both run a plan on the same station
(docs/station.md, docs/web-runs.md).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from imucalib.errors import ConfigurationError

if TYPE_CHECKING:
    from imucalib.plan.schema import Plan
    from imucalib.station.devices import Station

__all__ = ["make_station"]


def make_station(spec: str, plan: Plan, start_time_s: float = 0.0) -> tuple[Station, str]:
    """Build the station named by ``--station`` (``sim`` or a station TOML file).

    Returns the station and the station file's text (empty for the twin).

    Raises
    ------
    ConfigurationError
        ``sim`` for a plan without a ``[twin]`` table; a station file that cannot be used.
    """
    if spec == "sim":
        from imucalib.station.sim import SimStation

        if plan.twin is None:
            raise ConfigurationError(
                f"plan {plan.name!r} has no [twin] table describing the simulated station; "
                "add one (see `imucalib plan schema`) or give --station STATION.toml")
        return SimStation(plan.twin, start_time_s=start_time_s), ""
    from imucalib.drivers import load_driver_station

    path = Path(spec)
    station: Station = load_driver_station(path, start_time_s=start_time_s)
    return station, path.read_text(encoding="utf-8")
