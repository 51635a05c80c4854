"""Gyro rate transfer (registered as ``"rate-transfer"``).

Scale factor, bias, nonlinearity and asymmetry of each gyro from turns at several rates on a
single-axis table (docs/rate-transfer.md).
"""
