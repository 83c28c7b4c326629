"""Whole evo scripts, file to statistic, with evo's Python API and with ``sitar.evo`` (the
same script, its imports changed), on the shared real runs: the median of 5 of each, one
machine, one run. Prints a Markdown table (python/README.md quotes it).

    python3 python/bench/evo_speed.py [--repeat 5] [--data ../shared/data/real-runs]
    python3 python/bench/evo_speed.py --steps --repeat 15   # sitar.evo's RPE script by step

Needs evo and the sitar package installed (the wheel, or ``pip install ./python``). Each
timing starts before reading the files and ends with the statistic in hand; the imports are
done once before (their times are printed apart), and each script runs once untimed
before its 5 timed runs, with either library (a process's first run also starts thread pools
and imports what the libraries import lazily). Each library is timed in a process of its
own (evo's, then sitar.evo's, one after the other), so neither runs beside the other's
threads: numpy's OpenBLAS workers spin for a while after evo's SVDs, and on two cores they
took the CPU from sitar.evo's scripts timed right after them in one process.
"""

import argparse
import importlib
import json
import os
import subprocess
import statistics
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def modules(prefix):
    started = time.perf_counter()
    fi = importlib.import_module(f"{prefix}.tools.file_interface")
    sync = importlib.import_module(f"{prefix}.core.sync")
    metrics = importlib.import_module(f"{prefix}.core.metrics")
    return (fi, sync, metrics), time.perf_counter() - started


def ape(m, ref, est):
    fi, sync, metrics = m
    r, e = sync.associate_trajectories(fi.read_tum_trajectory_file(ref),
                                       fi.read_tum_trajectory_file(est), max_diff=0.01)
    e.align(r)
    metric = metrics.APE(metrics.PoseRelation.translation_part)
    metric.process_data((r, e))
    return metric.get_statistic(metrics.StatisticsType.rmse)


def rpe_frames(m, ref, est):
    fi, sync, metrics = m
    r, e = sync.associate_trajectories(fi.read_tum_trajectory_file(ref),
                                       fi.read_tum_trajectory_file(est), max_diff=0.01)
    e.align(r)
    metric = metrics.RPE(metrics.PoseRelation.translation_part, 1, metrics.Unit.frames)
    metric.process_data((r, e))
    return metric.get_statistic(metrics.StatisticsType.rmse)


def rpe_meters_all_pairs(m, ref, est):
    fi, sync, metrics = m
    r, e = sync.associate_trajectories(fi.read_tum_trajectory_file(ref),
                                       fi.read_tum_trajectory_file(est), max_diff=0.01)
    metric = metrics.RPE(metrics.PoseRelation.translation_part, 1.0, metrics.Unit.meters,
                         all_pairs=True)
    metric.process_data((r, e))
    return metric.get_statistic(metrics.StatisticsType.rmse)


def rpe_meters_all_pairs_metric_only(m, ref, est):
    """The metric alone: the files read and associated before the clock starts."""
    fi, sync, metrics = m
    key = (id(m), ref, est)
    if key not in _READ:
        _READ[key] = sync.associate_trajectories(fi.read_tum_trajectory_file(ref),
                                                 fi.read_tum_trajectory_file(est), max_diff=0.01)
    return key


_READ = {}


def _metric_only(m, key):
    fi, sync, metrics = m
    r, e = _READ[key]
    metric = metrics.RPE(metrics.PoseRelation.translation_part, 1.0, metrics.Unit.meters,
                         all_pairs=True)
    metric.process_data((r, e))
    return metric.get_statistic(metrics.StatisticsType.rmse)


SCRIPTS = [("APE, SE(3) aligned", ape), ("RPE, 1 frame", rpe_frames),
           ("RPE, 1 m, all pairs", rpe_meters_all_pairs),
           ("RPE, 1 m, all pairs: process_data alone", None)]


def median_time(script, m, ref, est, repeat):
    times, value = [], None
    if script is None:  # the metric alone, on trajectories read before
        key = rpe_meters_all_pairs_metric_only(m, ref, est)
        script = lambda m, ref, est: _metric_only(m, key)  # noqa: E731
    script(m, ref, est)  # untimed: one-time costs of a process (thread pools, lazy imports)
    for _ in range(repeat):
        started = time.perf_counter()
        value = script(m, ref, est)
        times.append(time.perf_counter() - started)
    return statistics.median(times), value


def sequences_of(data):
    return [("EuRoC MH_04", data / "euroc-vio" / "MH_04"),
            ("KITTI 00", data / "kitti-orbslam2-stereo" / "00"),
            ("TUM fr1_desk", data / "tum-orbslam2-rgbd" / "fr1_desk")]


def worker(prefix, data, repeat):
    """Times every script with one library; prints JSON: the import time and, per script
    and sequence, the median time and the RMSE."""
    m, imported = modules(prefix)
    out = {"import": imported, "rows": []}
    for title, script in SCRIPTS:
        for name, seq in sequences_of(data):
            ref, est = str(seq / "ground_truth.txt"), str(seq / "runs" / "run0.txt")
            t, v = median_time(script, m, ref, est, repeat)
            out["rows"].append([title, name, t, v])
    print(json.dumps(out))


STEPS = ["read ground truth", "read run", "associate", "parse kept poses", "process_data",
         "statistic", "whole"]


def steps(data, repeat):
    """``sitar.evo``'s RPE 1 m all-pairs script timed step by step (median of ``repeat``
    after one untimed run), as a Markdown table; the poses are parsed when first used, here
    timed apart before ``process_data``."""
    fi, sync, metrics = modules("sitar.evo")[0]
    print("| sequence | " + " | ".join(STEPS) + " |")
    print("|---|" + "---:|" * len(STEPS))
    for name, seq in sequences_of(data):
        ref, est = str(seq / "ground_truth.txt"), str(seq / "runs" / "run0.txt")
        times = []
        for _ in range(repeat + 1):
            t = [time.perf_counter()]
            r = fi.read_tum_trajectory_file(ref)
            t.append(time.perf_counter())
            e = fi.read_tum_trajectory_file(est)
            t.append(time.perf_counter())
            r, e = sync.associate_trajectories(r, e, max_diff=0.01)
            t.append(time.perf_counter())
            r.positions_xyz, e.positions_xyz  # the poses are parsed when first used
            t.append(time.perf_counter())
            metric = metrics.RPE(metrics.PoseRelation.translation_part, 1.0, metrics.Unit.meters,
                                 all_pairs=True)
            metric.process_data((r, e))
            t.append(time.perf_counter())
            metric.get_statistic(metrics.StatisticsType.rmse)
            t.append(time.perf_counter())
            times.append([b - a for a, b in zip(t, t[1:])] + [t[-1] - t[0]])
        medians = [statistics.median(column) for column in zip(*times[1:])]
        print(f"| {name} | " + " | ".join(f"{m * 1e3:.2f} ms" for m in medians) + " |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--data", type=Path, default=REPO.parent / "shared" / "data" / "real-runs")
    parser.add_argument("--steps", action="store_true",
                        help="time sitar.evo's RPE 1 m all-pairs script step by step instead")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        return worker(args.worker, args.data, args.repeat)
    if args.steps:
        return steps(args.data, args.repeat)
    sequences = sequences_of(args.data)
    missing = [str(s) for _, s in sequences if not (s / "ground_truth.txt").is_file()]
    if missing:
        sys.exit(f"missing real runs: {', '.join(missing)}")

    def timed(prefix):
        out = subprocess.run([sys.executable, __file__, "--worker", prefix, "--data", str(args.data),
                              "--repeat", str(args.repeat)], check=True, capture_output=True, text=True)
        return json.loads(out.stdout)

    load_before = os.getloadavg()
    evo, ours = timed("evo"), timed("sitar.evo")
    load_after = os.getloadavg()
    print(f"load average (1, 5, 15 min): {' '.join(f'{v:.2f}' for v in load_before)} before, "
          f"{' '.join(f'{v:.2f}' for v in load_after)} after, on {os.cpu_count()} cores")
    print(f"imports: evo {evo['import']:.2f} s, sitar.evo {ours['import']:.2f} s (once per process, "
          f"not timed below)\n")
    print("| script | sequence (ground-truth poses) | evo (s) | sitar.evo (s) | speed-up | same rmse |")
    print("|---|---|---:|---:|---:|---|")
    poses = {name: sum(1 for l in open(seq / "ground_truth.txt") if not l.startswith("#"))
             for name, seq in sequences}
    for (title, name, t_evo, v_evo), (_, _, t_sitar, v_sitar) in zip(evo["rows"], ours["rows"]):
        same = "yes" if abs(v_evo - v_sitar) <= 1e-9 else f"NO ({v_evo} vs {v_sitar})"
        print(f"| {title} | {name} ({poses[name]}) | {t_evo:.3f} | {t_sitar:.4f} | "
              f"{t_evo / t_sitar:.0f}× | {same} |", flush=True)


if __name__ == "__main__":
    main()
