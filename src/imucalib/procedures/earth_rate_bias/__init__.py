"""Earth-rate gyro bias: 4-position and up/down methods (docs/earth-rate-bias.md)."""
