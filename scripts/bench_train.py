#!/usr/bin/env python3
"""Helper of scripts/bench-train: scikit-learn's converged FastICA on a layout's frames.

  bench_train.py fit M FILE...        prints "best_s frames channels iterations converged"
  bench_train.py report M RESULTS     prints the tables of scripts/bench-train from its results

Reads the takes (C3D through ezc3d, TRC and emoshift CSV as text; missing samples as C3D stores them, zeros),
stacks their frames (frames x markers*3, float64) and fits scikit-learn's FastICA with M
components, whiten="unit-variance", whiten_solver="eigh", max_iter=1000, tol=1e-4, its
default BLAS threads, three times; prints the best time (the fit alone, not the reading).
"""
import sys
import time

import numpy as np


def load_c3d(path):
    import ezc3d

    points = ezc3d.c3d(path)["data"]["points"][:3]  # 3 x markers x frames
    x = points.transpose(2, 1, 0).reshape(points.shape[2], -1)
    return np.nan_to_num(x)


def load_trc(path):
    """A TRC file's coordinates: five header lines, then frame, time, x y z per marker."""
    rows = []
    with open(path) as f:
        for i, line in enumerate(f):
            if i < 5 or not line.strip():
                continue
            cells = line.rstrip("\n").split("\t")[2:]
            rows.append([float(c) if c.strip() else 0.0 for c in cells])
    width = max(len(r) for r in rows)
    return np.array([r + [0.0] * (width - len(r)) for r in rows])


def load_csv(path):
    """emoshift's CSV: '#' lines, a header, then frame, time, x y z per marker."""
    rows = []
    with open(path) as f:
        lines = (line for line in f if not line.startswith("#"))
        next(lines)
        for line in lines:
            cells = line.rstrip("\n").split(",")[2:]
            rows.append([float(c) if c.strip() else 0.0 for c in cells])
    return np.array(rows)


def load(paths):
    readers = {".c3d": load_c3d, ".trc": load_trc, ".csv": load_csv}
    parts = [readers[p[p.rfind("."):].lower()](p) for p in paths]
    return np.ascontiguousarray(np.vstack(parts), dtype=np.float64)


def fit(m, paths):
    from sklearn.decomposition import FastICA

    x = load(paths)
    best, ica = float("inf"), None
    for _ in range(3):
        ica = FastICA(n_components=m, whiten="unit-variance", whiten_solver="eigh",
                      max_iter=1000, tol=1e-4, random_state=0)
        start = time.perf_counter()
        ica.fit(x)
        best = min(best, time.perf_counter() - start)
    print(f"{best:.4f} {x.shape[0]} {x.shape[1]} {ica.n_iter_} {int(ica.n_iter_ < 1000)}")


def report(m, path):
    """Markdown tables: train against scikit-learn per layout, then edit and project."""
    import statistics

    train, sk, stream = {}, {}, {}
    order = []
    with open(path) as f:
        for line in f:
            w = line.split()
            if w[0] == "train":
                if w[1] not in train:
                    order.append(w[1])
                train.setdefault(w[1], []).append(
                    (float(w[2]), int(w[3]), int(w[4]), float(w[5]), float(w[6])))
            elif w[0] == "sklearn":
                sk[w[1]] = (float(w[2]), int(w[3]), int(w[4]), int(w[5]), w[6] == "1")
            elif w[0] in ("edit", "project"):
                stream.setdefault(w[0], []).append((float(w[1]), int(w[2]), int(w[3])))
    print(f"\n| layout | frames | channels | `train --components {m}`: median s (min-max) "
          "| head decision: median s (share) | glitch limits: median s | peak RSS MB "
          "| scikit-learn: best s (iterations) | ratio |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for layout in order:
        runs = train[layout]
        wall = statistics.median(r[0] for r in runs)
        head = statistics.median(r[3] for r in runs)
        share = statistics.median(r[3] / r[0] for r in runs)
        limits = statistics.median(r[4] for r in runs)
        rss = statistics.median(r[1] for r in runs) / 1024
        lo, hi = min(r[0] for r in runs), max(r[0] for r in runs)
        frames = runs[0][2]
        if layout in sk:
            best, skf, ch, it, conv = sk[layout]
            skcell = f"{best:.3f} ({it}{'' if conv else ', not converged'})"
            ratio = f"{wall / best:.2f}x"
            if skf != frames:
                ratio += f" (sklearn {skf:,} frames)"
        else:
            ch, skcell, ratio = "-", "-", "-"
        print(f"| {layout} | {frames:,} | {ch} | {wall:.3f} ({lo:.3f}-{hi:.3f}) | "
              f"{head:.3f} ({100 * share:.0f} %) | {limits:.3f} | {rss:.0f} | {skcell} | {ratio} |")
    if stream:
        print("\n| command (10-minute take) | median s (min-max) | MB/s of C3D read | peak RSS MB |")
        print("|---|---:|---:|---:|")
        for cmd in ("project", "edit"):
            runs = stream.get(cmd, [])
            if not runs:
                continue
            wall = statistics.median(r[0] for r in runs)
            lo, hi = min(r[0] for r in runs), max(r[0] for r in runs)
            mb = runs[0][2] / 1e6
            rss = statistics.median(r[1] for r in runs) / 1024
            print(f"| {cmd} | {wall:.2f} ({lo:.2f}-{hi:.2f}) | {mb / wall:.0f} | {rss:.0f} |")


if __name__ == "__main__":
    if len(sys.argv) >= 4 and sys.argv[1] == "fit":
        fit(int(sys.argv[2]), sys.argv[3:])
    elif len(sys.argv) == 4 and sys.argv[1] == "report":
        report(int(sys.argv[2]), sys.argv[3])
    else:
        sys.exit(__doc__)
