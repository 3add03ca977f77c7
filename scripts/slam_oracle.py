#!/usr/bin/env python3
"""What better closures would give: re-solves a `seqslam slam --out DIR` graph in double
precision with closure measurements of known quality (docs/mapping.md, "What limits it").

Usage: scripts/slam_oracle.py DIR [DIR ...]
Needs python3-numpy and python3-scipy (Debian: apt-get install python3-numpy python3-scipy);
an analysis aid, not part of the build or the tests.

For each run it builds the graph of `trajectory.csv` (odometry edges between consecutive
places, information 1 / step length in position and heading, as the core's PoseGraph) and
solves it by Gauss-Newton (node 0 fixed), with loop closures:
  estimated    the run's own closures (closures.csv) as the tool made them: heading offset,
               dx along the route, dy 0;
  true heading the same closures with the true heading offset, dx dy as estimated;
  true pose    the same closures with the true relative pose of their two places;
  dense zero   a closure from every place of the second lap to its truly nearest place of
               the first (within 0.5 m and 30 degrees), true heading, position offset 0;
  dense true   the same with the true relative pose.
It prints the corrected RMSE against the true poses for each. The "dense" rows are an upper
bound on what recognition could give; "dense zero" shows what closures without a position
offset cost even then.
"""
import csv
import math
import os
import sys

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def between(a, b):
    """Pose b seen from pose a: (dx, dy, dtheta)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    ex, ey = b[0] - a[0], b[1] - a[1]
    return np.array([c * ex + s * ey, -s * ex + c * ey, wrap(b[2] - a[2])])


def load(d):
    with open(os.path.join(d, "trajectory.csv"), newline="") as f:
        t = list(csv.DictReader(f))
    with open(os.path.join(d, "closures.csv"), newline="") as f:
        c = list(csv.DictReader(f))
    truth = np.array([[float(r["true_x"]), float(r["true_y"]), math.radians(float(r["true_heading_deg"]))]
                      for r in t])
    odo = np.array([[float(r["odo_x"]), float(r["odo_y"]), math.radians(float(r["odo_heading_deg"]))]
                    for r in t])
    return truth, odo, c


def solve(odo, edges, iterations=20):
    """Gauss-Newton over all poses; edges (a, b, z, w_xy, w_theta); node 0 fixed."""
    n = len(odo)
    x = odo.copy()
    for _ in range(iterations):
        rows, cols, vals, res = [], [], [], []
        k = 0
        for a, b, z, wxy, wth in edges:
            pa, pb = x[a], x[b]
            c, s = math.cos(pa[2]), math.sin(pa[2])
            ex, ey = pb[0] - pa[0], pb[1] - pa[1]
            e = [c * ex + s * ey - z[0], -s * ex + c * ey - z[1], wrap(pb[2] - pa[2] - z[2])]
            ja = [[-c, -s, -s * ex + c * ey], [s, -c, -c * ex - s * ey], [0, 0, -1]]
            jb = [[c, s, 0], [-s, c, 0], [0, 0, 1]]
            for i, w in enumerate((wxy, wxy, wth)):
                if w == 0:
                    continue
                sw = math.sqrt(w)
                for j in range(3):
                    if ja[i][j]:
                        rows.append(k), cols.append(3 * a + j), vals.append(sw * ja[i][j])
                    if jb[i][j]:
                        rows.append(k), cols.append(3 * b + j), vals.append(sw * jb[i][j])
                res.append(sw * e[i])
                k += 1
        for j in range(3):  # anchor node 0
            rows.append(k), cols.append(j), vals.append(1e3)
            res.append(1e3 * (x[0, j] - odo[0, j]))
            k += 1
        jac = sp.csr_matrix((vals, (rows, cols)), shape=(k, 3 * n))
        step = spl.spsolve((jac.T @ jac).tocsc(), -(jac.T @ np.array(res)))
        x += step.reshape(n, 3)
        if np.abs(step).max() < 1e-7:
            break
    return x


def rmse(x, truth):
    return math.sqrt(float(np.mean(np.sum((x[:, :2] - truth[:, :2]) ** 2, axis=1))))


def odometry_edges(odo):
    out = []
    for i in range(len(odo) - 1):
        z = between(odo[i], odo[i + 1])
        d = max(math.hypot(z[0], z[1]), 0.01)
        out.append((i, i + 1, z, 1 / d, 1 / d))
    return out


def run(d):
    truth, odo, closures = load(d)
    base = odometry_edges(odo)
    result = {"dead reckoning": rmse(odo, truth)}
    for name in ("estimated", "true heading", "true pose"):
        edges = list(base)
        for c in closures:
            a, b = int(c["matched_place"]), int(c["place"])
            zt = between(truth[a], truth[b])
            z = np.array([float(c.get("along_offset_m") or 0), 0.0, math.radians(float(c["heading_offset_deg"]))])
            if name == "true heading":
                z[2] = zt[2]
            elif name == "true pose":
                z = zt
            edges.append((a, b, z, 1.0, 1.0))
        result[name] = rmse(solve(odo, edges), truth)
    # Dense ideal closures: every second-lap place to its truly nearest first-lap place. The
    # second lap starts where the run's first closure's place is, less the 60 places the
    # sequence and the gate need; places before it minus 30 count as the first lap.
    if closures:
        start = min(int(c["place"]) for c in closures) - 60
        for name in ("dense zero", "dense true"):
            edges = list(base)
            for b in range(start, len(odo)):
                dist = np.hypot(truth[: start - 30, 0] - truth[b, 0], truth[: start - 30, 1] - truth[b, 1])
                a = int(np.argmin(dist))
                if dist[a] > 0.5 or abs(wrap(truth[b, 2] - truth[a, 2])) > math.radians(30):
                    continue
                zt = between(truth[a], truth[b])
                edges.append((a, b, zt if name == "dense true" else np.array([0.0, 0.0, zt[2]]), 1.0, 1.0))
            result[name] = rmse(solve(odo, edges), truth)
    return result


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    cols = ["dead reckoning", "estimated", "true heading", "true pose", "dense zero", "dense true"]
    print("| run | " + " | ".join(f"RMSE {c} m" for c in cols) + " |")
    print("|" + " --- |" * (len(cols) + 1))
    for d in sys.argv[1:]:
        r = run(d)
        print(f"| {os.path.basename(os.path.normpath(d))} | " +
              " | ".join(f"{r[c]:.3f}" if c in r else "" for c in cols) + " |")


if __name__ == "__main__":
    main()
