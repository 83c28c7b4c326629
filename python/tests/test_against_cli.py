"""sitar.ape / rpe / drift return the document ``sitar … --format json`` prints."""

import numpy as np
import pytest

import sitar


def rows_as_arrays(doc):
    """The CLI's document with its errors rows as the package gives them."""
    for trial in doc.get("trials", []):
        rows_as_arrays(trial)
    rows = doc.get("errors")
    if isinstance(rows, list):
        doc["errors"] = [np.nan if r["error"] is None else r["error"] for r in rows]
    return doc


def assert_same(doc, cli_doc):
    cli_doc = rows_as_arrays(cli_doc)
    assert set(doc) == set(cli_doc)
    for key, value in cli_doc.items():
        if key == "trials":
            assert len(doc[key]) == len(value)
            for mine, theirs in zip(doc[key], value):
                assert set(mine) == set(theirs)
                for k, v in theirs.items():
                    compare(mine[k], v, k)
        else:
            compare(doc[key], value, key)


def compare(mine, theirs, key):
    if key == "errors":
        assert isinstance(mine, np.ndarray) and mine.dtype == np.float64
        np.testing.assert_array_equal(mine, np.asarray(theirs, dtype=np.float64))
    else:
        assert mine == theirs, key


@pytest.mark.parametrize(
    "options, flags",
    [
        ({}, []),
        ({"align": True}, ["-a"]),
        ({"align": True, "correct_scale": True}, ["-a", "-s"]),
        ({"align": True, "n_to_align": 50, "pose_relation": "angle_deg"}, ["-a", "--n_to_align", "50", "-r", "angle_deg"]),
        ({"align": True, "yaw_only": True, "pose_relation": "along_track"}, ["-a", "--yaw_only", "-r", "along_track"]),
        ({"align_origin": True, "t_max_diff": 0.02}, ["--align_origin", "--t_max_diff", "0.02"]),
    ],
)
def test_ape_equals_the_cli_on_a_real_run(mh04, cli, options, flags):
    gt, runs = mh04
    doc = sitar.ape("tum", gt, runs[0], **options)
    assert doc["metric"] == "ape" and len(doc["errors"]) > 100
    assert_same(doc, cli("ape", "tum", gt, runs[0], *flags))


@pytest.mark.parametrize(
    "options, flags",
    [
        ({}, []),
        ({"align": True, "delta": 10, "all_pairs": True}, ["-a", "-d", "10", "--all_pairs"]),
        ({"align": True, "delta": 1, "delta_unit": "m", "pose_relation": "angle_deg"}, ["-a", "-d", "1", "-u", "m", "-r", "angle_deg"]),
    ],
)
def test_rpe_equals_the_cli_on_a_real_run(mh04, cli, options, flags):
    gt, runs = mh04
    doc = sitar.rpe("tum", gt, runs[1], **options)
    assert doc["metric"] == "rpe" and doc["errors"].ndim == 1
    assert_same(doc, cli("rpe", "tum", gt, runs[1], *flags))


def test_drift_equals_the_cli_on_a_real_run(mh04, cli):
    gt, runs = mh04
    doc = sitar.drift("tum", gt, runs[0], lengths=[1, 2, 4, 8], align=True)
    assert doc["metric"] == "drift" and doc["segments"] > 10
    assert_same(doc, cli("drift", "tum", gt, runs[0], "--lengths", "1,2,4,8", "-a"))


def test_repeated_runs_equal_the_cli(mh04, cli):
    gt, runs = mh04
    doc = sitar.ape("tum", gt, runs, align=True, correct_scale=True)
    assert doc["runs"] == 3 and all(isinstance(t["errors"], np.ndarray) for t in doc["trials"])
    assert_same(doc, cli("ape", "tum", gt, *runs, "-a", "-s"))


def test_synthetic_pair_equals_the_cli(synthetic, cli):
    ref, est = synthetic
    doc = sitar.ape("tum", ref, est, align=True)
    assert doc["statistics"]["rmse"] < 0.02  # the offset is aligned away, the noise stays
    assert_same(doc, cli("ape", "tum", ref, est, "-a"))
    doc = sitar.rpe("tum", ref, est, delta=5, pose_relation="trans_part")
    assert_same(doc, cli("rpe", "tum", ref, est, "-d", "5", "-r", "trans_part"))
