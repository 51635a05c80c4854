"""imucalib: the software of an inertial-sensor calibration station.

It plans a calibration, drives (or simulates) the rate table, thermal chamber and centrifuge,
records every sample in a crash-safe HDF5 Recording, and estimates every error parameter with its
uncertainty.

Conventions (frames, signs, units) are defined once in :mod:`imucalib.conventions`; SI is used
inside, and every public name carrying a quantity ends in its unit (``rate_rps``, ``duration_s``).

Subpackages
-----------
``models``  deterministic error models and stochastic noise models of IMU triads
``sim``     the station's digital twin (Earth, tables, chamber, centrifuge, fixtures, IMU synthesis)
``io``      the Recording format, its reader, recovery and exports
"""

from __future__ import annotations

__all__ = ["__version__"]

__version__ = "0.1.0"
