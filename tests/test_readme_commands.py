"""The README's shell commands run as shown, in order, without a terminal (examples are tests).

Every command of README.md's ``sh`` blocks runs in one fresh folder as ``python -m imucalib …``
with stdin closed and no terminal, so a command that would ask a question or needs a file the
README does not make fails here. Only the commands in :data:`SKIPPED` are not run, each for the
reason it gives; :data:`EXPECTED_EXIT` names the commands whose documented exit code is not 0.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"

#: Commands not run, by their text (comments stripped), with the reason.
SKIPPED = {
    "make demo": "builds the virtual environment and runs the demo (make, not imucalib)",
    "make test": "runs the whole suite, this test included",
    "imucalib simulate my_scenario.toml --out mine.h5": (
        "a scenario file the reader writes (docs/twin.md); the built-in ones run above"),
}

#: Commands whose documented exit code is not 0.
EXPECTED_EXIT = {
    # The README runs it on the finished run above: nothing is left to resume, said in one line.
    "imucalib run --resume runs/p1.h5 --yes": 2,
}


def readme_commands() -> list[str]:
    """The commands of README.md's ``sh`` blocks, in order, without their comments."""
    blocks = re.findall(r"```sh\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)
    commands = []
    for block in blocks:
        for line in block.splitlines():
            words = shlex.split(line, comments=True)
            if words:
                commands.append(shlex.join(words))
    return commands


def test_the_readme_has_commands_and_the_skip_list_is_current():
    commands = readme_commands()
    assert any(c.startswith("imucalib run ") for c in commands)
    for listed in (*SKIPPED, *EXPECTED_EXIT):
        assert listed in commands, f"{listed!r} is no longer in README.md; update the lists"
    for command in commands:
        assert command.startswith("imucalib ") or command in SKIPPED, command


@pytest.mark.slow
def test_readme_commands_run_as_shown(tmp_path):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT / "src"), *filter(None, [os.environ.get("PYTHONPATH")])])}
    env.pop("COLUMNS", None)
    for command in readme_commands():
        if command in SKIPPED:
            continue
        argv = [sys.executable, "-m", "imucalib", *shlex.split(command)[1:]]
        done = subprocess.run(argv, cwd=tmp_path, env=env, stdin=subprocess.DEVNULL,
                              capture_output=True, text=True, timeout=600)
        expected = EXPECTED_EXIT.get(command, 0)
        assert done.returncode == expected, (
            f"`{command}` exited {done.returncode}, not {expected}:\n{done.stdout}\n{done.stderr}")
        assert "Traceback" not in done.stderr, (command, done.stderr)
        if expected:
            assert len(done.stderr.strip().splitlines()) == 1, (command, done.stderr)
