"""Gyro random drift and accelerometer zero stability (docs/random-drift.md)."""
