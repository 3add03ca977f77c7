#!/usr/bin/env python3
"""Merges the board benchmark and the board image's size report into build/bench/summary.json.

`make bench` runs three images (docs/performance.md): seqslam_bench writes
build/bench/summary.json, seqslam_bench_board build/bench/board/summary.json. This script
copies the board image's "board" member into the first and adds "board_image": the size of
seqslam_fw_app.elf per module (scripts/size-report.py --json), so one file holds every
figure. Running it again replaces what it added before.

Usage: bench-summary.py SUMMARY BOARD_SUMMARY SIZE_JSON
       bench-summary.py --self-test
Exit status 0, 1 on unreadable or malformed input (the summary is then left as it was).
"""
import json
import os
import sys
import tempfile

# The per-M members the issues ask for (docs/performance.md, "The head board's step" and
# "The time between places").
STEP_KEYS = ("places", "card_bytes_per_step", "card_requests_per_step", "step_ms_at_72mhz",
             "ram_bytes", "place_cpu_ms", "place_card_ms", "share_at_035_percent",
             "share_at_015_percent", "longest_slice_ms", "pieces_over_snapshot_period",
             "slices_over_snapshot_period", "scan_places_per_second", "whole_scan_ms",
             "whole_scan_places")


class BadInput(Exception):
    pass


def load(path, what):
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except OSError as e:
        raise BadInput(f"{what} {path}: {e.strerror}") from e
    except json.JSONDecodeError as e:
        raise BadInput(f"{what} {path}: not JSON ({e.msg}, line {e.lineno})") from e
    if not isinstance(data, dict):
        raise BadInput(f"{what} {path}: not a JSON object")
    return data


def board_member(board):
    b = board.get("board")
    if not isinstance(b, dict) or not isinstance(b.get("steps"), list) or not b["steps"]:
        raise BadInput("board summary: no \"board\" object with a non-empty \"steps\" list")
    if not isinstance(b.get("board_capacity_places"), int):
        raise BadInput("board summary: no integer \"board_capacity_places\"")
    for i, step in enumerate(b["steps"]):
        missing = [k for k in STEP_KEYS if not isinstance(step, dict) or k not in step]
        if missing:
            raise BadInput(f"board summary: steps[{i}] lacks {', '.join(missing)}")
    return b


def image_member(size):
    modules = size.get("modules")
    ram = size.get("ram")
    if not isinstance(modules, dict) or not isinstance(ram, dict):
        raise BadInput("size report: no \"modules\" and \"ram\" objects (size-report.py --json)")
    try:
        return {
            "elf": os.path.basename(str(size.get("elf", ""))),
            "ram_used_bytes": int(ram["used"]),
            "ram_budget_bytes": int(ram["budget"]),
            "ram_free_bytes": int(ram["free"]),
            "sections": size.get("sections", {}),
            "modules": {name: int(m["total"]) for name, m in modules.items()},
            "module_sections": modules,
        }
    except (KeyError, TypeError, ValueError) as e:
        raise BadInput(f"size report: malformed module or RAM figures ({e})") from e


def merge(summary_path, board_path, size_path):
    summary = load(summary_path, "summary")
    board = board_member(load(board_path, "board summary"))
    image = image_member(load(size_path, "size report"))
    summary["board"] = board
    summary["board_image"] = image
    # Written next to the file and renamed: a failure leaves the old summary whole.
    folder = os.path.dirname(os.path.abspath(summary_path))
    fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        json.dump(summary, f, indent=2)
        f.write("\n")
    os.replace(tmp, summary_path)
    return summary


def self_test():
    with tempfile.TemporaryDirectory() as d:
        def write(name, text):
            p = os.path.join(d, name)
            with open(p, "w", encoding="utf-8") as f:
                f.write(text)
            return p
        step = {k: 1 for k in STEP_KEYS}
        good_board = json.dumps({"board": {"board_capacity_places": 8032, "steps": [step]}})
        good_size = json.dumps({"elf": "x/seqslam_fw_app.elf",
                                "ram": {"used": 10, "budget": 65456, "free": 65446},
                                "sections": {".text": 8}, "modules": {"core": {"total": 10}}})
        summary = write("summary.json", json.dumps({"config": {"a": 1}}))
        merged = merge(summary, write("b.json", good_board), write("s.json", good_size))
        assert merged["config"] == {"a": 1}
        assert merged["board"]["board_capacity_places"] == 8032
        assert merged["board_image"]["modules"] == {"core": 10}
        assert merged["board_image"]["elf"] == "seqslam_fw_app.elf"
        # Again: replaced, not doubled.
        again = merge(summary, write("b.json", good_board), write("s.json", good_size))
        assert again == merged
        before = open(summary, encoding="utf-8").read()
        bad = [
            ("b.json", "not json", "not JSON"),
            ("b.json", "[1]", "not a JSON object"),
            ("b.json", json.dumps({"board": {"steps": []}}), "non-empty"),
            ("b.json", json.dumps({"board": {"board_capacity_places": 1,
                                             "steps": [{"places": 1}]}}), "lacks card_bytes"),
            ("s.json", json.dumps({"modules": {}}), "size report"),
            ("s.json", json.dumps({"ram": {"used": 1, "budget": 2, "free": 1},
                                   "modules": {"core": {}}}), "malformed"),
        ]
        for name, text, message in bad:
            b = write("b.json", good_board)
            s = write("s.json", good_size)
            write(name, text)
            try:
                merge(summary, b, s)
            except BadInput as e:
                assert message in str(e), (message, str(e))
            else:
                raise AssertionError(f"accepted bad {name}: {text}")
            assert open(summary, encoding="utf-8").read() == before, "summary changed on bad input"
        try:
            merge(os.path.join(d, "missing.json"), b, s)
        except BadInput as e:
            assert "missing.json" in str(e)
        else:
            raise AssertionError("accepted a missing summary")
    print("bench-summary self-test passed")


def main(argv):
    if argv[1:] == ["--self-test"]:
        self_test()
        return 0
    if len(argv) != 4:
        print(__doc__.strip().split("\n\n")[2], file=sys.stderr)
        return 2
    try:
        merged = merge(argv[1], argv[2], argv[3])
    except BadInput as e:
        print(f"bench-summary: {e}", file=sys.stderr)
        return 1
    image = merged["board_image"]
    print(f"bench-summary: {argv[1]} gains \"board\" ({len(merged['board']['steps'])} library sizes) "
          f"and \"board_image\" ({image['elf']}: {image['ram_used_bytes']} of "
          f"{image['ram_budget_bytes']} bytes)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
