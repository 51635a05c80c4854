"""imucalib: the software of an inertial-sensor calibration station.

It plans a calibration, drives (or simulates) the rate table, thermal chamber and centrifuge,
records every sample in a crash-safe HDF5 Recording, estimates every error parameter with its
uncertainty, verifies the result and decides pass/fail; it writes the result for other tools and
for firmware, reports it (the calibration certificate, PDF or HTML) and keeps it in a
hash-chained records database. The flow and the layers: docs/architecture.md.

Eleven procedures come with it: ``p1``, ``allan``, ``p2``, ``p3``, ``rate-transfer``,
``installation``, ``g-sensitivity``, ``earth-rate-bias``, ``random-drift``, ``tumble`` and
``field`` (docs/procedures.md). They are found through the ``imucalib.procedures`` entry points,
so an installed distribution can add its own (docs/plugins.md); ``imucalib procedures`` lists
them and ``imucalib procedures NAME`` a procedure's plan and analysis options.

Conventions (frames, signs, units) are defined once in :mod:`imucalib.conventions`; SI is used
inside, and every public name carrying a quantity ends in its unit (``rate_rps``, ``duration_s``;
docs/conventions.md).

Subpackages
-----------
What each may import is ranked in docs/architecture.md, "Layers".

``models``      deterministic error models and stochastic noise models of IMU triads, the Earth
                model, the calibration result and its application to data
``io``          the Recording format (writer, reader, recovery) and the CSV importers
``processing``  outliers, low-pass, time synchronisation, window statistics, segmentation
``estimation``  weighted and nonlinear least squares, Kalman filter, Cramér–Rao bounds
``analysis``    Allan-family deviations, noise-term fits, verification of a calibration
``plan``        test plans: schema and step vocabulary, bounds, equipment, size estimates
``sim``         the station's digital twin (Earth, tables, chamber, centrifuge, fixtures, IMU
                synthesis, hand-held sessions)
``station``     the plan runner (step executors, guards, resume) and the twin as a station
``drivers``     real equipment: transports, device dialects, devices, the station file
``procedures``  the calibration procedures (plan, options, analysis) and their registry
``report``      the terminal rendering, figures and the calibration report
``exports``     output files: result JSON, CSV and MAT, Kalibr/OpenVINS YAML, the C runtime
``records``     the calibration records database (docs/records.md)
``cli``         the ``imucalib`` command (also ``python -m imucalib``); ``demo`` is ``make demo``
"""

from __future__ import annotations

__all__ = ["__version__"]

__version__ = "0.1.0"
