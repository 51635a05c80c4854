"""The body of one process of test_concurrency's simultaneous openings (imported by the child)."""

from __future__ import annotations

from multiprocessing.synchronize import Barrier
from typing import Any


def open_and_write(urls: list[str], worker: int, barrier: Barrier, out: Any) -> None:
    """Open each new database at the same instant as the other process, and append a unit."""
    from imucalib.errors import CalibrationError
    from imucalib.records import open_records

    failures = []
    for url in urls:
        barrier.wait(timeout=60)
        try:
            with open_records(url) as rec:
                rec.add_unit(f"W{worker}")
        except CalibrationError as exc:
            failures.append(f"{url}: {exc}")
    out.put((worker, failures))
