#!/usr/bin/env python3
"""Markdown table of `seqslam slam --json` results (docs/mapping.md, "Measured").

Usage: scripts/slam_table.py DIR [COMPARE_DIR]
DIR holds SEED-RUN.json files (e.g. 1-dim.json) of the default settings; COMPARE_DIR, if
given, the same runs with another setting, whose corrected RMSE is shown in an extra column.
Standard library only.
"""
import json
import os
import sys

RUNS = ["bright-sun", "dim", "lamps-only", "low-sun", "morning-lamps", "noon-lamps"]


def load(d, seed, run):
    with open(os.path.join(d, f"{seed}-{run}.json"), encoding="utf-8") as f:
        return json.load(f)


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    d = sys.argv[1]
    cmp_dir = sys.argv[2] if len(sys.argv) == 3 else None
    head = ["seed", "run", "places", "RMSE dead reckoning m", "RMSE corrected m", "ratio"]
    if cmp_dir:
        head.append("RMSE corrected, other setting m")
    head += ["closures", "false", "rejected (position)", "closure heading error / same heading, RMS deg",
             "closure along-route error / matcher's place, RMS m",
             "map accuracy corrected / dead reckoning", "places to relocalise after return"]
    print("| " + " | ".join(head) + " |")
    print("|" + " --- |" * len(head))
    rows = []
    for seed in (1, 2, 3):
        for run in RUNS:
            j = load(d, seed, run)
            ratio = j["rmse_corrected_m"] / j["rmse_dead_reckoning_m"]
            cells = [str(seed), "explore_" + run, str(j["places"]), f'{j["rmse_dead_reckoning_m"]:.3f}',
                     f'{j["rmse_corrected_m"]:.3f}', f"{ratio:.2f}"]
            if cmp_dir:
                cells.append(f'{load(cmp_dir, seed, run)["rmse_corrected_m"]:.3f}')
            cells += [str(j["closures"]), str(j["false_closures"]), str(j["rejected_position"]),
                      f'{j["closure_heading_error_rms_deg"]:.2f} / {j["closure_same_heading_error_rms_deg"]:.2f}',
                      f'{j.get("closure_along_error_rms_m", 0):.3f} / {j.get("closure_gate_along_error_rms_m", 0):.3f}',
                      f'{j["map_accuracy_corrected"]:.3f} / {j["map_accuracy_dead_reckoning"]:.3f}',
                      str([e["relocalised_after"] for e in j["events"]])]
            print("| " + " | ".join(cells) + " |")
            rows.append((seed, j, ratio))
    met = [(s, j) for s, j, r in rows if j["rmse_corrected_m"] <= 0.15 and r <= 0.25]
    mean = lambda xs: sum(xs) / len(xs)
    print()
    print(f"mean corrected RMSE: seed 1 {mean([j['rmse_corrected_m'] for s, j, _ in rows if s == 1]):.3f} m, "
          f"seeds 2-3 {mean([j['rmse_corrected_m'] for s, j, _ in rows if s != 1]):.3f} m; "
          f"runs meeting <= 0.15 m and <= 1/4 of dead reckoning: {len(met)} of {len(rows)}; "
          f"false closures: {sum(j['false_closures'] for _, j, _ in rows)}")


if __name__ == "__main__":
    main()
