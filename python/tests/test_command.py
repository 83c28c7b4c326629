"""The ``sitar`` command the package installs is the CLI: the wheel carries its
evo-compatible and beyond-evo commands, listed as the ``sitar`` binary lists them."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import sitar

WHEEL_COMMANDS = ["ape", "rpe", "traj", "res", "drift", "relative", "bench"]


def installed_command():
    command = shutil.which("sitar", path=str(Path(sys.executable).parent))
    assert command, "installing the package puts the sitar command next to python"
    return command


def test_the_installed_command_runs_the_cli(synthetic):
    ref, est = synthetic
    command = installed_command()
    out = subprocess.run([command, "ape", "tum", str(ref), str(est), "-a", "--format", "json"],
                         check=True, capture_output=True, text=True)
    assert json.loads(out.stdout)["alignment"] == "se3"
    failed = subprocess.run([command, "ape", "tum", str(ref)], capture_output=True, text=True)
    assert failed.returncode != 0 and "EST_FILE" in failed.stderr.upper()


def test_the_wheel_s_command_lists_the_evo_and_beyond_evo_commands_as_the_binary():
    if not os.environ.get("SITAR_EXPECT_WHEEL"):
        pytest.skip("SKIPPED: not the wheel's test (SITAR_EXPECT_WHEEL unset)")
    source = Path(__file__).resolve().parents[1] / "sitar"
    assert not Path(sitar.__file__).resolve().is_relative_to(source), (
        f"the tests import the installed wheel, not the source tree ({sitar.__file__})"
    )
    ours = subprocess.run([installed_command(), "--help"], check=True, capture_output=True,
                          text=True).stdout.splitlines()
    binary = os.environ.get("SITAR_BIN")
    theirs = subprocess.run([binary, "--help"], check=True, capture_output=True,
                            text=True).stdout.splitlines() if binary else []
    for name in WHEEL_COMMANDS:
        line = [l for l in ours if l.strip().split(" ", 1)[0] == name]
        assert line, f"the wheel's sitar --help lists {name}"
        if theirs:
            assert line[0].strip() in [l.strip() for l in theirs], f"{name} as the binary says it"
    for absent in ("serve", "worker", "demo"):
        assert not [l for l in ours if l.strip().split(" ", 1)[0] == absent], (
            f"the wheel's command has no backend ({absent})")
