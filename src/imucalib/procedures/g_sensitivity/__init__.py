"""Gyro g-sensitivity from static positions on a dual-axis table (docs/g-sensitivity.md)."""
