"""Gyro g-sensitivity from static multi-position data on a dual-axis table (docs/g-sensitivity.md)."""
