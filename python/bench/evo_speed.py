"""Whole evo scripts, file to statistic, with evo's Python API and with ``sitar.evo`` (the
same script, its imports changed), on the shared real runs: the median of 5 of each, one
machine, one run. Prints a Markdown table (python/README.md quotes it).

    python3 python/bench/evo_speed.py [--repeat 5] [--data ../shared/data/real-runs]

Needs evo and the sitar package installed (the wheel, or ``pip install ./python``). Each
timing starts before reading the files and ends with the statistic in hand; the imports are
done once before (their times are printed apart).
"""

import argparse
import importlib
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
    for _ in range(repeat):
        started = time.perf_counter()
        value = script(m, ref, est)
        times.append(time.perf_counter() - started)
    return statistics.median(times), value


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--data", type=Path, default=REPO.parent / "shared" / "data" / "real-runs")
    args = parser.parse_args()
    sequences = [("EuRoC MH_04", args.data / "euroc-vio" / "MH_04"),
                 ("KITTI 00", args.data / "kitti-orbslam2-stereo" / "00"),
                 ("TUM fr1_desk", args.data / "tum-orbslam2-rgbd" / "fr1_desk")]
    missing = [str(s) for _, s in sequences if not (s / "ground_truth.txt").is_file()]
    if missing:
        sys.exit(f"missing real runs: {', '.join(missing)}")
    sitar_m, sitar_import = modules("sitar.evo")
    evo_m, evo_import = modules("evo")
    print(f"imports: evo {evo_import:.2f} s, sitar.evo {sitar_import:.2f} s (once, not timed below)\n")
    print("| script | sequence (ground-truth poses) | evo (s) | sitar.evo (s) | speed-up | same rmse |")
    print("|---|---|---:|---:|---:|---|")
    for title, script in SCRIPTS:
        for name, seq in sequences:
            ref, est = str(seq / "ground_truth.txt"), str(seq / "runs" / "run0.txt")
            poses = sum(1 for l in open(ref) if not l.startswith("#"))
            t_evo, v_evo = median_time(script, evo_m, ref, est, args.repeat)
            t_sitar, v_sitar = median_time(script, sitar_m, ref, est, args.repeat)
            same = "yes" if abs(v_evo - v_sitar) <= 1e-9 else f"NO ({v_evo} vs {v_sitar})"
            print(f"| {title} | {name} ({poses}) | {t_evo:.3f} | {t_sitar:.4f} | "
                  f"{t_evo / t_sitar:.0f}× | {same} |", flush=True)


if __name__ == "__main__":
    main()
