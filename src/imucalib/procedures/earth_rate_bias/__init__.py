"""Earth-rate gyro bias: 4-position and up/down methods on a single-axis table (docs/earth-rate-bias.md)."""
