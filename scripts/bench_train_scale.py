"""Helper of scripts/bench-train-scale.

  bench_train_scale.py fit SESSION.toml   scikit-learn FastICA on the session's frames; prints
                                          "fit_s peak_rss_kb frames iterations converged"
  bench_train_scale.py report RESULTS     the table (medians, spread, frames/s, exponent)
"""
import math
import os
import resource
import statistics
import sys
import time
import tomllib


def load_frames(manifest):
    import ezc3d
    import numpy as np

    base = os.path.dirname(manifest)
    with open(manifest, "rb") as f:
        session = tomllib.load(f)
    rows = []
    for take in session["take"]:
        c = ezc3d.c3d(os.path.join(base, take["file"]))
        points = c["data"]["points"][:3]  # 3 x markers x frames
        rows.append(points.transpose(2, 1, 0).reshape(points.shape[2], -1))
    return np.ascontiguousarray(np.vstack(rows), dtype=np.float64)


def fit(manifest):
    from sklearn.decomposition import FastICA

    x = load_frames(manifest)
    ica = FastICA(n_components=20, whiten="unit-variance", max_iter=1000, tol=1e-4,
                  random_state=0)
    start = time.perf_counter()
    ica.fit(x)
    seconds = time.perf_counter() - start
    rss_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(f"{seconds:.2f} {rss_kb} {x.shape[0]} {ica.n_iter_} {int(ica.n_iter_ < 1000)}")


def spread(values):
    return f"{statistics.median(values):.2f} ({min(values):.2f}-{max(values):.2f})"


def cpu_per_frame(runs):
    """Median CPU time (user + system, both cores) per frame, µs; — for older results."""
    cpu = [r[4] / r[2] for r in runs if len(r) > 4]
    return f"{1e6 * statistics.median(cpu):.1f}" if cpu else "—"


def iterations(runs):
    """FastICA's iterations over all frames, as one number or a range; — for older results."""
    its = sorted({int(r[5]) for r in runs if len(r) > 5})
    return "—" if not its else str(its[0]) if len(its) == 1 else f"{its[0]}-{its[-1]}"


def report(path):
    train, sk, one = {}, {}, {}
    with open(path) as f:
        for line in f:
            kind, size, *rest = line.split()
            if kind == "train":
                train.setdefault(size, []).append([float(v) for v in rest])
            elif kind == "train1":
                one[size] = [float(v) for v in rest]
            else:
                sk.setdefault(size, []).append([float(v) for v in rest])
    print("\n| session | frames | train wall s, median (min-max) | peak RSS MB | frames/s | "
          "µs per frame | CPU µs per frame | CPU stolen | FastICA iterations | sklearn fit s | "
          "sklearn RSS MB | sklearn iterations |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    points = []
    for size, runs in train.items():
        frames = int(runs[0][2])
        walls = [r[0] for r in runs]
        rss = max(r[1] for r in runs) / 1024
        med = statistics.median(walls)
        if size != "12k":
            points.append((frames, med))
        s = sk.get(size)
        sk_cols = " — | — | — "
        if s:
            sk_cols = (f" {spread([r[0] for r in s])} | {max(r[1] for r in s) / 1024:.0f} | "
                       f"{int(s[0][3])}{'' if s[0][4] else ' (not converged)'} ")
        # Stolen CPU time (both cores) as a share of the wall time, summed over the runs.
        stolen = sum(r[3] for r in runs if len(r) > 3) / sum(walls)
        print(f"| {size} | {frames:,} | {spread(walls)} | {rss:.0f} | {frames / med:,.0f} | "
              f"{1e6 * med / frames:.1f} | {cpu_per_frame(runs)} | {100 * stolen:.1f} % | {iterations(runs)} |{sk_cols}|")
    if len(points) >= 2:
        xs = [math.log(f) for f, _ in points]
        ys = [math.log(t) for _, t in points]
        mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
        slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
        per = [t / f for f, t in points]
        print(f"\nscaling exponent (time ~ frames^k): k = {slope:.3f}; time per frame, largest "
              f"session / smallest: {per[-1] / per[0]:.3f}")
        sizes = [size for size in train if size != "12k"]
        # The reading of linear cost: every size's time per frame (median run) within
        # 20 % of every other's, not only the smallest against the largest.
        per_size = {size: statistics.median(r[0] for r in train[size]) / train[size][0][2]
                    for size in sizes}
        lo, hi = min(per_size, key=per_size.get), max(per_size, key=per_size.get)
        print(f"time per frame from {sizes[0]} to {sizes[-1]}: cheapest {1e6 * per_size[lo]:.1f} µs "
              f"({lo}), dearest {1e6 * per_size[hi]:.1f} µs ({hi}): a spread of "
              f"{per_size[hi] / per_size[lo]:.2f}")
        # What a frame more costs between neighbouring sizes, which a fixed part does not
        # weigh on, and the fixed part the two smallest sizes imply: the spread above holds
        # only when that part is under a fifth of the smallest session's time at the rate.
        marginal = [(tb - ta) / (fb - fa) for (fa, ta), (fb, tb) in zip(points, points[1:])]
        steps = [f"{a} to {b} {1e6 * r:.1f} µs" for a, b, r in zip(sizes, sizes[1:], marginal)]
        print(f"time per frame more, between sizes: {', '.join(steps)}; spread "
              f"{max(marginal) / min(marginal):.2f}")
        (f0, t0), rate = points[0], marginal[0]
        print(f"fixed part at {sizes[0]} (its time less its frames at the {sizes[0]} to "
              f"{sizes[1]} rate): {t0 - rate * f0:.2f} s; within 20 % needs it under "
              f"{0.2 * rate * f0:.2f} s")
        # Run by run (the sizes took turns), so drift over minutes falls on both alike.
        small, large = train[sizes[0]], train[sizes[-1]]
        for name, col in (("wall time", 0), ("CPU time", 4)):
            pairs = [(a, b) for a, b in zip(small, large) if len(a) > col and len(b) > col]
            if not pairs:
                continue
            ratios = [(a[col] / a[2]) / (b[col] / b[2]) for a, b in pairs]
            print(f"{name} per frame, {sizes[0]} / {sizes[-1]}, run by run: "
                  f"{' '.join(f'{r:.2f}' for r in ratios)} "
                  f"(median {statistics.median(ratios):.2f})")
        # FastICA's iteration count is the data's (the synthetic sessions' 20 components are
        # not stable across restarts, and a last-digit change moves it by 10 either way). The
        # same ratio with the smaller run's refinement scaled to the larger run's count.
        pairs = [(a, b) for a, b in zip(small, large)
                 if len(a) > 6 and len(b) > 6 and a[6] > 0 and a[5] > 0]
        if pairs:
            def at_iterations(run, iterations):
                return run[0] - run[6] + run[6] * iterations / run[5]
            ratios = [(at_iterations(a, b[5]) / a[2]) / (b[0] / b[2]) for a, b in pairs]
            print(f"wall time per frame at the {sizes[-1]} run's FastICA iterations, "
                  f"{sizes[0]} / {sizes[-1]}, run by run: "
                  f"{' '.join(f'{r:.2f}' for r in ratios)} "
                  f"(median {statistics.median(ratios):.2f}; refinement "
                  f"{statistics.median(a[6] for a, _ in pairs):.2f} s for {int(pairs[0][0][5])} "
                  f"iterations against {int(pairs[0][1][5])})")
    for size, r in one.items():
        two = statistics.median(x[0] for x in train[size])
        print(f"{size} on one thread: {r[0]:.2f} s; on all cores {two:.2f} s ({r[0] / two:.2f}x speed-up)")
    if "12k" in train and "12k" in sk:
        ours = statistics.median(r[0] for r in train["12k"])
        theirs = statistics.median(r[0] for r in sk["12k"])
        print(f"12,000 frames: whole `train` command {ours:.2f} s, sklearn converged fit "
              f"{theirs:.2f} s: ratio {ours / theirs:.2f}")


if __name__ == "__main__":
    {"fit": lambda: fit(sys.argv[2]), "report": lambda: report(sys.argv[2])}[sys.argv[1]]()
