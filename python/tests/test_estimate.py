"""``sitar.estimate`` against ``sitar estimate --format json`` on the real runs: the same
windows, errors, pair counts and classes, from paths or from PoseTrajectory3D objects."""

import json
import os
import subprocess

import numpy as np
import pytest

import sitar
from sitar.evo.tools import file_interface


def cli_estimate(runs, *args):
    binary = os.environ.get("SITAR_BIN")
    if not binary:
        pytest.skip("SKIPPED: no sitar CLI with `estimate` (set SITAR_BIN)")
    out = subprocess.run([binary, "estimate", *map(str, runs), "--format", "json", *args],
                         check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


@pytest.mark.parametrize("setting, delta", [("trim_mean_30", 10), ("median", 5)])
def test_the_estimate_equals_the_cli_s(mh04, setting, delta):
    _, runs = mh04
    doc = cli_estimate(runs, "--setting", setting, "-d", str(delta))
    windows = doc["windows"]
    for given in (runs, [file_interface.read_tum_trajectory_file(str(r)) for r in runs]):
        ours = sitar.estimate(given, setting=setting, delta=delta)
        assert ours["trials"] == len(runs) and ours["setting"] == setting
        assert len(ours["error"]) == len(windows)
        assert isinstance(ours["error"], np.ndarray) and ours["error"].dtype == np.float64
        np.testing.assert_allclose(ours["error"], [w["error_m"] for w in windows], rtol=0, atol=1e-9)
        assert ours["pairs"].tolist() == [w["pairs"] for w in windows]
        assert ours["class"].tolist() == [w["class"] for w in windows]
        starts = np.array([float(w["start"]) for w in windows])
        # The CLI prints stamps as written (ns or 9 decimals); float seconds hold 1e-7 s here.
        np.testing.assert_allclose(ours["start"], starts, rtol=0, atol=1e-6)
        assert np.all(np.isnan(ours["lower"])) and ours["calibration"] is None


def test_estimate_errors_name_what_is_wrong(mh04, tmp_path):
    _, runs = mh04
    with pytest.raises(ValueError, match="at least 2"):
        sitar.estimate(runs[:1])
    with pytest.raises(ValueError, match="setting"):
        sitar.estimate(runs, setting="trim_mean_55")
    with pytest.raises(TypeError, match=r"trajectories\[1\]"):
        sitar.estimate([runs[0], 3.5])
    bad = tmp_path / "calibration.json"
    bad.write_text("{}")
    with pytest.raises(sitar.SitarError, match="calibration.json"):
        sitar.estimate(runs, calibration=bad)
    with pytest.raises(FileNotFoundError):
        sitar.estimate([runs[0], tmp_path / "missing.txt"])
    with pytest.raises(NotImplementedError, match="sitar calibrate"):
        sitar.calibrate(runs)
