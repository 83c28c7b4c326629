"""The ``sitar`` command the package installs is the CLI."""

import json
import shutil
import subprocess
import sys


def test_the_installed_command_runs_the_cli(synthetic):
    ref, est = synthetic
    command = shutil.which("sitar", path=str(__import__("pathlib").Path(sys.executable).parent))
    assert command, "pip install ./python installs the sitar command next to python"
    out = subprocess.run([command, "ape", "tum", str(ref), str(est), "-a", "--format", "json"],
                         check=True, capture_output=True, text=True)
    assert json.loads(out.stdout)["alignment"] == "se3"
    failed = subprocess.run([command, "ape", "tum", str(ref)], capture_output=True, text=True)
    assert failed.returncode != 0 and "EST_FILE" in failed.stderr.upper()
