#!/usr/bin/env python3
"""Times scikit-learn's FastICA on the files `fit_timing` wrote and compares with our fit.

Reads, per m, DIR/data_m{m}.f32 (frames x channels), DIR/mixing_m{m}.f64 (channels x m),
DIR/ours_unmixing_m{m}.f64 (m x channels) and our timings (JSON lines, DIR/ours.jsonl).
sklearn runs with its defaults plus whiten="unit-variance", whiten_solver="eigh", the same m
and tol as ours (1e-4), on float64 data, limited to one BLAS thread (ours is single-threaded,
and on a busy 2-core machine sklearn's two threads thrash). Its default max_iter is 200.
Columns: medians in seconds, ratio = ours / sklearn (target <= 0.5), AI = Amari index of the
unmixing against the true mixing (0 = perfect), sk iter / sk warn = sklearn's iterations and
ConvergenceWarnings over the runs. One summary line per m closes the output, with CPU-time
medians as well: on a loaded machine wall time also counts waiting for a core.
"""

import argparse
import json
import statistics
import time
import warnings

import numpy as np
from sklearn.decomposition import FastICA
from sklearn.exceptions import ConvergenceWarning
from threadpoolctl import threadpool_limits


def amari_index(p):
    """Normalised Amari index in [0, 1], the same formula as ica_core::fit::amari_index."""
    a = np.abs(p)
    m = a.shape[0]
    rows = (a.sum(axis=1) / a.max(axis=1) - 1.0).sum()
    cols = (a.sum(axis=0) / a.max(axis=0) - 1.0).sum()
    return (rows + cols) / (2.0 * m * (m - 1.0))


def time_sklearn(x, m, max_iter, runs):
    """Median wall and CPU seconds of `runs` fits, ConvergenceWarnings, the last model."""
    times, cpu, warned, ica = [], [], 0, None
    for _ in range(runs):
        ica = FastICA(
            n_components=m,
            whiten="unit-variance",
            whiten_solver="eigh",
            max_iter=max_iter,
            tol=1e-4,
            random_state=0,
        )
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ConvergenceWarning)
            t0, c0 = time.perf_counter(), time.process_time()
            ica.fit(x)
            times.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
        warned += sum(issubclass(w.category, ConvergenceWarning) for w in caught)
    return statistics.median(times), statistics.median(cpu), warned, ica


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dir", required=True)
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    ours = [json.loads(line) for line in open(f"{args.dir}/ours.jsonl") if line.strip()]
    print(f"numpy {np.__version__}; sklearn limited to one BLAS thread (ours is single-threaded)")
    header = (
        f"{'m':>3} {'ours s':>8} {'sk 1thr s':>9} {'ratio':>6} {'AI ours':>8} {'AI sk':>8} "
        f"{'sk iter':>7} {'sk warn':>7}  ours restarts (explored frames) + refinement"
    )
    print(header)
    lines = []
    for row in ours:
        m, frames, channels = row["m"], row["frames"], row["channels"]
        x = np.fromfile(f"{args.dir}/data_m{m}.f32", dtype="<f4").reshape(frames, channels)
        x = x.astype(np.float64)
        a = np.fromfile(f"{args.dir}/mixing_m{m}.f64", dtype="<f8").reshape(channels, m)
        w_ours = np.fromfile(f"{args.dir}/ours_unmixing_m{m}.f64", dtype="<f8").reshape(m, channels)
        with threadpool_limits(limits=1):
            sk_s, sk_cpu, sk_warn, ica = time_sklearn(x, m, 200, args.runs)
        sk_ai = amari_index(ica.components_ @ a)
        our_ai = amari_index(w_ours @ a)
        ours_s = row["median_s"]
        print(
            f"{m:>3} {ours_s:>8.3f} {sk_s:>9.3f} {ours_s / sk_s:>6.2f} {our_ai:>8.4f} {sk_ai:>8.4f} "
            f"{ica.n_iter_:>7} {sk_warn:>4}/{args.runs:<2}  "
            f"{row['iterations']} ({row.get('explored_frames', frames)}) "
            f"+ {row.get('refine_iterations', 0)} (whitening {row['whiten_median_s']:.3f} s)"
        )
        lines.append(
            f"m={m}: ours {ours_s:.3f} s, sklearn {sk_s:.3f} s (1 thread), "
            f"ratio {ours_s / sk_s:.2f}x, Amari ours {our_ai:.3f} / sklearn {sk_ai:.3f} "
            f"(CPU time: ours {row.get('cpu_median_s', float('nan')):.3f} s, "
            f"sklearn {sk_cpu:.3f} s, ratio {row.get('cpu_median_s', float('nan')) / sk_cpu:.2f}x)"
        )
    print()
    print("\n".join(lines))


if __name__ == "__main__":
    main()
