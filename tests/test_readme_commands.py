"""The README's shell commands run as shown, in order, without a terminal (examples are tests).

Every command of README.md's ``sh`` blocks runs as ``python -m imucalib …`` with stdin closed and
no terminal, so a command that would ask a question or needs a file the README does not make
fails here. The blocks form independent chains (:func:`readme_chains`: a block that names a file
an earlier block names continues that block's chain, any other starts its own), each run in
order in one fresh folder, so that the suite's workers run the chains side by side; a block that
needs an earlier chain's file without naming it fails here too. Only the commands in
:data:`SKIPPED` are not run, each for the reason it gives; :data:`EXPECTED_EXIT` names the
commands whose documented exit code is not 0.
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


def _blocks() -> list[list[str]]:
    """The commands of each of README.md's ``sh`` blocks, without their comments."""
    blocks = re.findall(r"```sh\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)
    out = []
    for block in blocks:
        commands = []
        for line in block.splitlines():
            words = shlex.split(line, comments=True)
            if words:
                commands.append(shlex.join(words))
        out.append(commands)
    return out


def readme_commands() -> list[str]:
    """The commands of README.md's ``sh`` blocks, in order, without their comments."""
    return [c for block in _blocks() for c in block]


def _files(commands: list[str]) -> set[str]:
    """The file names a block's commands name (words with a dot that are not options)."""
    return {w for c in commands for w in shlex.split(c)[1:]
            if "." in w and not w.startswith("-")}


def readme_chains() -> list[list[str]]:
    """The README's commands as chains of blocks that share files (module docstring)."""
    chains: list[list[str]] = []
    names: list[set[str]] = []
    for block in _blocks():
        files = _files(block)
        joined = next((i for i in reversed(range(len(chains))) if files & names[i]), None)
        if joined is None:
            chains.append(list(block))
            names.append(set(files))
        else:
            chains[joined] += block
            names[joined] |= files
    return [c for c in chains if any(cmd not in SKIPPED for cmd in c)]


def test_the_readme_has_commands_and_the_skip_list_is_current():
    commands = readme_commands()
    assert any(c.startswith("imucalib run ") for c in commands)
    for listed in (*SKIPPED, *EXPECTED_EXIT):
        assert listed in commands, f"{listed!r} is no longer in README.md; update the lists"
    for command in commands:
        assert command.startswith("imucalib ") or command in SKIPPED, command


def test_the_chains_hold_every_command_once_in_the_readme_order():
    chains = readme_chains()
    assert len(chains) >= 2  # the P1 walk, the Allan walk, the twin's scenarios
    run = [c for chain in chains for c in chain]
    commands = [c for c in readme_commands() if any(c in chain for chain in chains)]
    assert sorted(run) == sorted(commands) and len(set(run)) == len(run)
    for chain in chains:  # each chain keeps the README's order
        positions = [commands.index(c) for c in chain]
        assert positions == sorted(positions)


@pytest.mark.slow
@pytest.mark.parametrize("chain", readme_chains(), ids=lambda chain: chain[0].split()[1])
def test_readme_commands_run_as_shown(tmp_path, chain):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT / "src"), *filter(None, [os.environ.get("PYTHONPATH")])])}
    env.pop("COLUMNS", None)
    for command in chain:
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
