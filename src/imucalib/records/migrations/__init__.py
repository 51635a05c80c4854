"""Alembic migrations of the records database (run by :func:`imucalib.records.open_records`)."""
