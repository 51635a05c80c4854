"""The one-line text of an HDF5 write failure (imucalib.io._abandon.failure_text)."""

from __future__ import annotations

from imucalib.io._abandon import failure_text
from imucalib.io.recover import stale_partial


def test_a_failed_write_reads_as_one_line_led_by_the_reason():
    exc = RuntimeError("Unable to synchronously flush file (file write failed: time = Sun Nov 29 "
                       "04:48:30 2026\n, filename = 'f.h5', file descriptor = 3, errno = 28, "
                       "error message = 'No space left on device', buf = 0x55, total write "
                       "size = 524288, bytes this sub-write = 524288, offset = 35754)")
    assert failure_text(exc) == ("No space left on device (HDF5: Unable to synchronously flush "
                                 "file)")


def test_other_messages_keep_their_words_on_one_line():
    assert failure_text(OSError("Unable to open\n  file  (truncated)")) == \
        "Unable to open file (truncated)"
    assert failure_text(RuntimeError()) == "RuntimeError"


def test_the_partial_copy_has_a_name_of_its_own(tmp_path):
    assert stale_partial(tmp_path / "run.h5") == tmp_path / ".run.h5.compact.partial"
