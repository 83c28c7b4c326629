"""``sitar.estimate`` against ``sitar estimate --format json`` on the real runs: the same
windows, errors, pair counts and classes, from paths or from PoseTrajectory3D objects; with a
calibration, for several runs (the expected error), one run (its own error) and a live run
with replays. ``sitar.calibrate`` against the file ``sitar calibrate`` writes."""

import json
import os
import subprocess

import numpy as np
import pytest

import sitar
from sitar.evo.tools import file_interface

from conftest import REAL_RUNS


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


def cli_path():
    binary = os.environ.get("SITAR_BIN")
    if not binary:
        pytest.skip("SKIPPED: no sitar CLI with `calibrate` (set SITAR_BIN)")
    return binary


@pytest.fixture(scope="module")
def euroc_vio(tmp_path_factory):
    """The shared real runs (three EuRoC sequences, runs/ each) and the calibration the CLI
    fits on them (``sitar calibrate FOLDER -o FILE``)."""
    folder = REAL_RUNS
    if not all((folder / s / "ground_truth.txt").is_file() for s in ("MH_04", "MH_05", "V1_02")):
        pytest.skip(f"SKIPPED: the real runs are missing ({folder})")
    out = tmp_path_factory.mktemp("calibration") / "euroc-vio.json"
    subprocess.run([cli_path(), "calibrate", str(folder), "-o", str(out)], check=True,
                   capture_output=True, text=True)
    return folder, out


def assert_same_numbers(ours, theirs, path="calibration"):
    """Equal JSON values, numbers to 1e-9."""
    if isinstance(theirs, dict):
        assert isinstance(ours, dict) and sorted(ours) == sorted(theirs), path
        for key in theirs:
            assert_same_numbers(ours[key], theirs[key], f"{path}.{key}")
    elif isinstance(theirs, list):
        assert isinstance(ours, list) and len(ours) == len(theirs), path
        for i, (a, b) in enumerate(zip(ours, theirs)):
            assert_same_numbers(a, b, f"{path}[{i}]")
    elif isinstance(theirs, float) and not isinstance(ours, bool):
        assert ours == pytest.approx(theirs, rel=0, abs=1e-9), path
    else:
        assert ours == theirs, path


def test_calibrate_equals_the_cli_s_file(euroc_vio, tmp_path):
    folder, cli_file = euroc_vio
    theirs = json.loads(cli_file.read_text())
    written = tmp_path / "ours.json"
    ours = sitar.calibrate(folder, output=written)
    assert_same_numbers(ours, theirs)
    assert_same_numbers(json.loads(written.read_text()), theirs)
    assert [s["name"] for s in ours["fitted_on"]["sequences"]] == ["MH_04", "MH_05", "V1_02"]
    assert [(m["target"], m["runs"]) for m in ours["models"]] == [
        ("live", "one"), ("live", "several"), ("expected", "several")]
    # The same sequences as folders one by one, and as (name, gt, set_a, set_b) of paths and
    # of PoseTrajectory3D objects (half the runs, rounded up, in set A, as runs/ is split).
    assert_same_numbers(sitar.calibrate([folder / s for s in ("MH_04", "MH_05", "V1_02")]), theirs)
    given = []
    for name in ("MH_04", "MH_05", "V1_02"):
        runs = sorted((folder / name / "runs").glob("*.txt"), key=lambda p: int(p.stem[3:]))
        k = (len(runs) + 1) // 2
        given.append((name, folder / name / "ground_truth.txt", runs[:k], runs[k:]))
    assert_same_numbers(sitar.calibrate(given), theirs)
    read = file_interface.read_tum_trajectory_file
    objects = [(n, read(str(gt)), [read(str(r)) for r in a], [read(str(r)) for r in b])
               for n, gt, a, b in given]
    # Float seconds hold EuRoC's stamps to ~1e-7 s, within t_max_diff: the same windows
    # associate, and the file is the same to 1e-9.
    assert_same_numbers(sitar.calibrate(objects), theirs)


def cli_windows(*args):
    out = subprocess.run([cli_path(), "estimate", *map(str, args), "--format", "json"],
                         check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def assert_same_estimate(ours, doc):
    windows = doc["windows"]
    assert len(ours["error"]) == len(windows)
    np.testing.assert_allclose(ours["error"], [w["error_m"] for w in windows], rtol=0, atol=1e-9)
    np.testing.assert_allclose(ours["raw"], [np.nan if w["raw_m"] is None else w["raw_m"]
                                             for w in windows], rtol=0, atol=1e-9)
    np.testing.assert_allclose(ours["lower"], [w["lower_m"] for w in windows], rtol=0, atol=1e-9)
    np.testing.assert_allclose(ours["upper"], [w["upper_m"] for w in windows], rtol=0, atol=1e-9)
    assert ours["pairs"].tolist() == [w["pairs"] for w in windows]
    assert ours["class"].tolist() == [w["class"] for w in windows]
    np.testing.assert_allclose(ours["start"], [float(w["start"]) for w in windows], rtol=0, atol=1e-6)
    for key in ("target", "runs", "informative", "calibration"):
        assert ours[key] == doc[key], key


def test_the_calibrated_estimate_equals_the_cli_s(euroc_vio, mh04):
    _, cli_file = euroc_vio
    _, runs = mh04
    # Several runs: the expected error.
    ours = sitar.estimate(runs, calibration=cli_file)
    assert (ours["target"], ours["runs"], ours["informative"]) == ("expected", 3, True)
    assert_same_estimate(ours, cli_windows(*runs, "--calibration", cli_file))
    # One run: its own error from its own motion.
    ours = sitar.estimate(runs[:1], calibration=cli_file)
    assert (ours["target"], ours["runs"]) == ("live", 1)
    assert np.all(np.isnan(ours["raw"])) and np.all(ours["lower"] <= ours["upper"])
    assert_same_estimate(ours, cli_windows(runs[0], "--calibration", cli_file))
    # A live run with replays; the calibration as the dict sitar.calibrate returns.
    as_dict = json.loads(cli_file.read_text())
    ours = sitar.estimate(runs[1:], live=runs[0], calibration=cli_file)
    assert (ours["target"], ours["runs"]) == ("live", 3)
    assert_same_estimate(ours, cli_windows(*runs[1:], "--live", runs[0], "--calibration", cli_file))
    from_dict = sitar.estimate(runs[1:], live=runs[0], calibration=as_dict)
    assert from_dict["calibration"] == "calibration"
    np.testing.assert_array_equal(from_dict["error"], ours["error"])
    # Without a calibration, a live run's spread against its replays (no target).
    ours = sitar.estimate(runs[1:], live=runs[0])
    assert ours["target"] is None and ours["informative"] is None and ours["runs"] == 3
    doc = cli_windows(*runs[1:], "--live", runs[0])
    np.testing.assert_allclose(ours["error"], [w["error_m"] for w in doc["windows"]], rtol=0, atol=1e-9)


def test_estimate_errors_name_what_is_wrong(mh04, tmp_path):
    _, runs = mh04
    with pytest.raises(ValueError, match="one run has no spread to measure"):
        sitar.estimate(runs[:1])
    with pytest.raises(ValueError, match="one run has no spread to measure"):
        sitar.estimate(runs[0])
    with pytest.raises(ValueError, match="setting"):
        sitar.estimate(runs, setting="trim_mean_55")
    with pytest.raises(TypeError, match=r"trajectories\[1\]"):
        sitar.estimate([runs[0], 3.5])
    with pytest.raises(TypeError, match="live"):
        sitar.estimate(runs, live=3.5)
    with pytest.raises(TypeError, match="calibration"):
        sitar.estimate(runs, calibration=3.5)
    bad = tmp_path / "calibration.json"
    bad.write_text("{}")
    with pytest.raises(sitar.SitarError, match="calibration.json"):
        sitar.estimate(runs, calibration=bad)
    with pytest.raises(FileNotFoundError, match="missing.json"):
        sitar.estimate(runs, calibration=tmp_path / "missing.json")
    with pytest.raises(FileNotFoundError, match="missing.txt"):
        sitar.estimate([runs[0], tmp_path / "missing.txt"])


def test_calibrate_errors_name_what_is_wrong(mh04, tmp_path):
    gt, runs = mh04
    with pytest.raises(ValueError, match="coverage must be between 0 and 1"):
        sitar.calibrate([("MH_04", gt, runs[:1], runs[1:])], coverage=1.5)
    with pytest.raises(ValueError, match="pose_relation: a calibration is fitted for trans_part or angle_deg"):
        sitar.calibrate([("MH_04", gt, runs[:1], runs[1:])], pose_relation="full")
    with pytest.raises(ValueError, match=r"MH_04.*set B at least 2 \(got 2 and 1\)"):
        sitar.calibrate([("MH_04", gt, runs[:2], runs[2:])])
    with pytest.raises(TypeError, match=r"sequences\[0\]"):
        sitar.calibrate([3.5])
    with pytest.raises(FileNotFoundError, match="nowhere"):
        sitar.calibrate(tmp_path / "nowhere")
    with pytest.raises(ValueError, match="neither a sequence"):
        sitar.calibrate(tmp_path)
    seq = tmp_path / "seq"
    (seq / "runs").mkdir(parents=True)
    (seq / "ground_truth.txt").write_text(gt.read_text())
    for k in range(3):
        (seq / "runs" / f"run{k}.txt").write_text(runs[k].read_text())
    with pytest.raises(ValueError, match="3 runs, at least 4"):
        sitar.calibrate(seq)
    (seq / "runs" / "run3.txt").write_text("")
    with pytest.raises(sitar.SitarError, match=r"run3.txt: no poses"):
        sitar.calibrate(seq)
    with pytest.raises(ValueError, match="split=3: set A needs at least 1 of the 4 runs"):
        sitar.calibrate(seq, split=3)
