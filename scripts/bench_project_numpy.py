#!/usr/bin/env python3
"""numpy baseline for scripts/bench-project: the same per-frame work as the Rust
`frame_timing` example (u = W @ (x - mean); u[k] += a; x2 = mean + M @ u), one frame per
Python loop iteration, float32 like the Rust hot path. Prints median (and min) ns per frame
per m, then, given the Rust example's output file, a table with the ratios."""

import re
import sys
import time

import numpy as np

BATCH = 2_000
BATCHES = 101


def timing_ns(markers: int, m: int) -> tuple[float, float]:
    n = markers * 3
    rng = np.random.default_rng(42)
    mixing = rng.uniform(-1.0, 1.0, size=(n, m)).astype(np.float32)
    unmixing = np.linalg.pinv(mixing.astype(np.float64)).astype(np.float32)
    mean = rng.uniform(900.0, 1100.0, size=n).astype(np.float32)
    frames = [mean + rng.uniform(-5.0, 5.0, size=n).astype(np.float32) for _ in range(64)]
    k, alpha = m // 2, np.float32(1.5)

    def batch() -> None:
        for f in range(BATCH):
            x = frames[f % 64]
            u = unmixing @ (x - mean)
            u[k] += alpha
            x2 = mean + mixing @ u  # noqa: F841 (the output frame)

    batch()  # warm-up
    per_frame = []
    for _ in range(BATCHES):
        start = time.perf_counter_ns()
        batch()
        per_frame.append((time.perf_counter_ns() - start) / BATCH)
    per_frame.sort()
    return per_frame[BATCHES // 2], per_frame[0]


def parse_rust(path: str) -> dict[int, dict[str, float]]:
    rows = {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            if not line.startswith("rust "):
                continue
            fields = dict(re.findall(r"(\w+)=([0-9.]+)", line))
            rows[int(fields["m"])] = {key: float(v) for key, v in fields.items()}
    return rows


def main() -> None:
    markers = int(sys.argv[1])
    ms = [int(v) for v in sys.argv[2].split(",")]
    rust = parse_rust(sys.argv[3]) if len(sys.argv) > 3 else {}
    print(f"numpy {np.__version__}, {markers} markers ({markers * 3} channels), float32, "
          "per frame: project + translate one component + resynthesise")
    header = f"{'m':>3} {'rust ns':>10} {'numpy ns':>10} {'numpy/rust':>11}   " \
             f"{'rust min':>9} {'numpy min':>10} {'ratio(min)':>11}   {'rust masked 20%':>15}"
    print(header)
    for m in ms:
        med, best = timing_ns(markers, m)
        r = rust.get(m)
        if r is None:
            print(f"{m:>3} {'-':>10} {med:>10.1f}")
            continue
        print(f"{m:>3} {r['full_ns']:>10.1f} {med:>10.1f} {med / r['full_ns']:>10.1f}x   "
              f"{r['full_min_ns']:>9.1f} {best:>10.1f} {best / r['full_min_ns']:>10.1f}x   "
              f"{r['masked_ns']:>15.1f}")


if __name__ == "__main__":
    main()
