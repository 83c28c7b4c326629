#!/usr/bin/env python3
"""ROS 1 bags, compressed ROS 2 bags and tf bags from the real fr1/xyz trajectories, and
evo 1.38.1's output on them (issue 26: `sitar ape|rpe|traj bag|bag2`).

Writes into rust/cli/tests/golden/evo_bag_formats/ (the first 3 s of the TUM fr1/xyz RGBD-SLAM
estimate and the ground truth of those seconds, rust/cli/tests/golden/evo_real/data, CC BY 4.0):

- ROS 1 bags with `rosbags`: `fr1_ros1.bag` (bz2 chunks: every pose type evo reads, a
  Twist topic, /tf and /tf_static), `fr1_plain.bag` (uncompressed, the first 1.5 s of
  /ground_truth and /odom) and `fr1_lz4.bag` (lz4 chunks);
- ROS 2 bags: `fr1_mcap_zstd` (rosbags, zstd chunks), `fr1_mcap_lz4` (the same messages
  rewritten with lz4 chunks by Foxglove's `mcap` package), `fr1_db3_file` and
  `fr1_db3_message` (sqlite3 with rosbag2's zstd file / message compression, rosbags);
- `fr1_tf` (ROS 2, MCAP): /ground_truth, /tf with odom->base at the estimate's stamps,
  /tf_static with map->odom, and /tf_reference: the poses of `/tf:map.base` as evo's
  TfCache looks them up (tf2's rule: every 0.1 s from the first /tf stamp to the last, each
  edge interpolated linearly and by tf2's slerp, the static edge chained in), computed here
  with numpy. evo itself needs ROS's tf2_py for tf topics, which pip cannot install, so
  this reference stands in for it; evo's numbers on /tf_reference are then the expected
  numbers of sitar on /tf:map.base.

Then runs evo_ape / evo_rpe / evo_traj on them (CASES) and records stdout and the archive's
stats, errors and timestamps in expected.json. The Rust test
(rust/cli/tests/evo.rs, `ros1_compressed_and_tf_bags_as_evo_reads_them`) runs sitar alike.

Usage (from the repository root; needs `pip install evo==1.38.1 rosbags mcap`):
    python3 scripts/golden/make_evo_bag_formats_goldens.py
"""
import json
import pathlib
import shutil
import sys
import tempfile

import numpy as np
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer as Writer2
from rosbags.typesys import Stores, get_typestore, get_types_from_msg

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from make_evo_cli_goldens import load_archive, run  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
SOURCE = ROOT / "rust/cli/tests/golden/evo_real/data"
OUT = ROOT / "rust/cli/tests/golden/evo_bag_formats"
SECONDS = 3.0
# map -> odom, a fixed offset and a turn about z.
STATIC_T = np.array([0.5, -0.25, 0.1])
STATIC_Q = np.array([0.0, 0.0, np.sin(0.15), np.cos(0.15)])  # x y z w

CASES = [
    ("ape_bag_ros1_odometry", "ape", ["bag", "fr1_ros1.bag", "/ground_truth", "/odom", "-a"]),
    ("rpe_bag_ros1_pose_cov", "rpe", ["bag", "fr1_ros1.bag", "/ground_truth", "/pose_cov", "-d", "5", "-r", "angle_deg"]),
    ("ape_bag_ros1_point", "ape", ["bag", "fr1_ros1.bag", "/ground_truth", "/point", "-a", "-r", "point_distance"]),
    ("ape_bag_plain_odometry", "ape", ["bag", "fr1_plain.bag", "/ground_truth", "/odom", "-a", "-s"]),
    ("ape_bag_lz4_transform", "ape", ["bag", "fr1_lz4.bag", "/ground_truth", "/tf_pose", "-a", "-r", "full"]),
    ("ape_bag2_mcap_zstd", "ape", ["bag2", "fr1_mcap_zstd", "/ground_truth", "/odom", "-a"]),
    ("ape_bag2_mcap_lz4", "ape", ["bag2", "fr1_mcap_lz4", "/ground_truth", "/odom", "-a"]),
    ("rpe_bag2_db3_file", "rpe", ["bag2", "fr1_db3_file", "/ground_truth", "/odom", "-d", "3"]),
    ("ape_bag2_db3_message", "ape", ["bag2", "fr1_db3_message", "/ground_truth", "/odom", "-a"]),
    ("ape_bag2_tf_reference", "ape", ["bag2", "fr1_tf", "/ground_truth", "/tf_reference", "-a"]),
    ("traj_bag_all_topics", "traj", ["bag", "fr1_ros1.bag", "--all_topics", "--ref", "/ground_truth", "-a", "--full_check"]),
    ("traj_bag2_compressed", "traj", ["bag2", "fr1_db3_message", "/odom", "-v"]),
]


def read_tum(name):
    rows = []
    for line in (SOURCE / name).read_text().splitlines():
        if line.startswith("#") or not line.strip():
            continue
        rows.append(line.split())
    return rows


def ns_of(stamp):
    """The decimal stamp as integer ns, exactly (the file's digits, not a float)."""
    whole, _, frac = stamp.partition(".")
    return int(whole) * 1_000_000_000 + int((frac + "000000000")[:9])


def quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ])


def quat_rotate(q, v):
    p = quat_mul(quat_mul(q, np.array([*v, 0.0])), q * np.array([-1, -1, -1, 1]))
    return p[:3]


def tf2_slerp(a, b, t):
    """tf2's Quaternion::slerp (shortest path)."""
    dot = float(np.dot(a, b))
    s = np.sqrt(np.dot(a, a) * np.dot(b, b))
    theta = np.arccos(min(1.0, abs(dot) / s))
    if theta == 0.0:
        return a
    d = 1.0 / np.sin(theta)
    s0, s1 = np.sin((1.0 - t) * theta), np.sin(t * theta)
    if dot < 0:
        b = -b
    return (a * s0 + b * s1) * d


def tf_reference(odom_base):
    """map->base as evo's TfCache looks it up (see the module docs): [(ns, t, q)]."""
    stamps = [s for s, _, _ in odom_base]
    start, latest = stamps[0], max(stamps)
    out = []
    t = start
    inv_static_q = STATIC_Q * np.array([-1, -1, -1, 1])
    while t <= latest:
        k = int(np.searchsorted(stamps, t, side="right")) - 1
        s1, t1, q1 = odom_base[k]
        if s1 == t:
            tr, q = t1, q1
        else:
            s2, t2, q2 = odom_base[k + 1]
            ratio = (t - s1) / (s2 - s1)
            tr = t1 * (1.0 - ratio) + t2 * ratio
            q = tf2_slerp(q1, q2, ratio)
        out.append((t, quat_rotate(STATIC_Q, tr) + STATIC_T, quat_mul(STATIC_Q, q)))
        t += 100_000_000
    del inv_static_q
    return out


class Messages:
    """The pose messages of one typestore (ROS 1 or ROS 2)."""

    def __init__(self, ros1):
        self.ros1 = ros1
        self.store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.LATEST)
        if ros1:
            self.store.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"))
        self.T = self.store.types

    def serialize(self, msg):
        kind = type(msg).__msgtype__
        return self.store.serialize_ros1(msg, kind) if self.ros1 else self.store.serialize_cdr(msg, kind)

    def header(self, ns, frame="map"):
        T = self.T
        stamp = T["builtin_interfaces/msg/Time"](sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)
        if self.ros1:
            return T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame)
        return T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    def pose(self, v):
        T = self.T
        return T["geometry_msgs/msg/Pose"](
            position=T["geometry_msgs/msg/Point"](x=v[0], y=v[1], z=v[2]),
            orientation=T["geometry_msgs/msg/Quaternion"](x=v[3], y=v[4], z=v[5], w=v[6]))

    def transform(self, ns, parent, child, t, q):
        T = self.T
        return T["geometry_msgs/msg/TransformStamped"](
            header=self.header(ns, parent), child_frame_id=child,
            transform=T["geometry_msgs/msg/Transform"](
                translation=T["geometry_msgs/msg/Vector3"](x=t[0], y=t[1], z=t[2]),
                rotation=T["geometry_msgs/msg/Quaternion"](x=q[0], y=q[1], z=q[2], w=q[3])))

    def make(self, topic, ns, v):
        """The message of `topic` for one pose (7 values)."""
        T = self.T
        cov = np.zeros(36, dtype=np.float64)
        zero = T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
        h, p = self.header(ns), self.pose(v)
        if topic in ("/ground_truth", "/tf_reference"):
            return T["geometry_msgs/msg/PoseStamped"](header=h, pose=p)
        if topic == "/odom":
            return T["nav_msgs/msg/Odometry"](
                header=h, child_frame_id="base", pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=p, covariance=cov),
                twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=T["geometry_msgs/msg/Twist"](linear=zero, angular=zero), covariance=cov))
        if topic == "/pose_cov":
            return T["geometry_msgs/msg/PoseWithCovarianceStamped"](header=h, pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=p, covariance=cov))
        if topic == "/tf_pose":
            return self.transform(ns, "map", "base", v[:3], v[3:])
        if topic == "/point":
            return T["geometry_msgs/msg/PointStamped"](header=h, point=p.position)
        if topic == "/cmd_vel":
            return T["geometry_msgs/msg/Twist"](linear=zero, angular=zero)
        raise ValueError(topic)


def tf_messages(m, est):
    """(topic, ns, msg) of /tf (odom->base such that map->base is the estimate) and /tf_static."""
    inv_q = STATIC_Q * np.array([-1, -1, -1, 1])
    out = []
    for ns, v in est:
        t = quat_rotate(inv_q, np.array(v[:3]) - STATIC_T)
        q = quat_mul(inv_q, np.array(v[3:]))
        out.append(("/tf", ns, m.T["tf2_msgs/msg/TFMessage"](transforms=[m.transform(ns, "odom", "base", t, q)])))
    ns0 = est[0][0]
    out.append(("/tf_static", ns0, m.T["tf2_msgs/msg/TFMessage"](transforms=[m.transform(ns0, "map", "odom", STATIC_T, STATIC_Q)])))
    return out


def odom_base(est):
    inv_q = STATIC_Q * np.array([-1, -1, -1, 1])
    return [(ns, quat_rotate(inv_q, np.array(v[:3]) - STATIC_T), quat_mul(inv_q, np.array(v[3:]))) for ns, v in est]


def messages_of(m, topics, gt, est, tf=False):
    out = []
    for topic in topics:
        rows = gt if topic == "/ground_truth" else est
        out += [(topic, ns, m.make(topic, ns, v)) for ns, v in rows]
    if tf:
        out += tf_messages(m, est)
    return out


def write_ros1(path, messages, compression=None):
    m = Messages(True)
    writer = Writer1(path)
    if compression:
        writer.set_compression(compression)
    with writer:
        conns = {}
        for topic, ns, msg in messages(m):
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, type(msg).__msgtype__, typestore=m.store)
            writer.write(conns[topic], ns, m.serialize(msg))


def write_ros2(path, messages, storage, mode=None):
    m = Messages(False)
    writer = Writer2(path, version=9, storage_plugin=storage)
    if mode:
        writer.set_compression(mode, CompressionFormat.ZSTD)
    with writer:
        conns = {}
        for topic, ns, msg in messages(m):
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, type(msg).__msgtype__, typestore=m.store)
            writer.write(conns[topic], ns, m.serialize(msg))


def rewrite_lz4(source, dest):
    """The MCAP bag `source` with its chunks lz4-compressed (Foxglove's mcap writer)."""
    from mcap.reader import make_reader
    from mcap.writer import CompressionType, Writer

    dest.mkdir()
    name = f"{dest.name}.mcap"
    with open(source / f"{source.name}.mcap", "rb") as f, open(dest / name, "wb") as out:
        reader = make_reader(f)
        writer = Writer(out, compression=CompressionType.LZ4)
        writer.start(profile="ros2", library="mcap-python")
        summary = reader.get_summary()
        for schema in summary.schemas.values():
            writer.register_schema(schema.name, schema.encoding, schema.data)
        for channel in summary.channels.values():
            writer.register_channel(channel.topic, channel.message_encoding, channel.schema_id, channel.metadata)
        for _, channel, message in reader.iter_messages():
            writer.add_message(channel.id, message.log_time, message.data, message.publish_time, message.sequence)
        writer.finish()
    meta = (source / "metadata.yaml").read_text().replace(f"{source.name}.mcap", name)
    (dest / "metadata.yaml").write_text(meta)


def main():
    # The estimate's first 3 s, and the ground truth from 0.1 s before them.
    start = ns_of(read_tum("freiburg1_xyz-rgbdslam.txt")[0][0])
    end = start + int(SECONDS * 1e9)

    def rows(name):
        return [(ns_of(r[0]), list(map(float, r[1:8]))) for r in read_tum(name)
                if start - 100_000_000 <= ns_of(r[0]) < end]

    gt, est = rows("freiburg1_xyz-groundtruth.txt"), rows("freiburg1_xyz-rgbdslam.txt")
    every = ["/ground_truth", "/odom", "/pose_cov", "/tf_pose", "/point", "/cmd_vel"]
    reference = tf_reference(odom_base(est))
    ref_rows = [(ns, [*t, *q]) for ns, t, q in reference]
    if OUT.exists():
        shutil.rmtree(OUT)
    OUT.mkdir(parents=True)
    write_ros1(OUT / "fr1_ros1.bag", lambda m: messages_of(m, every, gt, est, tf=True), Writer1.CompressionFormat.BZ2)
    first = [r for r in gt if r[0] < start + 1_500_000_000], [r for r in est if r[0] < start + 1_500_000_000]
    write_ros1(OUT / "fr1_plain.bag", lambda m: messages_of(m, ["/ground_truth", "/odom"], *first))
    write_ros1(OUT / "fr1_lz4.bag", lambda m: messages_of(m, ["/ground_truth", "/tf_pose"], gt, est), Writer1.CompressionFormat.LZ4)
    pair = lambda m: messages_of(m, ["/ground_truth", "/odom"], gt, est)  # noqa: E731
    write_ros2(OUT / "fr1_mcap_zstd", pair, StoragePlugin.MCAP, CompressionMode.STORAGE)
    with tempfile.TemporaryDirectory() as tmp:
        plain = pathlib.Path(tmp) / "plain"
        write_ros2(plain, pair, StoragePlugin.MCAP)
        rewrite_lz4(plain, OUT / "fr1_mcap_lz4")
    write_ros2(OUT / "fr1_db3_file", pair, StoragePlugin.SQLITE3, CompressionMode.FILE)
    write_ros2(OUT / "fr1_db3_message", pair, StoragePlugin.SQLITE3, CompressionMode.MESSAGE)

    def tf_bag(m):
        out = messages_of(m, ["/ground_truth"], gt, est, tf=True)
        return out + [("/tf_reference", ns, m.make("/tf_reference", ns, v)) for ns, v in ref_rows]

    write_ros2(OUT / "fr1_tf", tf_bag, StoragePlugin.MCAP, CompressionMode.STORAGE)
    expected = {"tf_reference": [[ns, *map(float, t), *map(float, q)] for ns, t, q in reference], "cases": []}
    with tempfile.TemporaryDirectory() as tmp:
        for name, tool, args in CASES:
            work = pathlib.Path(tmp) / name
            shutil.copytree(OUT, work)
            if tool == "traj":
                stdout = run(tool, args, work)
                expected["cases"].append({"name": name, "tool": tool, "args": args, "stdout": stdout})
                print(f"{name}: {len(stdout.splitlines())} lines")
                continue
            stdout = run(tool, args + ["--save_results", "result.zip"], work)
            archive = load_archive(work / "result.zip")
            expected["cases"].append({
                "name": name, "tool": tool, "args": args, "stdout": stdout, "stats": archive["stats"],
                "errors": archive["arrays"]["error_array"],
                # repr: the exact float64s, for a bit-for-bit comparison.
                "timestamps": [repr(t) for t in archive["arrays"]["timestamps"]]})
            print(f"{name}: {archive['stats']['rmse']}")
    (OUT / "expected.json").write_text(json.dumps(expected) + "\n")


if __name__ == "__main__":
    main()
