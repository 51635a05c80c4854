"""Installation errors (registered as ``"installation"``).

The gyro triad's misalignment angles from one +ω and one −ω turn with each axis up
(docs/installation.md).
"""
