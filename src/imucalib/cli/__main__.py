"""``python -m imucalib.cli``."""

from imucalib.cli import main

main()
