#!/usr/bin/env python3
"""An independent double-precision check of issue 6's corridor test: does OpenSeqSLAM's slope
search (its default ds = 10, vmin 0.8, vmax 1.2 in 0.1 steps, contrast enhancement
Rwindow = 10) find the right place at least as often as the fixed velocity 1 (the diagonal)?

Written from OpenSeqSLAM's description, not from the core: trajectories start at library
place s and run over ds + 1 query frames with library places s + floor(v t), clipped at the
library's end; contrast enhancement z-scores each library row against the rows +-R/2 around
it (sample standard deviation); the answer for the query at the trajectory's end is the
library place where the best trajectory ends. Only the image differences come from the core
(HE, 32x16 SAD), through seqslam eval's matrix cache. Standard library only.

    build/host/bin/seqslam eval tests/data/corridor/ref tests/data/corridor/query \
        --ground-truth tests/data/corridor/ground_truth.csv --cache /tmp/cc --quiet
    scripts/openseqslam_corridor.py /tmp/cc/diff-*.bin tests/data/corridor/ground_truth.csv
"""
import math
import struct
import sys


def load_matrix(path):
    raw = open(path, "rb").read()
    magic, _key, queries, library, _hash = struct.unpack("<8sQIIQ", raw[:32])
    if magic != b"SQDIFF02":
        sys.exit(f"{path}: not a seqslam difference-matrix cache (magic {magic!r})")
    if len(raw) != 32 + 4 * queries * library:
        sys.exit(f"{path}: truncated")
    values = struct.unpack(f"<{queries * library}I", raw[32:])
    # d[j][q]: mean absolute difference of library place j and query q (SAD / 512 pixels).
    return [[values[q * library + j] / 512.0 for q in range(queries)] for j in range(library)], \
        queries, library


def load_truth(path):
    truth = {}
    for line in open(path).read().splitlines()[1:]:
        if line.strip():
            q, refs = line.split(",")
            truth[int(q)] = {int(r) for r in refs.split()}
    return truth


def enhance(d, window):
    if window == 0:
        return d
    n, queries = len(d), len(d[0])
    out = [[0.0] * queries for _ in range(n)]
    for i in range(n):
        lo, hi = max(0, i - window // 2), min(n - 1, i + window // 2)
        for q in range(queries):
            v = [d[k][q] for k in range(lo, hi + 1)]
            mean = sum(v) / len(v)
            sd = math.sqrt(sum((x - mean) ** 2 for x in v) / (len(v) - 1))
            out[i][q] = (d[i][q] - mean) / (sd if sd > 0 else 1e-9)
    return out


def top1(d, truth, queries, library, ds, velocities):
    correct = total = 0
    for q in range(ds, queries):
        xs = range(q - ds, q + 1)
        best = None
        for s in range(library):
            for v in velocities:
                ys = [min(s + int(math.floor(v * t + 1e-9)), library - 1) for t in range(ds + 1)]
                cost = sum(d[y][x] for y, x in zip(ys, xs))
                if best is None or cost < best[0]:
                    best = (cost, ys[-1])
        total += 1
        correct += best[1] in truth.get(q, set())
    return correct, total


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    d, queries, library = load_matrix(sys.argv[1])
    truth = load_truth(sys.argv[2])
    for window in (10, 0):
        e = enhance(d, window)
        one = top1(e, truth, queries, library, 10, [1.0])
        slope = top1(e, truth, queries, library, 10, [0.8, 0.9, 1.0, 1.1, 1.2])
        print(f"Rwindow {window:2d}: top-1 velocity 1 {100 * one[0] / one[1]:.1f} % "
              f"({one[0]}/{one[1]}), velocities 0.8..1.2 {100 * slope[0] / slope[1]:.1f} % "
              f"({slope[0]}/{slope[1]})")


main()
