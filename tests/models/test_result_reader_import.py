"""The result and its reader import each other in neither direction that would make a circle."""

from __future__ import annotations

import subprocess
import sys


def test_the_reader_imports_first_in_a_fresh_interpreter_without_the_result():
    code = ("import sys\n"
            "import imucalib.models._result_reader as reader\n"
            "assert 'imucalib.models.result' not in sys.modules, 'the reader imports the result'\n"
            "from imucalib.models.result import CalibrationResult\n"
            "assert reader.ResultReader is sys.modules['imucalib.models.result'].ResultReader\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
