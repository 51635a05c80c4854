"""A validated copy's seal lets opening skip the probe, and only while its metadata is unchanged.

compact_recording and recover_recording seal the file they validated (imucalib.io._seal); an
open of a sealed file runs the checks in the process, without the forked probe. Every change to
the file outside its raw data breaks the seal, and a damaged file still gets the probe and its
one clear line.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

import imucalib.io.opening as opening
from imucalib.io import open_recording
from imucalib.io._seal import ATTRIBUTE, is_sealed, seal
from imucalib.io.recover import compact_recording, recover_recording

from . import damage


def _xattrs_here(folder: Path) -> bool:
    probe = folder / "xattr-probe"
    probe.write_bytes(b"")
    try:
        os.setxattr(probe, "user.imucalib.test", b"1")
    except (OSError, AttributeError):
        return False
    finally:
        probe.unlink()
    return True


@pytest.fixture(scope="module")
def template(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("sealed")
    if not _xattrs_here(folder):  # the seal's home; without it every open probes (tested below)
        pytest.fail(f"{folder}'s file system has no user extended attributes: the seal's tests "
                    "need one (ext4, xfs, btrfs, tmpfs)")
    return damage.write_small(folder / "small.h5")


@pytest.fixture
def small(template, tmp_path) -> Path:
    path = tmp_path / "run.h5"
    shutil.copy2(template, path)  # copy2 keeps the extended attributes, hence the seal
    return path


class _Probes:
    """Counts the probes that opening forks (the real probe still runs)."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.count = 0
        real = opening.run_probe

        def counted(*args, **kwargs):
            self.count += kwargs.get("fork", True)
            return real(*args, **kwargs)

        monkeypatch.setattr(opening, "run_probe", counted)


def _read_everything(path: Path, **kwargs) -> dict[str, np.ndarray]:
    out = {}
    with open_recording(path, **kwargs) as rec:
        rec.metadata, rec.truth, rec.steps, rec.log  # noqa: B018
        for s in rec.streams:
            data = rec.read_stream(s.device, s.unit)
            out[s.name + "/time_s"] = data.time_s
            out.update({f"{s.name}/{c}": v for c, v in data.columns.items()})
    return out


def test_a_compacted_file_is_sealed_and_opens_without_the_probe(small, monkeypatch):
    assert is_sealed(small)
    probes = _Probes(monkeypatch)
    sealed = _read_everything(small)
    assert probes.count == 0
    unsealed = small.with_name("copy.h5")
    shutil.copyfile(small, unsealed)  # the bytes without the attribute: not sealed
    assert not is_sealed(unsealed)
    plain = _read_everything(unsealed)
    assert probes.count == 1
    assert sealed.keys() == plain.keys()
    for key, values in sealed.items():
        np.testing.assert_array_equal(values, plain[key])


def test_recovery_and_compaction_seal_what_they_write(small, tmp_path):
    out = recover_recording(small, tmp_path / "out.h5").output
    assert is_sealed(out)
    plain = tmp_path / "plain.h5"
    shutil.copyfile(small, plain)
    compact_recording(plain, "lzf")
    assert is_sealed(plain)


#: Damages to the raw data of /steps and /log, edited in place: the seal holds, and the checks
#: that run without the probe find them.
IN_RAW_DATA = {"commanded-not-json", "log-level-unknown", "log-time-nan", "step-index-wrong",
               "step-status-unknown", "step-window-inf"}


@pytest.mark.parametrize("name", sorted(damage.DAMAGES))
def test_a_damaged_sealed_file_still_gets_its_clear_error(small, name, monkeypatch):
    func, error, _ = damage.DAMAGES[name]
    func(small)
    if name not in IN_RAW_DATA:  # the seal broke (checked first: the heap would hang unprobed)
        assert not is_sealed(small)
    probes = _Probes(monkeypatch)
    with pytest.raises(error, match=damage.expected_message(name, small)) as info:
        _read_everything(small, probe_timeout_s=1.0)
    assert "\n" not in str(info.value)
    assert is_sealed(small) is (name in IN_RAW_DATA)
    assert probes.count == (0 if name in IN_RAW_DATA else 1)


def test_metadata_damage_breaks_the_seal_and_raw_data_does_not(small, tmp_path):
    raw = bytearray(small.read_bytes())
    ranges = json.loads(os.getxattr(small, ATTRIBUTE)[:-32])["raw"]
    inside = ranges[0][0] + ranges[0][1] // 2  # a byte of a dataset's raw data
    outside = 9  # the superblock's version byte
    for offset, sealed in ((inside, True), (outside, False)):
        copy = tmp_path / f"at-{offset}.h5"
        shutil.copy2(small, copy)
        changed = bytearray(raw)
        changed[offset] ^= 0x01
        with open(copy, "r+b") as fh:
            fh.write(changed)
        assert is_sealed(copy) is sealed


@pytest.mark.parametrize("edit", ["appended", "truncated", "attribute-size", "attribute-ranges",
                                  "attribute-garbage", "attribute-digest"])
def test_any_change_to_the_file_or_its_seal_unseals_it(small, edit):
    value = os.getxattr(small, ATTRIBUTE)
    body, digest = json.loads(value[:-32]), value[-32:]
    if edit == "appended":
        with open(small, "ab") as fh:
            fh.write(b"\0")
    elif edit == "truncated":
        with open(small, "r+b") as fh:
            fh.truncate(small.stat().st_size - 1)
    elif edit == "attribute-size":
        body["size"] += 1
        os.setxattr(small, ATTRIBUTE, json.dumps(body).encode() + digest)
    elif edit == "attribute-ranges":  # claim the whole file is raw data
        os.setxattr(small, ATTRIBUTE, json.dumps(
            {**body, "raw": [[0, body["size"]]]}, separators=(",", ":")).encode() + digest)
    elif edit == "attribute-garbage":
        os.setxattr(small, ATTRIBUTE, b"{not json" + bytes(32))
    else:
        os.setxattr(small, ATTRIBUTE, value[:-1] + bytes([value[-1] ^ 1]))
    assert not is_sealed(small)


def test_sealing_again_the_same_bytes_gives_the_same_seal(small):
    before = os.getxattr(small, ATTRIBUTE)
    assert seal(small)
    assert os.getxattr(small, ATTRIBUTE) == before


def test_a_missing_or_foreign_file_is_not_sealed(tmp_path):
    assert not is_sealed(tmp_path / "nope.h5")
    empty = tmp_path / "empty.h5"
    empty.write_bytes(b"")
    assert not is_sealed(empty)
