"""``python -m imucalib``: the ``imucalib`` command."""

from imucalib.cli import main

main()
