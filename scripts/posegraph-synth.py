#!/usr/bin/env python3
"""A synthetic 2-D pose graph as g2o, for the pose graph's work-versus-size figures (issue 35;
docs/mapping.md, "Work against the graph's size").

The route of tests/unit/test_pose_graph.cpp's ten-thousand-pose city: a grid of streets 20 m
apart inside a 120 m square, 0.5 m steps, a random turn (left, right or on) at each crossing.
Odometry edges k-1 -> k measure the true step with noise (0.01 m along each axis, 0.3 degrees),
information the inverse variances; every 10th node from node 100 on is closed to the nearest
earlier pose (at least 100 steps back) within 0.5 m and 30 degrees, measured with noise
(--closure-sigma, default 0.01 m along each axis, and --closure-sigma-heading, default 0.005 rad:
about as sure as one odometry step, as in manhattanOlson3500) and that information. Vertices
are the chained odometry; OUT.g2o.truth has the true poses. Deterministic for a seed.

Usage: posegraph-synth.py POSES OUT.g2o [--seed S] [--closure-sigma M] [--closure-sigma-heading R]
"""
import argparse
import math
import random


def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))


def relative(a, b):
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return (c * dx + s * dy, -s * dx + c * dy, wrap(b[2] - a[2]))


def compose(a, r):
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * r[0] - s * r[1], a[1] + s * r[0] + c * r[1], wrap(a[2] + r[2]))


def route(n, rng):
    truth = []
    x = y = 0.0
    d = 0
    for _ in range(n):
        truth.append((x, y, wrap(d * math.pi / 2)))
        gx, gy = x / 20.0, y / 20.0
        if abs(gx - round(gx)) < 1e-9 and abs(gy - round(gy)) < 1e-9:
            for tries in range(8):
                nd = (d + rng.randint(-1, 1)) % 4
                nx = x + (20 if nd == 0 else -20 if nd == 2 else 0)
                ny = y + (20 if nd == 1 else -20 if nd == 3 else 0)
                if -1e-9 <= nx <= 120 + 1e-9 and -1e-9 <= ny <= 120 + 1e-9:
                    d = nd
                    break
                if tries == 7:
                    d = (d + 2) % 4
        x = round((x + 0.5 * math.cos(d * math.pi / 2)) * 2) / 2
        y = round((y + 0.5 * math.sin(d * math.pi / 2)) * 2) / 2
    return truth


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("poses", type=int)
    ap.add_argument("out")
    ap.add_argument("--seed", type=int, default=35)
    ap.add_argument("--closure-sigma", type=float, default=0.01)
    ap.add_argument("--closure-sigma-heading", type=float, default=0.005)
    a = ap.parse_args()
    rng = random.Random(a.seed)
    truth = route(a.poses, rng)
    so, sh = 0.01, 0.3 * math.pi / 180  # odometry noise
    sc, shc = a.closure_sigma, a.closure_sigma_heading
    edges = []
    for k in range(1, a.poses):
        r = relative(truth[k - 1], truth[k])
        m = (r[0] + rng.gauss(0, so), r[1] + rng.gauss(0, so), wrap(r[2] + rng.gauss(0, sh)))
        edges.append((k - 1, k, m, 1 / so**2, 1 / sh**2))
    cells = {}
    for i, p in enumerate(truth):
        cells.setdefault((round(p[0] * 2), round(p[1] * 2)), []).append(i)
    for j in range(100, a.poses, 10):
        p = truth[j]
        best, best_d = None, 0.5
        cx, cy = round(p[0] * 2), round(p[1] * 2)
        for ddx in (-1, 0, 1):
            for ddy in (-1, 0, 1):
                for i in cells.get((cx + ddx, cy + ddy), []):
                    if i + 100 >= j:
                        continue
                    q = truth[i]
                    dist = math.hypot(q[0] - p[0], q[1] - p[1])
                    if dist < best_d and abs(wrap(p[2] - q[2])) < math.radians(30):
                        best, best_d = i, dist
        if best is not None:
            r = relative(truth[best], truth[j])
            m = (r[0] + rng.gauss(0, sc), r[1] + rng.gauss(0, sc), wrap(r[2] + rng.gauss(0, shc)))
            edges.append((best, j, m, 1 / sc**2, 1 / shc**2))
    pose = (0.0, 0.0, 0.0)
    vertices = [pose]
    for e in edges[: a.poses - 1]:
        pose = compose(pose, e[2])
        vertices.append(pose)
    with open(a.out, "w") as f:
        for i, v in enumerate(vertices):
            f.write("VERTEX_SE2 %d %.9f %.9f %.9f\n" % (i, v[0], v[1], v[2]))
        for i, j, m, ip, ih in edges:
            f.write("EDGE_SE2 %d %d %.9f %.9f %.9f %.6f 0 0 %.6f 0 %.6f\n"
                    % (i, j, m[0], m[1], m[2], ip, ip, ih))
    with open(a.out + ".truth", "w") as f:
        for i, v in enumerate(truth):
            f.write("VERTEX_SE2 %d %.9f %.9f %.9f\n" % (i, v[0], v[1], v[2]))


if __name__ == "__main__":
    main()
