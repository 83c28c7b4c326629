"""``sitar.evo`` against evo's Python API (installed in the test venv): the same script with
its imports changed gives the same numbers (1e-9) on the real runs and synthetic files, the
same in-place and copy semantics, and errors of evo's types."""

import copy
import io
from pathlib import Path

import numpy as np
import pytest

evo_metrics = pytest.importorskip("evo.core.metrics", reason="SKIPPED: evo is not installed")
from evo.core import sync as evo_sync  # noqa: E402
from evo.core import trajectory as evo_trajectory  # noqa: E402
from evo.tools import file_interface as evo_fi  # noqa: E402

from sitar.evo.core import metrics, sync, trajectory  # noqa: E402
from sitar.evo.tools import file_interface  # noqa: E402

TOL = 1e-9


def close(a, b, what):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape, f"{what}: shape {a.shape} vs evo's {b.shape}"
    if a.size:
        # 1e-9, relative to values above 1 (a path of 60 km holds 1e-11 m no more).
        diff = np.nanmax(np.abs(a - b) / np.maximum(1.0, np.abs(b)))
        assert np.array_equal(np.isnan(a), np.isnan(b)), f"{what}: NaN where evo has none"
        assert diff <= TOL, f"{what}: differs from evo by {diff} (relative above 1)"


def same_trajectory(ours, theirs, what):
    close(ours.positions_xyz, theirs.positions_xyz, f"{what} positions_xyz")
    close(ours.orientations_quat_wxyz, theirs.orientations_quat_wxyz, f"{what} quaternions")
    close(np.array(ours.poses_se3), np.array(theirs.poses_se3), f"{what} poses_se3")
    assert ours.num_poses == theirs.num_poses
    close(ours.path_length, theirs.path_length, f"{what} path_length")
    close(ours.distances, theirs.distances, f"{what} distances")
    if hasattr(theirs, "timestamps"):
        close(ours.timestamps, theirs.timestamps, f"{what} timestamps")


@pytest.fixture(scope="module")
def pairs(real_runs, synthetic):
    """(name, reader, ref, est): TUM and EuRoC-CSV-free real runs, KITTI, synthetic TUM."""
    out = [("synthetic", "read_tum_trajectory_file", *synthetic)]
    for name, reader, ref, est in real_runs:
        out.append((name, reader, ref, est))
    return out


def read_both(reader, path):
    return getattr(file_interface, reader)(str(path)), getattr(evo_fi, reader)(str(path))


def test_readers_give_evo_s_values(pairs):
    for name, reader, ref, est in pairs:
        for path in (ref, est):
            ours, theirs = read_both(reader, path)
            assert type(ours).__name__ == type(theirs).__name__
            same_trajectory(ours, theirs, f"{name} {path.name}")
            assert ours.name == theirs.name == str(path)
            assert ours.get_infos().keys() == theirs.get_infos().keys()
            for k, v in theirs.get_infos().items():
                close(ours.get_infos()[k], v, f"{name} info {k}")
            for k, v in theirs.get_statistics().items():
                close(ours.get_statistics()[k], v, f"{name} statistic {k}")
            assert str(ours) == str(theirs)
            assert ours.check() == theirs.check()


def test_readers_take_file_handles_and_csv(synthetic, tmp_path):
    ref, _ = synthetic
    text = ref.read_text()
    ours = file_interface.read_tum_trajectory_file(io.StringIO(text))
    theirs = evo_fi.read_tum_trajectory_file(io.StringIO(text))
    same_trajectory(ours, theirs, "handle")
    assert ours.name is None and theirs.name is None
    # A EuRoC ground-truth CSV with extra columns, comments and a BOM.
    rows = ["#timestamp, p_x, p_y, p_z, q_w, q_x, q_y, q_z, v_x"]
    for i, line in enumerate(text.splitlines()):
        t, x, y, z, qx, qy, qz, qw = line.split()
        rows.append(f"{1403636580000000000 + i * 5000000},{x},{y},{z},{qw},{qx},{qy},{qz},0.1")
    csv = tmp_path / "data.csv"
    csv.write_text("\ufeff" + "\n".join(rows) + "\n", encoding="utf-8")
    ours, theirs = read_both("read_euroc_csv_trajectory", csv)
    same_trajectory(ours, theirs, "euroc csv")


@pytest.mark.parametrize(
    "content",
    ["1 2 3 4 5 6 7 8 \n", "1 2 3 4 5 6 7\n", "1 2 3 4 5 6 7 8\n1 2 3 x 5 6 7 8\n",
     "1 2 3 4 5 6 7 8\n1 2 3 4 5 6 7 8 9\n", "# only a comment\n"],
)
def test_bad_files_raise_evo_s_exception_naming_the_line(tmp_path, content):
    path = tmp_path / "bad.txt"
    path.write_text(content)
    with pytest.raises(evo_fi.FileInterfaceException):
        evo_fi.read_tum_trajectory_file(str(path))
    with pytest.raises(file_interface.FileInterfaceException) as error:
        file_interface.read_tum_trajectory_file(str(path))
    assert str(path) in str(error.value)
    assert "TUM trajectory files must have 8 entries per row" in str(error.value)
    if content.count("\n") > 1 and not content.startswith("#"):
        assert f"{path}:2" in str(error.value)


# Fields as Python's float() reads them: plain decimals (the fast path), 20+ digits, signs,
# exponents, inf/nan, underscores, surrounding tabs; and fields it refuses.
FIELDS = ["1403638158.1950969696", "1.403638128940097094e+09", "-0.011300000", "+1.5", ".5",
          "-.5", "5.", "1e5", "1E-5", "1.e3", "0.1000000000000000055511151231257827",
          "9007199254740993", "1e400", "-1e-400", "2.2250738585072011e-308", "inf", "-Infinity",
          "nan", "1_000.5", "\t2.5", "00012"]
BAD_FIELDS = ["1e", "1.5e+", "1..2", ".", "-", "+-1", "0x10", "1d5", "_1", "1_", "infinit",
              "1,5", "e5"]


def test_fields_read_as_python_float(tmp_path):
    row = [1.0] * 8
    for field in FIELDS:
        for column in (0, 3, 7):
            text = " ".join(field if i == column else "1" for i in range(8))
            path = tmp_path / "f.txt"
            path.write_text(f"1 2 3 4 5 6 7 8\n{text}\n")
            mat = file_interface._matrix(str(path), " ", 8, False, "rule")
            expected = float(field)
            got = mat[1, column]
            assert (np.isnan(got) and np.isnan(expected)) or got == expected, (field, got)
            assert np.array_equal(mat[1, [i for i in range(8) if i != column]], row[:7])
    for field in BAD_FIELDS:
        with pytest.raises(ValueError):
            float(field)
        path = tmp_path / "bad.txt"
        path.write_text(f"1 2 3 4 5 6 7 8\n1 2 {field} 4 5 6 7 8\n")
        # Reported on reading, or (number characters only, as "1..2") when the poses are
        # first used: see test_poses_are_parsed_when_first_used.
        with pytest.raises(file_interface.FileInterfaceException, match=f"{path}:2:5: "):
            file_interface.read_tum_trajectory_file(str(path)).positions_xyz


def test_associate_copies_and_leaves_its_inputs_alone(pairs):
    # The last TUM pair: a real run when the data is there.
    name, reader, ref, est = [p for p in pairs if p[1] == "read_tum_trajectory_file"][-1]
    a = file_interface.read_tum_trajectory_file(str(ref))
    b = file_interface.read_tum_trajectory_file(str(est))
    a.meta["note"] = ["kept"]
    before = (a.positions_xyz.copy(), a.timestamps.copy(), b.positions_xyz.copy())
    r, e = sync.associate_trajectories(a, b)
    assert np.array_equal(a.positions_xyz, before[0]) and np.array_equal(a.timestamps, before[1])
    assert np.array_equal(b.positions_xyz, before[2])
    assert r.meta == a.meta and r.meta is not a.meta and r.meta["note"] is not a.meta["note"]
    r.positions_xyz[0, 0] += 1.0  # the copy's arrays are its own
    assert np.array_equal(a.positions_xyz, before[0])
    er, ee = evo_sync.associate_trajectories(evo_fi.read_tum_trajectory_file(str(ref)),
                                             evo_fi.read_tum_trajectory_file(str(est)))
    assert np.array_equal(r.timestamps, er.timestamps) and np.array_equal(e.timestamps, ee.timestamps)
    assert np.array_equal(e.positions_xyz, ee.positions_xyz)


def test_a_missing_file_is_evo_s_error(tmp_path):
    missing = str(tmp_path / "nope.txt")
    with pytest.raises(file_interface.FileInterfaceException) as ours:
        file_interface.read_tum_trajectory_file(missing)
    with pytest.raises(evo_fi.FileInterfaceException) as theirs:
        evo_fi.read_tum_trajectory_file(missing)
    assert str(ours.value) == str(theirs.value)


def test_writers_write_evo_s_bytes(pairs, tmp_path):
    name, reader, ref, _ = pairs[0]
    ours, theirs = read_both(reader, ref)
    for a, b in ((ours, theirs), (copy.deepcopy(ours), copy.deepcopy(theirs))):
        a.transform(np.diag([1.0, -1.0, -1.0, 1.0]))
        b.transform(np.diag([1.0, -1.0, -1.0, 1.0]))
    file_interface.write_tum_trajectory_file(str(tmp_path / "ours.txt"), ours)
    evo_fi.write_tum_trajectory_file(str(tmp_path / "theirs.txt"), theirs)
    back = file_interface.read_tum_trajectory_file(str(tmp_path / "ours.txt"))
    same_trajectory(back, evo_fi.read_tum_trajectory_file(str(tmp_path / "theirs.txt")), "tum")
    file_interface.write_kitti_poses_file(str(tmp_path / "ours.kitti"), ours)
    evo_fi.write_kitti_poses_file(str(tmp_path / "theirs.kitti"), theirs)
    close(np.loadtxt(tmp_path / "ours.kitti"), np.loadtxt(tmp_path / "theirs.kitti"), "kitti")
    with pytest.raises(file_interface.FileInterfaceException):
        file_interface.write_tum_trajectory_file(str(tmp_path / "x.txt"), trajectory.PosePath3D(
            poses_se3=[np.eye(4)]))


def associated(name, reader, ref, est, **kwargs):
    r, e = read_both(reader, ref)
    re, ee = read_both(reader, est)
    if reader == "read_kitti_poses_file":
        return (r, re), (e, ee)
    ours = sync.associate_trajectories(r, re, **kwargs)
    theirs = evo_sync.associate_trajectories(e, ee, **kwargs)
    return ours, theirs


def test_association_equals_evo_s(pairs):
    for name, reader, ref, est in pairs:
        if reader == "read_kitti_poses_file":
            continue
        for kwargs in ({}, {"max_diff": 0.05}, {"max_diff": 0.02, "offset_2": 0.013}):
            r, e = read_both(reader, ref)
            re, ee = read_both(reader, est)
            before = r.num_poses
            ours = sync.associate_trajectories(r, re, **kwargs)
            theirs = evo_sync.associate_trajectories(e, ee, **kwargs)
            assert r.num_poses == before, "associate_trajectories changes no input"
            for a, b, which in zip(ours, theirs, ("first", "second")):
                same_trajectory(a, b, f"{name} {kwargs} {which}")


def test_association_without_matches_is_evo_s_error(synthetic):
    r = file_interface.read_tum_trajectory_file(str(synthetic[0]))
    e = evo_fi.read_tum_trajectory_file(str(synthetic[0]))
    with pytest.raises(sync.SyncException) as ours:
        sync.associate_trajectories(r, r, offset_2=100.0)
    with pytest.raises(evo_sync.SyncException) as theirs:
        evo_sync.associate_trajectories(e, e, offset_2=100.0)
    assert str(ours.value) == str(theirs.value)
    with pytest.raises(sync.SyncException, match="run A and run B"):
        sync.associate_trajectories(r, r, 0.01, 100.0, "run A", "run B")


def test_alignment_is_in_place_and_returns_the_transform(pairs):
    for name, reader, ref, est in pairs:
        (r, e), (er, ee) = associated(name, reader, ref, est)
        for kwargs in ({}, {"correct_scale": True}, {"correct_only_scale": True}, {"n": 50}):
            ours, theirs = copy.deepcopy(e), copy.deepcopy(ee)
            result = ours.align(r, **kwargs)
            expected = theirs.align(er, **kwargs)
            for a, b, part in zip(result, expected, "rts"):
                close(a, b, f"{name} align {kwargs} {part}")
            same_trajectory(ours, theirs, f"{name} aligned {kwargs}")
            assert ours != e or kwargs.get("correct_only_scale"), "align changes the object"
        same_trajectory(e, ee, f"{name} the original of the deep copies")
        ours, theirs = copy.deepcopy(e), copy.deepcopy(ee)
        close(ours.align_origin(r), theirs.align_origin(er), f"{name} align_origin")
        same_trajectory(ours, theirs, f"{name} after align_origin")
        aligned, rot, t, s = trajectory.align_trajectory(e, r, True, return_parameters=True)
        theirs = copy.deepcopy(ee)
        expected = theirs.align(er, correct_scale=True)
        same_trajectory(aligned, theirs, f"{name} align_trajectory")
        close(s, expected[2], f"{name} align_trajectory scale")


def test_transforms_and_reductions_equal_evo_s(pairs):
    rng = np.random.default_rng(4)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    from evo.core import transformations as tr

    t = tr.quaternion_matrix(q)
    t[:3, 3] = rng.normal(size=3)
    for name, reader, ref, _ in pairs:
        ours, theirs = read_both(reader, ref)
        for step in (
            lambda x: x.transform(t),
            lambda x: x.transform(t, right_mul=True),
            lambda x: x.transform(t, right_mul=True, propagate=True),
            lambda x: x.scale(1.7),
            lambda x: x.reduce_to_ids(np.arange(0, x.num_poses, 3)),
            lambda x: x.downsample(40),
        ):
            step(ours)
            step(theirs)
            same_trajectory(ours, theirs, f"{name} step")
        assert ours == ours and not (ours != copy.deepcopy(ours))
        close(ours.get_orientations_euler(), theirs.get_orientations_euler(), f"{name} euler")
        if hasattr(theirs, "timestamps"):
            middle = theirs.timestamps[len(theirs.timestamps) // 2]
            ours.reduce_to_time_range(None, middle)
            theirs.reduce_to_time_range(None, middle)
            same_trajectory(ours, theirs, f"{name} reduce_to_time_range")
        for plane in trajectory.Plane:
            a, b = copy.deepcopy(ours), copy.deepcopy(theirs)
            a.project(plane)
            b.project(evo_trajectory.Plane(plane.value))
            same_trajectory(a, b, f"{name} project {plane}")
            with pytest.raises(trajectory.TrajectoryException):
                a.project(plane)


def test_equality_as_evo_s():
    poses = [np.eye(4), np.eye(4)]
    poses[1][:3, 3] = [1.0, 0.0, 0.0]
    a = trajectory.PoseTrajectory3D(poses_se3=poses, timestamps=[0.0, 1.0])
    b = trajectory.PoseTrajectory3D(
        positions_xyz=[[0, 0, 0], [1, 0, 0]],
        orientations_quat_wxyz=[[-1, 0, 0, 0], [-1, 0, 0, 0]],
        timestamps=[0.0, 1.0],
    )
    assert a == b, "q and -q are one rotation (the whole array's sign, as evo)"
    mixed = copy.deepcopy(b)
    mixed.orientations_quat_wxyz[1] *= -1
    evo_mixed = evo_trajectory.PoseTrajectory3D(
        positions_xyz=mixed.positions_xyz, orientations_quat_wxyz=mixed.orientations_quat_wxyz,
        timestamps=mixed.timestamps)
    evo_a = evo_trajectory.PoseTrajectory3D(poses_se3=poses, timestamps=[0.0, 1.0])
    assert (a == mixed) == (evo_a == evo_mixed)
    assert a != trajectory.PoseTrajectory3D(poses_se3=poses, timestamps=[0.0, 2.0])
    assert a != trajectory.PosePath3D(poses_se3=poses)
    with pytest.raises(trajectory.TrajectoryException, match="no timestamps"):
        trajectory.PoseTrajectory3D(poses_se3=poses)
    with pytest.raises(trajectory.TrajectoryException, match="empty"):
        trajectory.PosePath3D(poses_se3=[])


RELATIONS = [r for r in metrics.PoseRelation if r is not metrics.PoseRelation.point_distance_error_ratio]


def statistics_close(ours, theirs, what):
    a, b = ours.get_all_statistics(), theirs.get_all_statistics()
    assert a.keys() == b.keys()
    for k in b:
        close(a[k], b[k], f"{what} {k}")
        close(ours.get_statistic(metrics.StatisticsType(k)),
              theirs.get_statistic(evo_metrics.StatisticsType(k)), f"{what} get_statistic {k}")


def test_ape_equals_evo_s(pairs):
    for name, reader, ref, est in pairs:
        (r, e), (er, ee) = associated(name, reader, ref, est)
        e, ee = copy.deepcopy(e), copy.deepcopy(ee)
        e.align(r, correct_scale=True)
        ee.align(er, correct_scale=True)
        for relation in RELATIONS:
            ours = metrics.APE(relation)
            ours.process_data((r, e))
            theirs = evo_metrics.APE(evo_metrics.PoseRelation[relation.name])
            theirs.process_data((er, ee))
            close(ours.error, theirs.error, f"{name} APE {relation}")
            statistics_close(ours, theirs, f"{name} APE {relation}")
            assert str(ours) == str(theirs) and ours.unit.value == theirs.unit.value
            result, expected = ours.get_result("gt", "run"), theirs.get_result("gt", "run")
            assert result.info == expected.info
            close(result.np_arrays["error_array"], expected.np_arrays["error_array"], "result")
            assert result.pretty_str() == expected.pretty_str()
        close(np.array(ours.E), np.array(theirs.E), f"{name} APE E")


RPE_CASES = [
    (1, "frames", False, False),
    (10, "frames", True, False),
    (5, "frames", False, True),
    (1, "meters", False, False),
    (1, "meters", True, False),
    (2, "meters", True, True),
    (10, "degrees", False, False),
    (10, "degrees", True, False),
    (0.2, "radians", True, False),
]


def test_rpe_equals_evo_s(pairs):
    for name, reader, ref, est in pairs:
        (r, e), (er, ee) = associated(name, reader, ref, est)
        for delta, unit, all_pairs, from_reference in RPE_CASES:
            if all_pairs and unit != "frames" and (name == "MH_04" or unit != "meters"):
                if name != "synthetic":
                    continue  # evo's all-pairs search by angle takes minutes on real runs
            relations = list(metrics.PoseRelation)
            if unit != "frames":  # the pairs are the costly part in evo: fewer relations
                relations = [metrics.PoseRelation.translation_part,
                             metrics.PoseRelation.rotation_angle_deg,
                             metrics.PoseRelation.point_distance_error_ratio]
            for relation in relations:
                args = dict(delta=delta, rel_delta_tol=0.1, all_pairs=all_pairs,
                            pairs_from_reference=from_reference)
                what = f"{name} RPE {relation.name} {args} {unit}"
                theirs = evo_metrics.RPE(evo_metrics.PoseRelation[relation.name],
                                         delta_unit=evo_metrics.Unit[unit], **args)
                ours = metrics.RPE(relation, delta_unit=metrics.Unit[unit], **args)
                try:
                    theirs.process_data((er, ee))
                except Exception as error:  # evo found no pairs: so must we, with its type
                    with pytest.raises(Exception) as raised:
                        ours.process_data((r, e))
                    assert type(raised.value).__name__ == type(error).__name__, what
                    continue
                ours.process_data((r, e))
                close(ours.error, theirs.error, what)
                assert ours.delta_ids == list(theirs.delta_ids), what
                statistics_close(ours, theirs, what)
                assert str(ours) == str(theirs)


def test_rpe_error_poses_and_unit_changes(pairs):
    name, reader, ref, est = pairs[0]
    (r, e), (er, ee) = associated(name, reader, ref, est)
    ours = metrics.RPE(metrics.PoseRelation.full_transformation, 3, metrics.Unit.frames)
    theirs = evo_metrics.RPE(evo_metrics.PoseRelation.full_transformation, 3, evo_metrics.Unit.frames)
    ours.process_data((r, e))
    theirs.process_data((er, ee))
    close(np.array(ours.E), np.array(theirs.E), "RPE E")
    ours = metrics.APE(metrics.PoseRelation.rotation_angle_rad)
    ours.process_data((r, e))
    theirs = evo_metrics.APE(evo_metrics.PoseRelation.rotation_angle_rad)
    theirs.process_data((er, ee))
    ours.change_unit(metrics.Unit.degrees)
    theirs.change_unit(evo_metrics.Unit.degrees)
    close(ours.error, theirs.error, "change_unit")
    with pytest.raises(metrics.MetricsException, match="cannot convert"):
        ours.change_unit(metrics.Unit.meters)


def test_metric_errors_are_evo_s(synthetic):
    r = file_interface.read_tum_trajectory_file(str(synthetic[0]))
    short = copy.deepcopy(r)
    short.reduce_to_ids([0, 1, 2])
    with pytest.raises(metrics.MetricsException, match="same number of poses"):
        metrics.APE().process_data((r, short))
    with pytest.raises(metrics.MetricsException, match="data tuple"):
        metrics.RPE().process_data((r,))
    with pytest.raises(metrics.MetricsException, match="integer"):
        metrics.RPE(delta=1.5)
    with pytest.raises(metrics.MetricsException, match="positive"):
        metrics.RPE(delta=-1)
    with pytest.raises(metrics.FilterException, match="empty index list"):
        metrics.RPE(delta=1000, delta_unit=metrics.Unit.meters).process_data((r, r))


@pytest.mark.parametrize(
    "module, name, nearest",
    [
        ("sitar.evo.tools.file_interface", "save_res_file", "sitar ape"),
        ("sitar.evo.tools.file_interface", "load_res_file", "sitar res"),
        ("sitar.evo.core.result", "merge_results", "sitar"),
        ("sitar.evo.core.trajectory", "xyz_quat_wxyz_to_se3_poses", "poses_se3"),
    ],
)
def test_what_is_not_mirrored_says_so(module, name, nearest):
    import importlib

    mod = importlib.import_module(module)
    with pytest.raises(NotImplementedError) as error:
        getattr(mod, name)
    assert f"evo.{module.split('evo.', 1)[1]}.{name}" in str(error.value)
    assert nearest in str(error.value)
    with pytest.raises(AttributeError):
        getattr(mod, "no_such_function_anywhere")
    with pytest.raises(file_interface.FileInterfaceException, match="rosbags"):
        file_interface.read_bag_trajectory(None, "/pose")


BAGS = Path(__file__).resolve().parents[2] / "rust" / "cli" / "tests" / "golden" / "evo_bag_formats"


@pytest.mark.parametrize("bag", ["fr1_ros1.bag", "fr1_lz4.bag", "fr1_mcap_lz4", "fr1_mcap_zstd"])
def test_bags_read_as_evo_reads_them(bag):
    rosbags = pytest.importorskip("rosbags.rosbag1", reason="SKIPPED: no rosbags (evo's)")
    from rosbags.rosbag2 import Reader as Rosbag2Reader

    reader_type = rosbags.Reader if bag.endswith(".bag") else Rosbag2Reader
    with reader_type(BAGS / bag) as reader:
        topics = list(reader.topics)
        assert topics, f"{bag} has topics"
        compared = 0
        for topic in topics:
            try:
                theirs = evo_fi.read_bag_trajectory(reader, topic)
            except evo_fi.FileInterfaceException as error:
                with pytest.raises(file_interface.FileInterfaceException):
                    file_interface.read_bag_trajectory(reader, topic)
                assert "unsupported message type" in str(error)
                continue
            for source in (reader, BAGS / bag):
                ours = file_interface.read_bag_trajectory(source, topic)
                same_trajectory(ours, theirs, f"{bag} {topic}")
                assert ours.meta == theirs.meta and ours.name == theirs.name == topic
            compared += 1
        assert compared >= 2
    with pytest.raises(file_interface.FileInterfaceException, match="no messages for topic"):
        file_interface.read_bag_trajectory(BAGS / bag, "/no_such_topic")


def test_db3_bags_and_tf_ids_name_the_sitar_command():
    with pytest.raises(NotImplementedError, match="sitar traj bag2"):
        file_interface.read_bag_trajectory(BAGS / "fr1_db3_message" / "fr1_db3_message.db3", "/odom")
    with pytest.raises(NotImplementedError, match="sitar traj bag"):
        file_interface.read_bag_trajectory(BAGS / "fr1_ros1.bag", "/tf:map.base_link")


def results_equal(ours, theirs, what):
    assert ours.info == theirs.info, what
    assert ours.stats.keys() == theirs.stats.keys()
    for k in theirs.stats:
        close(ours.stats[k], theirs.stats[k], f"{what} stats {k}")
    assert ours.np_arrays.keys() == theirs.np_arrays.keys(), what
    for k in theirs.np_arrays:
        close(ours.np_arrays[k], theirs.np_arrays[k], f"{what} {k}")
    assert ours.trajectories.keys() == theirs.trajectories.keys()
    for k in theirs.trajectories:
        same_trajectory(ours.trajectories[k], theirs.trajectories[k], f"{what} trajectory {k}")


def test_main_ape_and_main_rpe_results_equal_evo_s(pairs):
    from evo import main_ape as evo_main_ape, main_rpe as evo_main_rpe
    from sitar.evo import main_ape, main_rpe

    for name, reader, ref, est in pairs:
        for kwargs in ({"align": True}, {"align": True, "correct_scale": True},
                       {"correct_scale": True}, {"align_origin": True}, {"n_to_align": 30, "align": True},
                       {"project_to_plane": "xy"}):
            (r, e), (er, ee) = associated(name, reader, ref, est)
            ours_kw, theirs_kw = dict(kwargs), dict(kwargs)
            if "project_to_plane" in kwargs:
                ours_kw["project_to_plane"] = trajectory.Plane.XY
                theirs_kw["project_to_plane"] = evo_trajectory.Plane.XY
            ours = main_ape.ape(r, e, metrics.PoseRelation.translation_part, **ours_kw)
            theirs = evo_main_ape.ape(er, ee, evo_metrics.PoseRelation.translation_part, **theirs_kw)
            results_equal(ours, theirs, f"{name} main_ape {kwargs}")
            (r, e), (er, ee) = associated(name, reader, ref, est)
            ours = main_rpe.rpe(r, e, metrics.PoseRelation.rotation_angle_deg, delta=2,
                                delta_unit=metrics.Unit.frames, support_loop=True, **ours_kw)
            theirs = evo_main_rpe.rpe(er, ee, evo_metrics.PoseRelation.rotation_angle_deg, delta=2,
                                      delta_unit=evo_metrics.Unit.frames, support_loop=True,
                                      **theirs_kw)
            results_equal(ours, theirs, f"{name} main_rpe {kwargs}")
    with pytest.raises(ValueError, match="simultaneously"):
        main_ape.ape(r, e, metrics.PoseRelation.translation_part, align=True, align_origin=True)


def test_settings_and_logging_as_evo_s(synthetic):
    from sitar.evo.tools import log, settings

    assert settings.SETTINGS.plot_show_legend is True
    with pytest.raises(settings.SettingsException):
        settings.SETTINGS.no_such_setting
    log.configure_logging(verbose=True)
    import logging

    assert logging.getLogger("sitar.evo").level == logging.INFO
    log.configure_logging(silent=True)
