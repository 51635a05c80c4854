"""A closed Recording's steps table is read and parsed once per opened file."""

from __future__ import annotations

from imucalib.io import open_recording
from imucalib.io.reader import Recording


def test_steps_parsed_once(consumer_run, monkeypatch):
    calls = []
    real = Recording._read_steps

    def counted(self):
        calls.append(1)
        return real(self)

    monkeypatch.setattr(Recording, "_read_steps", counted)
    with open_recording(consumer_run) as rec:
        first = rec.steps
        first.clear()  # a caller's list is its own: the cache is not changed through it
        again = rec.steps
        for st in again:
            assert rec.step(st.index) == st
    assert len(again) > 3 and len(calls) == 1
    with open_recording(consumer_run) as rec:
        assert repr(rec.steps) == repr(again)
    assert len(calls) == 2


def test_stream_extents_read_once(consumer_run, monkeypatch):
    """The streams' extents (first and last stamps of every stream) likewise, as copies."""
    calls = []
    real = Recording._info

    def counted(self, path, committed=None):
        calls.append(path)
        return real(self, path, committed)

    monkeypatch.setattr(Recording, "_info", counted)
    with open_recording(consumer_run) as rec:
        first = rec.streams
        n = len(calls)
        first[0].columns.clear()  # a caller's info is its own
        again = rec.streams
        assert len(calls) == n and again[0].columns
        assert [(s.device, s.unit, s.n_samples, s.t_first_s, s.t_last_s) for s in again] == \
            [(s.device, s.unit, s.n_samples, s.t_first_s, s.t_last_s) for s in first]
    with open_recording(consumer_run) as rec:
        assert rec.streams
    assert len(calls) == 2 * n
