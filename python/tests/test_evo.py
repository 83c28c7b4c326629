"""A couple of values against evo's own Python API (evo 1.38.1), when evo is installed."""

import copy

import pytest

import sitar

evo = pytest.importorskip("evo", reason="SKIPPED: evo is not installed")
from evo.core import metrics, sync  # noqa: E402
from evo.tools import file_interface  # noqa: E402


def evo_pair(gt, run):
    ref = file_interface.read_tum_trajectory_file(str(gt))
    est = file_interface.read_tum_trajectory_file(str(run))
    return sync.associate_trajectories(ref, est, max_diff=0.01)


def test_ape_with_sim3_alignment_equals_evo(mh04):
    gt, runs = mh04
    ref, est = evo_pair(gt, runs[0])
    est = copy.deepcopy(est)
    est.align(ref, correct_scale=True)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, est))
    doc = sitar.ape("tum", gt, runs[0], align=True, correct_scale=True,
                    pose_relation=metrics.PoseRelation.translation_part)
    assert doc["statistics"]["rmse"] == pytest.approx(ape.get_statistic(metrics.StatisticsType.rmse), rel=1e-12)
    assert doc["errors"] == pytest.approx(ape.error, rel=1e-9, abs=1e-12)


def test_rpe_equals_evo(mh04):
    gt, runs = mh04
    ref, est = evo_pair(gt, runs[1])
    rpe = metrics.RPE(metrics.PoseRelation.rotation_angle_deg, delta=10,
                      delta_unit=metrics.Unit.frames, all_pairs=False)
    rpe.process_data((ref, est))
    doc = sitar.rpe("tum", gt, runs[1], pose_relation="angle_deg", delta=10,
                    delta_unit=metrics.Unit.frames)
    assert doc["statistics"]["mean"] == pytest.approx(rpe.get_statistic(metrics.StatisticsType.mean), rel=1e-9)
    assert len(doc["errors"]) == len(rpe.error)
