"""TUM and EuRoC poses parsed when first used (sitar/evo/tools/_rows.py): the values, copies,
pickles and reductions equal evo's eagerly read trajectories; what is checked on reading and
what only when the poses are used."""

import copy
import pickle

import numpy as np
import pytest

pytest.importorskip("evo", reason="SKIPPED: evo is not installed (pip install evo)")
from evo.core import sync as evo_sync  # noqa: E402
from evo.tools import file_interface as evo_fi  # noqa: E402

from sitar.evo.core import sync  # noqa: E402
from sitar.evo.tools import file_interface  # noqa: E402


def unparsed(traj) -> bool:
    """Whether the trajectory still holds its file's rows (nothing parsed but the stamps)."""
    return "_rows" in vars(traj)


def same(ours, theirs, atol=0.0):
    """Equal to evo's trajectory: exactly as read, to ``atol`` after arithmetic (the 4×4
    poses, built with numpy over all rows where evo builds them one by one: to 1e-12)."""
    assert ours.num_poses == theirs.num_poses
    assert np.array_equal(ours.timestamps, theirs.timestamps)
    for a, b, tol in ((ours.positions_xyz, theirs.positions_xyz, atol),
                      (ours.orientations_quat_wxyz, theirs.orientations_quat_wxyz, atol),
                      (np.array(ours.poses_se3), np.array(theirs.poses_se3), max(atol, 1e-12))):
        assert a.shape == b.shape and np.allclose(a, b, rtol=0.0, atol=tol), (a, b)


@pytest.fixture()
def tum(tmp_path):
    """A TUM file of 30 rows (stamps 0.0 .. 2.9) written with varied number spellings."""
    path = tmp_path / "poses.txt"
    lines = ["# t x y z qx qy qz qw"]
    for i in range(30):
        lines.append(f"{i / 10} {i}.5 -{i}e-2 +{i * 3} 0 0 {np.sin(i / 9):.12f} {np.cos(i / 9):.12f}")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_reading_parses_only_the_stamps_and_values_equal_evo_s(tum, synthetic):
    ours = file_interface.read_tum_trajectory_file(str(tum))
    theirs = evo_fi.read_tum_trajectory_file(str(tum))
    assert ours.num_poses == 30 and np.array_equal(ours.timestamps, theirs.timestamps)
    assert unparsed(ours), "num_poses and timestamps parse no pose"
    same(ours, theirs)
    assert not unparsed(ours)
    ours.positions_xyz[0, 0] = 99.0  # writable, and kept
    assert ours.positions_xyz[0, 0] == 99.0


@pytest.mark.parametrize(
    "ids",
    [np.arange(0, 30, 4), [3, 1, 1, 29], np.arange(30) % 3 == 0, slice(5, 25, 2), []],
    ids=["array", "list with repeats", "mask", "slice", "none"],
)
def test_reductions_before_and_after_parsing_equal_evo_s(tum, ids):
    ours = file_interface.read_tum_trajectory_file(str(tum))
    theirs = evo_fi.read_tum_trajectory_file(str(tum))
    ours.reduce_to_ids(ids)
    theirs.reduce_to_ids(ids)
    assert unparsed(ours)
    ours.reduce_to_ids(slice(None, None, -1))
    theirs.reduce_to_ids(slice(None, None, -1))
    same(ours, theirs)
    with pytest.raises(IndexError):
        file_interface.read_tum_trajectory_file(str(tum)).reduce_to_ids([30])


def test_copies_and_pickles_of_unparsed_trajectories(tum):
    ours = file_interface.read_tum_trajectory_file(str(tum))
    theirs = evo_fi.read_tum_trajectory_file(str(tum))
    ours.meta["note"] = ["kept"]
    deep = copy.deepcopy(ours)
    shallow = copy.copy(ours)
    assert unparsed(deep) and deep.meta == ours.meta and deep.meta is not ours.meta
    deep.reduce_to_ids([0, 1])
    assert ours.num_poses == 30 and shallow.num_poses == 30
    back = pickle.loads(pickle.dumps(ours))
    assert not unparsed(back) and back.meta == {"note": ["kept"]}
    same(back, theirs)
    same(shallow, theirs)
    theirs.reduce_to_ids([0, 1])
    same(deep, theirs)


def test_changes_of_an_unparsed_trajectory_equal_evo_s(tum):
    t = np.eye(4)
    t[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    t[:3, 3] = [1, 2, 3]
    for change in (
        lambda x: x.transform(t),
        lambda x: x.transform(t, right_mul=True),
        lambda x: x.scale(2.5),
        lambda x: x.downsample(7),
        lambda x: x.reduce_to_time_range(0.5, 1.5),
    ):
        ours = file_interface.read_tum_trajectory_file(str(tum))
        theirs = evo_fi.read_tum_trajectory_file(str(tum))
        change(ours)
        change(theirs)
        same(ours, theirs, atol=1e-12)


def test_euroc_csv_rows_equal_evo_s(tmp_path):
    path = tmp_path / "data.csv"
    rows = ["#timestamp,p_x,p_y,p_z,q_w,q_x,q_y,q_z,v_x"]
    for i in range(12):
        rows.append(f"{1403636580000000000 + i * 5000000},{i}.25,-{i},1e-3,1,0,0,0,0.5")
    path.write_text("\n".join(rows) + "\n")
    ours = file_interface.read_euroc_csv_trajectory(str(path))
    theirs = evo_fi.read_euroc_csv_trajectory(str(path))
    assert unparsed(ours)
    same(ours, theirs)


def test_a_bad_number_is_reported_when_its_poses_are_used(tum, tmp_path):
    # Number characters that make no number: evo refuses the file on reading; here the
    # same message comes when the row's poses are first parsed, or never if it is dropped.
    bad = tmp_path / "bad.txt"
    lines = tum.read_text().splitlines()
    lines[4] = lines[4].replace(".5 ", "..5 ", 1)  # the row of stamp 0.3, on line 5
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(evo_fi.FileInterfaceException):
        evo_fi.read_tum_trajectory_file(str(bad))
    traj = file_interface.read_tum_trajectory_file(str(bad))
    assert traj.num_poses == 30
    with pytest.raises(file_interface.FileInterfaceException, match=f"{bad}:5:5: '3..5'"):
        copy.deepcopy(traj).positions_xyz
    with pytest.raises(file_interface.FileInterfaceException, match=f"{bad}:5:5: '3..5'"):
        pickle.dumps(traj)
    # Associated with an estimate that has no pose near 0.3 s: the bad row is dropped.
    kept = [i for i in range(30) if i != 3]
    estimate = file_interface.read_tum_trajectory_file(str(tum))
    estimate.reduce_to_ids(kept)
    ref, _ = sync.associate_trajectories(traj, estimate)
    good, evo_estimate = (evo_fi.read_tum_trajectory_file(str(tum)) for _ in range(2))
    evo_estimate.reduce_to_ids(kept)
    evo_ref, _ = evo_sync.associate_trajectories(good, evo_estimate)
    same(ref, evo_ref)


@pytest.mark.parametrize(
    "row, message",
    [("0.1 1 2 3 0 0 0 x", ":3:17: 'x'"), ("0.1 1 2 3 0 0 0", ":3: 7 entries"),
     ("0.1 1 2 3 0 0 0 1 ", ":3:19: ''"), ("0.1e 1 2 3 0 0 0 1", ":3:1: '0.1e'")],
    ids=["text", "short row", "trailing delimiter", "bad stamp"],
)
def test_what_evo_refuses_on_reading_is_refused_on_reading(tmp_path, row, message):
    path = tmp_path / "bad.txt"
    path.write_text(f"# header\n0 1 2 3 0 0 0 1\n{row}\n")
    with pytest.raises(evo_fi.FileInterfaceException):
        evo_fi.read_tum_trajectory_file(str(path))
    with pytest.raises(file_interface.FileInterfaceException, match=f"{path}{message}"):
        file_interface.read_tum_trajectory_file(str(path))


def test_fields_read_as_python_float_when_parsed_late(tmp_path):
    from test_evo_api import BAD_FIELDS, FIELDS

    path = tmp_path / "f.txt"
    for field in FIELDS:
        expected = float(field)
        for column in (0, 2, 7):
            row = " ".join(field if i == column else "1" for i in range(8))
            path.write_text(f"0.5 2 3 4 5 6 7 8\n{row}\n")
            traj = file_interface.read_tum_trajectory_file(str(path))
            got = {0: traj.timestamps, 2: traj.positions_xyz[:, 1],
                   7: traj.orientations_quat_wxyz[:, 0]}[column][1]
            assert (np.isnan(got) and np.isnan(expected)) or got == expected, (field, got)
    for field in BAD_FIELDS:
        path.write_text(f"0.5 2 3 4 5 6 7 8\n1 2 {field} 4 5 6 7 8\n")
        with pytest.raises(file_interface.FileInterfaceException, match=f"{path}:2:5: "):
            file_interface.read_tum_trajectory_file(str(path)).orientations_quat_wxyz


@pytest.mark.parametrize(
    "reader, good",
    [("read_tum_trajectory_file", "0 1 2 3 0 0 0 1"),
     ("read_euroc_csv_trajectory", "0,1,2,3,1,0,0,0"),
     ("read_kitti_poses_file", "1 0 0 0 0 1 0 0 0 0 1 0")],
)
def test_a_file_that_is_not_utf8_names_the_line(tmp_path, reader, good):
    path = tmp_path / "latin1.txt"
    path.write_bytes(f"# header\n{good}\n# caf\xe9\n{good}\n".encode("latin-1"))
    with pytest.raises(file_interface.FileInterfaceException, match=f"{path}:3: not UTF-8"):
        getattr(file_interface, reader)(str(path))


def test_threads_parsing_one_trajectory_at_once_agree(tmp_path):
    # Large enough that the parse (outside the GIL) of one thread overlaps the others'.
    from concurrent.futures import ThreadPoolExecutor

    path = tmp_path / "large.txt"
    path.write_text("".join(f"{i / 100} {i}.25 -{i}e-3 3 0 0 0.6 0.8\n" for i in range(40000)))
    expected = evo_fi.read_tum_trajectory_file(str(path))
    for _ in range(10):
        traj = file_interface.read_tum_trajectory_file(str(path))
        with ThreadPoolExecutor(4) as pool:
            results = list(pool.map(lambda _: traj.orientations_quat_wxyz, range(4)))
        for quat in results:
            assert np.array_equal(quat, expected.orientations_quat_wxyz)
        same(traj, expected)
