#!/usr/bin/env python3
"""Markdown table of the obstacles near the true path in `seqslam slam --json` results
(docs/mapping.md, "Obstacles in the map: precision and recall near the path").

Usage: scripts/slam_obstacles_table.py DIR
       scripts/slam_obstacles_table.py --bands DIR [DIR...]
DIR holds SEED-RUN.json files (e.g. 1-dim.json) for seeds 1, 2, 3 and the six explore runs,
as scripts/slam_table.py reads them. Each must have near_path (a true map and true poses).
The first form prints every count for one band; --bands prints one row per run with
precision / recall / balanced accuracy of both maps for each DIR (e.g. the runs at
--path-band 1 and 1.5), and how many runs meet the target. Standard library only.
"""
import json
import os
import sys

RUNS = ["bright-sun", "dim", "lamps-only", "low-sun", "morning-lamps", "noon-lamps"]
TARGET = 0.8


def load(directory, seed, run):
    with open(os.path.join(directory, f"{seed}-{run}.json"), encoding="utf-8") as f:
        return json.load(f)


def prb(c):
    return (f'{c["occupied_precision"]:.3f} / {c["occupied_recall"]:.3f} / '
            f'{c["balanced_accuracy"]:.3f}')


def bands(dirs):
    """One row per run: P / R / BA of the corrected and the dead-reckoning map per band."""
    first = {}
    head = ["seed", "run", "RMSE corrected m"]
    for d in dirs:
        band = load(d, 1, RUNS[0])["near_path"]["band_m"]
        first[d] = band
        head += [f"{band:g} m corrected: P / R / BA", f"{band:g} m dead reckoning: P / R / BA"]
    print("| " + " | ".join(head) + " |")
    print("|" + " --- |" * len(head))
    met = {d: [0, 0] for d in dirs}
    for seed in (1, 2, 3):
        for run in RUNS:
            cells = [str(seed), run, ""]
            for d in dirs:
                j = load(d, seed, run)
                n = j["near_path"]
                if n["band_m"] != first[d]:
                    sys.exit(f"{d}: {seed}-{run}.json has band {n['band_m']}, not {first[d]}")
                cells[2] = f'{j["rmse_corrected_m"]:.3f}'
                c, k = n["corrected"], n["dead_reckoning"]
                cells += [prb(c), prb(k)]
                for i, m in enumerate((c, k)):
                    if m["occupied_precision"] >= TARGET and m["occupied_recall"] >= TARGET:
                        met[d][i] += 1
            print("| " + " | ".join(cells) + " |")
    print()
    for d in dirs:
        print(f"band {first[d]:g} m: runs with precision and recall >= {TARGET}: corrected "
              f"{met[d][0]} of 18, dead reckoning {met[d][1]} of 18")


def main():
    if len(sys.argv) >= 3 and sys.argv[1] == "--bands":
        bands(sys.argv[2:])
        return
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    head = ["seed", "run", "RMSE corrected m", "band m", "cells", "truly occupied",
            "corrected: called occupied", "both", "unknown to the map",
            "precision", "recall", "within one cell: precision / recall", "balanced accuracy",
            "dead reckoning: precision / recall", "balanced accuracy (dead reckoning)"]
    print("| " + " | ".join(head) + " |")
    print("|" + " --- |" * len(head))
    rows = []
    for seed in (1, 2, 3):
        for run in RUNS:
            j = load(sys.argv[1], seed, run)
            n = j["near_path"]
            c, d = n["corrected"], n["dead_reckoning"]
            unknown = c["cells"] - c["grid_occupied"] - c["grid_free"]
            cells = [str(seed), run, f'{j["rmse_corrected_m"]:.3f}', f'{n["band_m"]:.2f}',
                     str(c["cells"]), str(c["truth_occupied"]), str(c["grid_occupied"]),
                     str(c["occupied_occupied"]), str(unknown),
                     f'{c["occupied_precision"]:.3f}', f'{c["occupied_recall"]:.3f}',
                     f'{c["occupied_precision_within_1_cell"]:.3f} / '
                     f'{c["occupied_recall_within_1_cell"]:.3f}',
                     f'{c["balanced_accuracy"]:.3f}',
                     f'{d["occupied_precision"]:.3f} / {d["occupied_recall"]:.3f}',
                     f'{d["balanced_accuracy"]:.3f}']
            print("| " + " | ".join(cells) + " |")
            rows.append((seed, c))

    def mean(key, seeds):
        xs = [c[key] for s, c in rows if s in seeds]
        return sum(xs) / len(xs)

    def met(p, r):
        return sum(1 for _, c in rows if c[p] >= TARGET and c[r] >= TARGET)

    print()
    for name, seeds in (("seed 1", (1,)), ("seeds 2-3", (2, 3))):
        print(f"{name}, corrected map, mean: precision {mean('occupied_precision', seeds):.3f}, "
              f"recall {mean('occupied_recall', seeds):.3f}, within one cell "
              f"{mean('occupied_precision_within_1_cell', seeds):.3f} / "
              f"{mean('occupied_recall_within_1_cell', seeds):.3f}, balanced accuracy "
              f"{mean('balanced_accuracy', seeds):.3f}")
    print(f"runs with precision and recall >= {TARGET} (corrected map): "
          f"{met('occupied_precision', 'occupied_recall')} of {len(rows)}; within one cell: "
          f"{met('occupied_precision_within_1_cell', 'occupied_recall_within_1_cell')} of "
          f"{len(rows)}")


if __name__ == "__main__":
    main()
