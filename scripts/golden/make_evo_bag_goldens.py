#!/usr/bin/env python3
"""ROS 2 test bags from the real fr1/xyz trajectories, and evo 1.38.1's outputs on them
(issue 26, `sitar ape|rpe bag2`).

1. Writes two ROS 2 bags with the `rosbags` package (what evo reads bags with) into
   rust/cli/tests/golden/evo_bags/: `fr1_mcap` (MCAP storage) and `fr1_db3` (sqlite3), each
   holding the first 6 s of the TUM fr1/xyz ground truth (rust/cli/tests/golden/evo_real/data,
   CC BY 4.0) as geometry_msgs/msg/PoseStamped on /ground_truth, and the RGBD-SLAM estimate
   of the same seconds as nav_msgs/msg/Odometry (/odom), PoseWithCovarianceStamped
   (/pose_cov), TransformStamped (/tf_pose) and PointStamped (/point); one more topic
   (/cmd_vel, geometry_msgs/msg/Twist) that evo does not read.
2. Runs evo_ape / evo_rpe / evo_traj bag2 on them (CASES) and records stdout (and the
   archive's stats and error array) in rust/cli/tests/golden/evo_bags/expected.json.

The Rust test (rust/cli/tests/evo.rs, `ros2_bags_as_evo_reads_them`) runs sitar alike.

Usage (from the repository root; needs `pip install evo==1.38.1 rosbags`):
    python3 scripts/golden/make_evo_bag_goldens.py
"""
import json
import pathlib
import shutil
import sys
import tempfile

from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from make_evo_cli_goldens import load_archive, run  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
SOURCE = ROOT / "rust/cli/tests/golden/evo_real/data"
OUT = ROOT / "rust/cli/tests/golden/evo_bags"
SECONDS = 6.0

CASES = [
    ("ape_bag2_mcap_odometry", "ape", ["bag2", "fr1_mcap", "/ground_truth", "/odom", "-a"]),
    ("ape_bag2_db3_odometry", "ape", ["bag2", "fr1_db3", "/ground_truth", "/odom", "-a", "-s"]),
    ("rpe_bag2_mcap_pose_cov", "rpe", ["bag2", "fr1_mcap", "/ground_truth", "/pose_cov", "-d", "5", "-r", "angle_deg"]),
    ("ape_bag2_db3_transform", "ape", ["bag2", "fr1_db3", "/ground_truth", "/tf_pose", "-a", "-r", "full"]),
    ("ape_bag2_mcap_point", "ape", ["bag2", "fr1_mcap", "/ground_truth", "/point", "-a", "-r", "point_distance"]),
    ("traj_bag2_all_topics", "traj", ["bag2", "fr1_db3", "--all_topics", "--ref", "/ground_truth", "-a", "--full_check"]),
    ("traj_bag2_topics", "traj", ["bag2", "fr1_mcap", "/odom", "/tf_pose", "-v"]),
]


def read_tum(name):
    rows = []
    for line in (SOURCE / name).read_text().splitlines():
        if line.startswith("#") or not line.strip():
            continue
        rows.append(line.split())
    return rows


def write_bag(path, storage, gt, est):
    store = get_typestore(Stores.LATEST)
    T = store.types
    Time, Header = T["builtin_interfaces/msg/Time"], T["std_msgs/msg/Header"]
    Point, Quaternion, Pose = T["geometry_msgs/msg/Point"], T["geometry_msgs/msg/Quaternion"], T["geometry_msgs/msg/Pose"]
    Vector3, Transform = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Transform"]
    PoseStamped, PoseWithCovariance = T["geometry_msgs/msg/PoseStamped"], T["geometry_msgs/msg/PoseWithCovariance"]
    PoseWithCovarianceStamped = T["geometry_msgs/msg/PoseWithCovarianceStamped"]
    TransformStamped, PointStamped = T["geometry_msgs/msg/TransformStamped"], T["geometry_msgs/msg/PointStamped"]
    Odometry, Twist, TwistWithCovariance = T["nav_msgs/msg/Odometry"], T["geometry_msgs/msg/Twist"], T["geometry_msgs/msg/TwistWithCovariance"]
    import numpy as np

    def header(stamp, frame="map"):
        # The decimal stamp as sec + nanosec, exactly (the file's digits, not a float).
        whole, _, frac = stamp.partition(".")
        return Header(stamp=Time(sec=int(whole), nanosec=int((frac + "000000000")[:9])), frame_id=frame)

    def pose(r):
        x, y, z, qx, qy, qz, qw = map(float, r[1:8])
        return Pose(position=Point(x=x, y=y, z=z), orientation=Quaternion(x=qx, y=qy, z=qz, w=qw))

    cov = np.zeros(36, dtype=np.float64)
    zero = Vector3(x=0.0, y=0.0, z=0.0)
    with Writer(path, version=8, storage_plugin=storage) as writer:
        conns = {
            name: writer.add_connection(name, msgtype, typestore=store)
            for name, msgtype in [
                ("/ground_truth", PoseStamped.__msgtype__),
                ("/odom", Odometry.__msgtype__),
                ("/pose_cov", PoseWithCovarianceStamped.__msgtype__),
                ("/tf_pose", TransformStamped.__msgtype__),
                ("/point", PointStamped.__msgtype__),
                ("/cmd_vel", Twist.__msgtype__),
            ]
        }
        def put(topic, stamp, msg):
            whole, _, frac = stamp.partition(".")
            ns = int(whole) * 1_000_000_000 + int((frac + "000000000")[:9])
            writer.write(conns[topic], ns, store.serialize_cdr(msg, type(msg).__msgtype__))
        for r in gt:
            put("/ground_truth", r[0], PoseStamped(header=header(r[0]), pose=pose(r)))
        for r in est:
            h, p = header(r[0]), pose(r)
            put("/odom", r[0], Odometry(header=h, child_frame_id="base", pose=PoseWithCovariance(pose=p, covariance=cov),
                                        twist=TwistWithCovariance(twist=Twist(linear=zero, angular=zero), covariance=cov)))
            put("/pose_cov", r[0], PoseWithCovarianceStamped(header=h, pose=PoseWithCovariance(pose=p, covariance=cov)))
            put("/tf_pose", r[0], TransformStamped(header=h, child_frame_id="base", transform=Transform(
                translation=Vector3(x=p.position.x, y=p.position.y, z=p.position.z), rotation=p.orientation)))
            put("/point", r[0], PointStamped(header=h, point=p.position))
            put("/cmd_vel", r[0], Twist(linear=zero, angular=zero))


def main():
    gt = read_tum("freiburg1_xyz-groundtruth.txt")
    est = read_tum("freiburg1_xyz-rgbdslam.txt")
    start = float(gt[0][0])
    gt = [r for r in gt if float(r[0]) < start + SECONDS]
    est = [r for r in est if float(r[0]) < start + SECONDS]
    for name, storage in [("fr1_mcap", StoragePlugin.MCAP), ("fr1_db3", StoragePlugin.SQLITE3)]:
        if (OUT / name).exists():
            shutil.rmtree(OUT / name)
        write_bag(OUT / name, storage, gt, est)
    expected = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, tool, args in CASES:
            work = pathlib.Path(tmp) / name
            shutil.copytree(OUT, work, ignore=shutil.ignore_patterns("expected.json"))
            if tool == "traj":
                stdout = run(tool, args, work)
                expected.append({"name": name, "tool": tool, "args": args, "stdout": stdout})
                print(f"{name}: {len(stdout.splitlines())} lines")
                continue
            stdout = run(tool, args + ["--save_results", "result.zip"], work)
            archive = load_archive(work / "result.zip")
            expected.append({"name": name, "tool": tool, "args": args, "stdout": stdout,
                             "stats": archive["stats"], "errors": archive["arrays"]["error_array"]})
            print(f"{name}: {archive['stats']['rmse']}")
    (OUT / "expected.json").write_text(json.dumps(expected) + "\n")


if __name__ == "__main__":
    main()
