#!/usr/bin/env python3
"""Where the bytes of a target image go: per section, per module, per symbol.

    size-report.py [--map MAP] [--json FILE] [--top N] [--objects] IMAGE.elf
    size-report.py --self-test [IMAGE.elf ...]

Reads the ELF (section headers and symbol table) and the GNU ld link map that
seqslam_target_executable writes next to it (IMAGE.elf.map, -Wl,-Map=...). The map says
which object or archive member every input section comes from, so code that the compiler
inlined into a function is counted where it was emitted, not where it was written (nm alone
cannot do that). Prints, and with --json writes:

  - the bytes per output section in the RAM region (.text, .rodata, .data incl. .sdata,
    .bss incl. .sbss, the reserved stack incl. its guard) and the alignment gaps between
    them, against the RAM region's length (65 456 bytes for firmware.ld);
  - the bytes per module and section:
        core      objects from libseqslam.a (src/)
        storage   libseqslam_storage.a (storage/)
        session   libseqslam_session.a (session/: the pipeline's wiring, the capacity profile)
        hal       the board library (hal/board/<board>: crt0, console, virtio, ...)
        app       the image's own objects and libseqslam_app.a (firmware/app, bench/, ...)
        runtime   compiler runtime: libgcc members (64-bit division, shifts, __clz_tab)
                  and the board's memcpy/memset/memmove/memcmp (runtime.cpp)
        other     any other object or archive (e.g. a test harness)
        padding   alignment fill inside output sections and gaps between them
        stack     the reserved stack and its guard (.stack)
    Every byte of the used RAM is in exactly one row, and the rows of each column add up to
    the section sizes in the ELF; the report checks both and fails (status 1) if not.
  - the string-literal bytes (.rodata.str*/.rodata.<function>.str* input sections, after
    the linker merged duplicates) per module;
  - the libgcc members linked in and the reference that pulled each in;
  - the largest symbols (functions and objects, from the ELF symbol table) with module.

LTO: objects made by the link-time optimiser (*.ltrans.o) have no module. Their input
sections are attributed by the (mangled) function or object name in the section name:
seqslam::storage -> storage, seqslam::board / seqslam::hal / seqslam_board_* -> hal,
seqslam::app and main -> app, other seqslam:: names -> core; what has no name (switch
tables, .rodata.str1.4 of several functions) goes to "other". The report says so.

Exit status: 0 report written; 1 internal inconsistency (sums do not match);
2 bad input (missing file, not an ELF, no or unreadable map, map not of this ELF).
Standard library only; demangles with <prefix>c++filt / c++filt if found.
"""

import argparse
import bisect
import json
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile

MODULES = ["core", "storage", "session", "hal", "app", "runtime", "other", "padding", "stack"]
MODULE_TEXT = {
    "core": "core (libseqslam.a, src/)",
    "storage": "storage (libseqslam_storage.a)",
    "session": "session (libseqslam_session.a)",
    "hal": "HAL/board (hal/board/...)",
    "app": "app (firmware/<image>, libseqslam_app.a)",
    "runtime": "compiler runtime (libgcc, memcpy/memset)",
    "other": "other objects",
    "padding": "linker padding (alignment)",
    "stack": "stack (reserved + guard)",
}
COLUMNS = [".text", ".rodata", ".data", ".bss", "stack", "other"]
RUNTIME_FUNCS = {"memcpy", "memset", "memmove", "memcmp", "__cxa_pure_virtual"}
DEFAULT_BUDGET = 65456


class BadInput(Exception):
    """Input the tool cannot use: reported with exit status 2."""


# ----------------------------------------------------------------------------------------
# ELF


def read_elf(path):
    """Section headers and FUNC/OBJECT symbols of an ELF file."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except FileNotFoundError:
        raise BadInput(f"no such file: {path}")
    except OSError as e:
        raise BadInput(f"cannot read {path}: {e.strerror}")
    if len(data) < 52 or data[:4] != b"\x7fELF":
        raise BadInput(f"not an ELF file: {path}")
    ei_class, ei_data = data[4], data[5]
    if ei_class not in (1, 2) or ei_data not in (1, 2):
        raise BadInput(f"unsupported ELF class/encoding in {path}")
    end = "<" if ei_data == 1 else ">"
    try:
        if ei_class == 1:
            (shoff,) = struct.unpack_from(end + "I", data, 0x20)
            shentsize, shnum, shstrndx = struct.unpack_from(end + "HHH", data, 0x2E)
            sh_fmt, sym_fmt = end + "IIIIIIIIII", end + "IIIBBH"
        else:
            (shoff,) = struct.unpack_from(end + "Q", data, 0x28)
            shentsize, shnum, shstrndx = struct.unpack_from(end + "HHH", data, 0x3A)
            sh_fmt, sym_fmt = end + "IIQQQQIIQQ", end + "IBBHQQ"
        (machine,) = struct.unpack_from(end + "H", data, 0x12)
        raw = []
        for i in range(shnum):
            raw.append(struct.unpack_from(sh_fmt, data, shoff + i * shentsize))
        if not raw or shstrndx >= len(raw):
            raise BadInput(f"ELF file without section headers: {path}")

        def cstr(table_off, off):
            stop = data.index(b"\0", table_off + off)
            return data[table_off + off:stop].decode("utf-8", "replace")

        str_off = raw[shstrndx][4]
        sections = []
        for r in raw:
            name, stype, flags, addr, off, size, link, info, align, entsize = r
            sections.append({"name": cstr(str_off, name), "type": stype, "flags": flags,
                             "addr": addr, "offset": off, "size": size, "link": link,
                             "entsize": entsize})
        symbols = []
        for sec in sections:
            if sec["type"] != 2:  # SHT_SYMTAB
                continue
            strtab = sections[sec["link"]]["offset"]
            count = sec["size"] // sec["entsize"] if sec["entsize"] else 0
            for i in range(count):
                fields = struct.unpack_from(sym_fmt, data, sec["offset"] + i * sec["entsize"])
                if ei_class == 1:
                    st_name, value, size, info, _other, shndx = fields
                else:
                    st_name, info, _other, shndx, value, size = fields
                stype, bind = info & 0xF, info >> 4
                if stype not in (1, 2) or size == 0 or shndx == 0 or shndx >= len(sections):
                    continue  # only objects and functions with a size in a real section
                symbols.append({"name": cstr(strtab, st_name), "addr": value, "size": size,
                                "section": sections[shndx]["name"], "global": bind != 0,
                                "kind": "function" if stype == 2 else "object"})
    except (struct.error, ValueError, IndexError):
        raise BadInput(f"truncated or corrupt ELF file: {path}")
    return sections, symbols, {"machine": machine, "data": data, "little": ei_data == 1}


EM_RISCV = 0xF3


def riscv_call_targets(code, base):
    """(pc, target) of every direct call or jump (jal, c.jal, c.j, auipc+jalr) in a run of
    RISC-V code starting at address base. Decodes sequentially; no data in .text here."""
    out = []
    i = 0
    n = len(code)
    prev_auipc = None  # (rd, pc, value)
    while i + 2 <= n:
        half = code[i] | (code[i + 1] << 8)
        pc = base + i
        if half & 3 != 3:  # 16-bit (C extension)
            if half & 3 == 1 and (half >> 13) in (1, 5):  # c.jal (RV32) / c.j
                b = half
                imm = (((b >> 12) & 1) << 11 | ((b >> 11) & 1) << 4 | ((b >> 9) & 3) << 8
                       | ((b >> 8) & 1) << 10 | ((b >> 7) & 1) << 6 | ((b >> 6) & 1) << 7
                       | ((b >> 3) & 7) << 1 | ((b >> 2) & 1) << 5)
                if imm & 0x800:
                    imm -= 0x1000
                out.append((pc, pc + imm))
            prev_auipc = None
            i += 2
            continue
        if i + 4 > n:
            break
        w = half | (code[i + 2] << 16) | (code[i + 3] << 24)
        op = w & 0x7F
        if op == 0x6F:  # jal
            imm = (((w >> 31) & 1) << 20 | ((w >> 21) & 0x3FF) << 1 | ((w >> 20) & 1) << 11
                   | ((w >> 12) & 0xFF) << 12)
            if imm & 0x100000:
                imm -= 0x200000
            out.append((pc, pc + imm))
            prev_auipc = None
        elif op == 0x17:  # auipc
            imm = w & 0xFFFFF000
            if imm & 0x80000000:
                imm -= 0x100000000
            prev_auipc = ((w >> 7) & 0x1F, pc, pc + imm)
        elif op == 0x67 and prev_auipc and ((w >> 15) & 0x1F) == prev_auipc[0]:  # jalr
            imm = w >> 20
            if imm & 0x800:
                imm -= 0x1000
            out.append((prev_auipc[1], (prev_auipc[2] + imm) & 0xFFFFFFFF))
            prev_auipc = None
        else:
            prev_auipc = None
        i += 4
    return out


# ----------------------------------------------------------------------------------------
# GNU ld map

HEX = r"0x([0-9a-fA-F]+)"
RE_REGION = re.compile(r"^(\S+)\s+" + HEX + r"\s+" + HEX + r"(?:\s+\S+)?\s*$")
RE_OUT_FULL = re.compile(r"^(\.\S*|/DISCARD/|COMMON)\s+" + HEX + r"\s+" + HEX + r"(?:\s.*)?$")
RE_OUT_NAME = re.compile(r"^(\.\S*|/DISCARD/)\s*$")
RE_IN_FULL = re.compile(r"^ (\.\S*|COMMON)\s+" + HEX + r"\s+" + HEX + r"\s+(\S.*?)\s*$")
RE_IN_NAME = re.compile(r"^ (\.\S*|COMMON)\s*$")
RE_ADDR_SIZE = re.compile(r"^\s+" + HEX + r"\s+" + HEX + r"(?:\s+(\S.*?))?\s*$")
RE_FILL = re.compile(r"^ \*fill\*\s+" + HEX + r"\s+" + HEX)
RE_MEMBER = re.compile(r"^(\S.*\))\s*$")
RE_REF = re.compile(r"^\s+(\S+)?\s*\((.*)\)\s*$")


def parse_map(path):
    try:
        with open(path, "r", encoding="utf-8", errors="replace") as f:
            lines = f.read().splitlines()
    except FileNotFoundError:
        raise BadInput(f"no such map file: {path}")
    except OSError as e:
        raise BadInput(f"cannot read map {path}: {e.strerror}")
    return parse_map_lines(lines, path)


def parse_map_lines(lines, path="<map>"):
    try:
        mem_at = lines.index("Memory Configuration")
        script_at = lines.index("Linker script and memory map")
    except ValueError:
        raise BadInput(f"not a GNU ld link map (no memory map in it): {path}")

    # Archive members and what pulled them in (before the memory configuration).
    members = []
    i = 0
    while i < mem_at:
        line = lines[i]
        if line.startswith("Discarded input sections"):
            break
        m = RE_MEMBER.match(line)
        if m and i + 1 < mem_at and lines[i + 1].startswith(" "):
            r = RE_REF.match(lines[i + 1])
            if r:
                members.append({"member": m.group(1), "referenced_by": r.group(1) or "",
                                "symbol": r.group(2)})
                i += 2
                continue
        i += 1

    # Discarded input sections (COMDAT duplicates and --gc-sections removals).
    discarded = []
    try:
        d_at = lines.index("Discarded input sections")
    except ValueError:
        d_at = None
    if d_at is not None:
        pending = None
        for line in lines[d_at + 1:mem_at]:
            m = RE_IN_FULL.match(line)
            if m:
                discarded.append((m.group(1), int(m.group(3), 16), m.group(4)))
                pending = None
                continue
            m = RE_IN_NAME.match(line)
            if m:
                pending = m.group(1)
                continue
            m = RE_ADDR_SIZE.match(line)
            if m and pending and m.group(3):
                discarded.append((pending, int(m.group(2), 16), m.group(3)))
            pending = None

    regions = {}
    for line in lines[mem_at + 1:script_at]:
        m = RE_REGION.match(line)
        if m and m.group(1) not in ("Name", "*default*"):
            regions[m.group(1)] = (int(m.group(2), 16), int(m.group(3), 16))

    outputs = []
    out = None
    pending_out = None
    pending_in = None
    for line in lines[script_at + 1:]:
        if not line.strip():
            continue
        if pending_out is not None:
            m = RE_ADDR_SIZE.match(line)
            pending_name, pending_out = pending_out, None
            if m:
                out = {"name": pending_name, "addr": int(m.group(1), 16),
                       "size": int(m.group(2), 16), "inputs": [], "fills": []}
                outputs.append(out)
                continue
            out = {"name": pending_name, "addr": None, "size": 0, "inputs": [], "fills": []}
            outputs.append(out)
        if pending_in is not None:
            m = RE_ADDR_SIZE.match(line)
            name, pending_in = pending_in, None
            if m and m.group(3) is not None and out is not None:
                out["inputs"].append({"name": name, "addr": int(m.group(1), 16),
                                      "size": int(m.group(2), 16), "file": m.group(3)})
                continue
        if not line.startswith(" "):
            m = RE_OUT_FULL.match(line)
            if m:
                out = {"name": m.group(1), "addr": int(m.group(2), 16),
                       "size": int(m.group(3), 16), "inputs": [], "fills": []}
                outputs.append(out)
                continue
            m = RE_OUT_NAME.match(line)
            if m:
                pending_out = m.group(1)
                continue
            if line.startswith("OUTPUT("):
                out = None
            continue
        if out is None:
            continue
        m = RE_FILL.match(line)
        if m:
            out["fills"].append((int(m.group(1), 16), int(m.group(2), 16)))
            continue
        m = RE_IN_FULL.match(line)
        if m:
            out["inputs"].append({"name": m.group(1), "addr": int(m.group(2), 16),
                                  "size": int(m.group(3), 16), "file": m.group(4)})
            continue
        m = RE_IN_NAME.match(line)
        if m:
            pending_in = m.group(1)
            continue
    if not outputs:
        raise BadInput(f"no output sections in the link map: {path}")
    return {"regions": regions, "outputs": outputs, "members": members,
            "discarded": discarded}


# ----------------------------------------------------------------------------------------
# Attribution

RE_ARCHIVE = re.compile(r"^(.*?)([^/]+\.a)\((.+)\)$")


def split_file(file):
    """(archive basename or '', member or object basename)."""
    m = RE_ARCHIVE.match(file)
    if m:
        return m.group(2), m.group(3)
    return "", os.path.basename(file)


def is_lto_object(file):
    return ".ltrans" in file and file.endswith(".o")


def module_of_file(file):
    archive, member = split_file(file)
    if archive:
        if archive.startswith("libgcc"):
            return "runtime"
        if archive == "libseqslam.a":
            return "core"
        if archive == "libseqslam_storage.a":
            return "storage"
        if archive == "libseqslam_session.a":
            return "session"
        if archive == "libseqslam_board.a":
            return "runtime" if member.startswith("runtime.") else "hal"
        if archive == "libseqslam_app.a":
            return "app"
        return "other"
    if is_lto_object(file):
        return None  # decided by the section name
    norm = file.replace("\\", "/")
    if "/CMakeFiles/" in "/" + norm and ".dir/" in norm:
        return "app"  # the image's own sources (firmware/app, bench/, minimal/, tests)
    return "other"


SECTION_PREFIXES = (".text.unlikely.", ".text.startup.", ".text.hot.", ".text.",
                    ".rodata.", ".srodata.", ".data.rel.ro.", ".data.", ".sdata.",
                    ".bss.", ".sbss.", ".tbss.", ".tdata.")


def symbol_of_section(name):
    for p in SECTION_PREFIXES:
        if name.startswith(p):
            sym = name[len(p):]
            sym = re.sub(r"\.str\d+\.\d+$", "", sym)
            sym = re.sub(r"\.cst\d+$", "", sym)
            return sym
    return ""


def module_of_symbol(sym):
    """Module from a (mangled) symbol name; None if the name says nothing."""
    if not sym:
        return None
    base = sym.split(".")[0] if not sym.startswith("_Z") else sym
    if base in RUNTIME_FUNCS or re.match(r"^__(u?(div|mod)di3|[al]sh[lr]di3|clz|ctz|popcount|"
                                         r"bswap|muldi3)", base):
        return "runtime"
    if base == "main":
        return "app"
    if base.startswith("seqslam_board") or base.startswith("__seqslam"):
        return "hal"
    m = re.match(r"^_ZZ?N?[KVrOR]*(\d+)(\w+)", sym)
    if not m:
        return None
    n = int(m.group(1))
    first, rest = m.group(2)[:n], m.group(2)[n:]
    if first != "seqslam":
        return None
    m2 = re.match(r"^(\d+)", rest)
    second = rest[len(m2.group(1)):len(m2.group(1)) + int(m2.group(1))] if m2 else ""
    return {"storage": "storage", "session": "session", "board": "hal", "hal": "hal",
            "app": "app"}.get(second, "core")


def column_of(section_name):
    if section_name in (".text",):
        return ".text"
    if section_name in (".rodata", ".srodata"):
        return ".rodata"
    if section_name in (".data", ".sdata"):
        return ".data"
    if section_name in (".bss", ".sbss"):
        return ".bss"
    if section_name == ".stack":
        return "stack"
    return "other"


def is_string_section(name):
    return re.search(r"(^|\.)str\d+\.\d+$", name) is not None


# ----------------------------------------------------------------------------------------
# Analysis


def analyse(elf_path, map_path, budget=None):
    sections, symbols, raw = read_elf(elf_path)
    lmap = parse_map(map_path)
    if "RAM" in lmap["regions"]:
        origin, length = lmap["regions"]["RAM"]
        region_name = "RAM"
    else:
        # No RAM region: use the region holding .text.
        text = next((o for o in lmap["outputs"] if o["name"] == ".text"), None)
        region_name, origin, length = None, 0, 0
        for name, (o, l) in lmap["regions"].items():
            if text and text["addr"] is not None and o <= text["addr"] < o + l:
                region_name, origin, length = name, o, l
        if region_name is None:
            raise BadInput(f"the link map names no RAM region: {map_path}")
    if budget is None:
        budget = length

    # Sections up to the next memory region count: an image linked with --noinhibit-exec
    # that overflows the region still gets a full report.
    upper = min([o for o, _ in lmap["regions"].values() if o > origin] + [2 ** 64])
    if upper == 2 ** 64:
        upper = origin + length

    def in_ram(addr):
        return addr is not None and origin <= addr < upper

    outs = [o for o in lmap["outputs"]
            if in_ram(o["addr"]) and o["size"] and o["name"] != "/DISCARD/"]
    outs.sort(key=lambda o: (o["addr"], o["size"]))
    elf_by_name = {s["name"]: s for s in sections if s["flags"] & 2}  # SHF_ALLOC
    for o in outs:
        s = elf_by_name.get(o["name"])
        if s is None or s["addr"] != o["addr"] or s["size"] != o["size"]:
            raise BadInput(f"the map {map_path} does not describe {elf_path} (section "
                           f"{o['name']}: map 0x{o['addr']:x}+{o['size']}, ELF "
                           + (f"0x{s['addr']:x}+{s['size']}" if s else "absent")
                           + "); relink or pass the right --map")
    for s in sections:
        if s["flags"] & 2 and s["size"] and in_ram(s["addr"]) and \
                not any(o["name"] == s["name"] for o in outs):
            raise BadInput(f"section {s['name']} of {elf_path} is not in the map {map_path}")

    table = {m: {c: 0 for c in COLUMNS + ["gaps"]} for m in MODULES}
    strings = {m: 0 for m in MODULES}
    objects = {}
    lto = False
    unattributed_lto = 0
    ranges = []  # (start, end, module, file) of input sections, for symbols
    for o in outs:
        col = column_of(o["name"])
        if o["name"] == ".stack":
            table["stack"][col] += o["size"]
            continue
        # Merged string sections may overlap their neighbour in the map (the linker lets
        # them share tails): clip each input section at the start of the next one, so every
        # byte belongs to one input section.
        items = sorted([(i["addr"], i["size"], n) for n, i in enumerate(o["inputs"])
                        if i["size"]] + [(a, z, -1) for a, z in o["fills"] if z])
        owned = {}
        for k, (addr, size, n) in enumerate(items):
            nxt = next((a for a, _, _ in items[k + 1:] if a > addr), o["addr"] + o["size"])
            if n >= 0:
                owned[n] = max(0, min(size, nxt - addr))
        content = 0
        for n, inp in enumerate(o["inputs"]):
            if not owned.get(n):
                continue
            inp = dict(inp, size=owned[n])
            module = module_of_file(inp["file"])
            if module is None:
                lto = True
                module = module_of_symbol(symbol_of_section(inp["name"]))
                if module is None:
                    module = "other"
                    unattributed_lto += inp["size"]
            table[module][col] += inp["size"]
            content += inp["size"]
            if is_string_section(inp["name"]):
                strings[module] += inp["size"]
            archive, member = split_file(inp["file"])
            key = f"{archive}({member})" if archive else member
            ob = objects.setdefault(key, {"module": module, "bytes": 0, "strings": 0,
                                          **{c: 0 for c in COLUMNS}})
            ob[col] += inp["size"]
            ob["bytes"] += inp["size"]
            if is_string_section(inp["name"]):
                ob["strings"] += inp["size"]
            ranges.append((inp["addr"], inp["addr"] + inp["size"], module, key))
        pad = o["size"] - content
        if pad < 0:
            raise BadInput(f"the map {map_path} lists more bytes in {o['name']} than the "
                           "section holds; not a map this tool understands")
        table["padding"][col] += pad
    # Gaps between the output sections in RAM (alignment of the next section).
    gaps = 0
    for prev, nxt in zip(outs, outs[1:]):
        gap = nxt["addr"] - (prev["addr"] + prev["size"])
        if gap > 0:
            gaps += gap
    table["padding"]["gaps"] = gaps
    used = (outs[-1]["addr"] + outs[-1]["size"] - origin) if outs else 0
    leading = (outs[0]["addr"] - origin) if outs else 0
    table["padding"]["gaps"] += leading

    for m in MODULES:
        table[m]["total"] = sum(table[m][c] for c in COLUMNS + ["gaps"])

    # Checks: columns against the ELF, rows against the used RAM.
    problems = []
    col_totals = {c: sum(table[m][c] for m in MODULES) for c in COLUMNS + ["gaps"]}
    elf_cols = {c: 0 for c in COLUMNS}
    for s in sections:
        if s["flags"] & 2 and in_ram(s["addr"]):
            elf_cols[column_of(s["name"])] += s["size"]
    for c in COLUMNS:
        if col_totals[c] != elf_cols[c]:
            problems.append(f"column {c}: modules add up to {col_totals[c]}, ELF sections "
                            f"to {elf_cols[c]}")
    row_sum = sum(table[m]["total"] for m in MODULES)
    if row_sum != used:
        problems.append(f"modules add up to {row_sum}, used RAM is {used}")

    # Symbols: the largest functions and objects in RAM, with their module.
    ranges.sort()
    starts = [r[0] for r in ranges]
    seen = set()
    syms = []
    for s in sorted(symbols, key=lambda s: (not s["global"], s["addr"])):
        if not in_ram(s["addr"]) or (s["addr"], s["size"]) in seen:
            continue
        seen.add((s["addr"], s["size"]))
        k = bisect.bisect_right(starts, s["addr"]) - 1
        module, obj = "other", ""
        if k >= 0 and ranges[k][0] <= s["addr"] < ranges[k][1]:
            module, obj = ranges[k][2], ranges[k][3]
        syms.append({"name": s["name"], "addr": s["addr"], "size": s["size"],
                     "kind": s["kind"], "section": s["section"], "module": module,
                     "object": obj})
    syms.sort(key=lambda s: (-s["size"], s["name"]))

    # libgcc members: size and the reference that pulled each in.
    helpers = []
    for mem in lmap["members"]:
        archive, member = split_file(mem["member"])
        if not archive.startswith("libgcc"):
            continue
        size = objects.get(f"{archive}({member})", {}).get("bytes", 0)
        ref_archive, ref_member = split_file(mem["referenced_by"]) if mem["referenced_by"] \
            else ("", "")
        helpers.append({"member": member, "bytes": size, "symbol": mem["symbol"],
                        "referenced_by": (f"{ref_archive}({ref_member})" if ref_archive
                                          else ref_member)})

    # Who calls the compiler runtime (RISC-V images): direct calls and tail calls to the
    # start of a runtime function, found by decoding each function's code.
    runtime_calls = {}
    if raw["machine"] == EM_RISCV and raw["little"]:
        runtime_funcs = {s["addr"]: s["name"] for s in syms
                         if s["module"] == "runtime" and s["kind"] == "function"}
        code_secs = [sec for sec in sections if sec["flags"] & 4 and sec["type"] == 1
                     and in_ram(sec["addr"])]
        for f in syms:
            if f["kind"] != "function":
                continue
            addr = f["addr"]
            sec = next((c for c in code_secs
                        if c["addr"] <= addr < c["addr"] + c["size"]), None)
            if sec is None:
                continue
            off = sec["offset"] + addr - sec["addr"]
            for _pc, target in riscv_call_targets(raw["data"][off:off + f["size"]], addr):
                callee = runtime_funcs.get(target)
                if callee and callee != f["name"]:
                    callers = runtime_calls.setdefault(callee, {})
                    callers[f["name"]] = callers.get(f["name"], 0) + 1

    # Discarded code/data (COMDAT duplicates and sections removed by --gc-sections).
    discarded = {m: 0 for m in MODULES}
    for name, size, file in lmap["discarded"]:
        if name.startswith((".text", ".rodata", ".data", ".bss", ".sdata", ".sbss",
                            ".srodata")) and size:
            module = module_of_file(file) or module_of_symbol(symbol_of_section(name)) \
                or "other"
            discarded[module] += size

    return {
        "elf": elf_path, "map": map_path, "region": region_name,
        "ram": {"origin": origin, "length": length, "budget": budget, "used": used,
                "free": budget - used},
        "sections": {**{o["name"]: o["size"] for o in outs}, "gaps": gaps + leading},
        "columns": {c: col_totals[c] for c in COLUMNS + ["gaps"]},
        "modules": table,
        "strings": {**strings, "total": sum(strings.values())},
        "objects": dict(sorted(objects.items(), key=lambda kv: -kv[1]["bytes"])),
        "libgcc": helpers,
        "runtime_callers": runtime_calls,
        "discarded_by_link": discarded,
        "symbols": syms,
        "lto": lto, "lto_unattributed": unattributed_lto,
        "problems": problems,
    }


# ----------------------------------------------------------------------------------------
# Output


def demangler(names):
    tool = None
    for cand in ("riscv64-unknown-elf-c++filt", "c++filt"):
        tool = shutil.which(cand)
        if tool:
            break
    if not tool or not names:
        return {n: n for n in names}
    try:
        out = subprocess.run([tool], input="\n".join(names) + "\n", capture_output=True,
                             text=True, timeout=30, check=True).stdout.splitlines()
    except (OSError, subprocess.SubprocessError):
        return {n: n for n in names}
    if len(out) != len(names):
        return {n: n for n in names}
    return dict(zip(names, out))


def strip_params(name):
    """A demangled function name without its parameter list, qualifiers and clone suffix."""
    text = re.sub(r"\s*\[clone [^\]]*\]$", "", name)
    if not text.endswith(")") and not re.search(r"\)\s*(const|volatile|&|&&)$", text):
        return text
    depth = 0
    for i in range(len(text) - 1, -1, -1):
        if text[i] == ")":
            depth += 1
        elif text[i] == "(":
            depth -= 1
            if depth == 0:
                return text[:i]
    return text


def shorten(text, width):
    return text if len(text) <= width else text[:width - 3] + "..."


def print_report(r, top, show_objects, out=sys.stdout):
    w = out.write
    ram = r["ram"]
    w(f"size report: {r['elf']}\n")
    w(f"map: {r['map']}" + ("  [LTO: ltrans sections attributed by name; "
                             f"{r['lto_unattributed']} bytes without a name -> other]"
                             if r["lto"] else "") + "\n\n")
    w(f"RAM {ram['used']} of {ram['budget']} bytes used, "
      + (f"{ram['free']} free " if ram["free"] >= 0 else f"OVER BUDGET by {-ram['free']} ")
      + f"(region {r['region']} at 0x{ram['origin']:x}, {ram['length']} bytes)\n")
    sec = r["sections"]
    parts = [f"{name} {size}" for name, size in sec.items() if name != "gaps" and size]
    w("sections: " + ", ".join(parts) + f", alignment gaps {sec['gaps']}\n\n")

    cols = [".text", ".rodata", ".data", ".bss", "stack", "other", "gaps"]
    used_cols = [c for c in cols if r["columns"][c] or c in (".text", ".rodata", ".data",
                                                                ".bss", "stack")]
    head = f"{'module':<44}" + "".join(f"{c:>8}" for c in used_cols) + f"{'total':>8}" \
        + f"{'strings':>9}\n"
    w(head)
    w("-" * (len(head) - 1) + "\n")
    for m in MODULES:
        row = r["modules"][m]
        if not row["total"]:
            continue
        w(f"{MODULE_TEXT[m]:<44}" + "".join(f"{row[c]:>8}" for c in used_cols)
          + f"{row['total']:>8}" + f"{r['strings'][m]:>9}\n")
    w("-" * (len(head) - 1) + "\n")
    w(f"{'total':<44}" + "".join(f"{r['columns'][c]:>8}" for c in used_cols)
      + f"{ram['used']:>8}" + f"{r['strings']['total']:>9}\n")
    w("(strings: string-literal bytes in .rodata, included in the .rodata column)\n\n")

    if r["libgcc"]:
        w("libgcc members linked (and the first undefined reference that pulled each in, per "
          "the map;\n the code that calls them in the image is listed below):\n")
        for h in r["libgcc"]:
            w(f"  {h['member']:<14}{h['bytes']:>6}  {h['symbol']:<10} <- {h['referenced_by']}\n")
        w("\n")

    if r["runtime_callers"]:
        calls = r["runtime_callers"]
        names = demangler(sorted({c for cs in calls.values() for c in cs}))
        # The save/restore helpers are one family: list it as one line.
        grouped = {}
        for callee, cs in calls.items():
            key = "__riscv_save_N/__riscv_restore_N" \
                if re.match(r"^__riscv_(save|restore)_\d+$", callee) else callee
            g = grouped.setdefault(key, {})
            for c, n in cs.items():
                g[c] = g.get(c, 0) + n
        w("calls into the compiler runtime (direct and tail calls found in the code):\n")
        for callee in sorted(grouped, key=lambda c: (-len(grouped[c]), c)):
            cs = sorted(grouped[callee].items(), key=lambda kv: (-kv[1], kv[0]))
            shown = ", ".join(f"{shorten(strip_params(names[c]), 50)} ({n})"
                              for c, n in cs[:5])
            more = f", +{len(cs) - 5} more" if len(cs) > 5 else ""
            w(f"  {callee} <- {len(cs)} function(s): {shown}{more}\n")
        w("\n")

    if show_objects:
        w(f"{'object':<56}{'module':<9}{'.text':>7}{'.rodata':>8}{'.data':>7}{'.bss':>7}"
          f"{'strings':>8}\n")
        for name, ob in r["objects"].items():
            w(f"{shorten(name, 55):<56}{ob['module']:<9}{ob['.text']:>7}{ob['.rodata']:>8}"
              f"{ob['.data']:>7}{ob['.bss']:>7}{ob['strings']:>8}\n")
        w("\n")

    syms = r["symbols"][:top]
    names = demangler([s["name"] for s in syms])
    w(f"largest {len(syms)} symbols:\n")
    for s in syms:
        w(f"  {s['size']:>6}  {s['section']:<8} {s['module']:<8} "
          f"{shorten(names[s['name']], 90)}\n")
    if r["problems"]:
        w("\nINCONSISTENT: " + "; ".join(r["problems"]) + "\n")


def to_json(r, top):
    syms = r["symbols"][:top]
    names = demangler([s["name"] for s in syms])
    doc = dict(r)
    doc["symbols"] = [{**s, "demangled": names[s["name"]]} for s in syms]
    doc["module_names"] = MODULE_TEXT
    return doc


# ----------------------------------------------------------------------------------------
# Self-test

SELFTEST_MAP = """\
Archive member included to satisfy reference by file (symbol)

lib/libgcc.a(_udivdi3.o)
                              ../src/libseqslam.a(a.cpp.obj) (__udivdi3)
../hal/board/qemu_virt/libseqslam_board.a(crt0.S.obj)
                              (_start)

Discarded input sections

 .text._ZN7seqslam4deadEv
                0x00000000       0x10 ../src/libseqslam.a(a.cpp.obj)

Memory Configuration

Name             Origin             Length             Attributes
RAM              0x80000000         0x00000400         xrw
*default*        0x00000000         0xffffffff

Linker script and memory map

LOAD x.obj
                0x00000100                        __stack_size = 0x100

.text           0x80000000       0x80
 *(.text.init)
 .text.init     0x80000000       0x10 ../hal/board/qemu_virt/libseqslam_board.a(crt0.S.obj)
                0x80000000                _start
 .text._ZN7seqslam7storage6Volume5mountERNS_3hal11BlockDeviceE
                0x80000010       0x20 ../storage/libseqslam_storage.a(volume.cpp.obj)
                0x80000010                seqslam::storage::Volume::mount()
 *fill*         0x80000030        0x2 
 .text.startup.main
                0x80000032       0x1e CMakeFiles/seqslam_fw_app.dir/app/main_board.cpp.obj
 .text._ZN7seqslam3fooEv
                0x80000050       0x10 /tmp/ccXYZ.ltrans0.ltrans.o
 .text          0x80000060       0x1c lib/libgcc.a(_udivdi3.o)
 .text.memcpy   0x8000007c        0x4 ../hal/board/qemu_virt/libseqslam_board.a(runtime.cpp.obj)

.rodata         0x80000080       0x28
 .rodata._ZN7seqslam3fooEv.str1.4
                0x80000080        0x9 /tmp/ccXYZ.ltrans0.ltrans.o
                                  0xc (size before relaxing)
 *fill*         0x80000089        0x3 
 .rodata.str1.4
                0x8000008c        0xa ../src/libseqslam.a(a.cpp.obj)
 .rodata.CSWTCH.3
                0x80000096        0x8 /tmp/ccXYZ.ltrans0.ltrans.o
 .rodata.str1.4
                0x8000009e        0x2 lib/libgcc.a(_udivdi3.o)

.data           0x800000a8        0x10
 .data._ZN12_GLOBAL__N_15g_appE
                0x800000a8        0xc CMakeFiles/seqslam_fw_app.dir/app/main_board.cpp.obj

.bss            0x800000b8        0x8
 .bss.x         0x800000b8        0x8 ../src/libseqslam.a(a.cpp.obj)

.stack          0x800000c0      0x120
 *fill*         0x800000c0       0x20 
 *fill*         0x800000e0      0x100 

.comment        0x00000000       0x26
 .comment       0x00000000       0x26 x.obj
OUTPUT(x.elf elf32-littleriscv)
"""


def write_test_elf(path, sections, symbols):
    """A minimal little-endian ELF32 with the given (name, type, addr, size) sections and
    (name, addr, size, section index, is_function) symbols."""
    names = b"\0" + b"".join(n.encode() + b"\0" for n, *_ in sections) + \
        b".symtab\0.strtab\0.shstrtab\0"

    def name_off(n):
        return names.index(b"\0" + n.encode() + b"\0") + 1

    strtab = b"\0" + b"".join(s[0].encode() + b"\0" for s in symbols)
    symtab = b"\0" * 16
    off = 1
    for name, addr, size, shndx, func in symbols:
        symtab += struct.pack("<IIIBBH", off, addr, size, (1 << 4) | (2 if func else 1), 0,
                              shndx)
        off += len(name) + 1
    body = symtab + strtab + names
    shoff = 52 + len(body)
    shoff += (-shoff) % 4
    heads = [struct.pack("<10I", *([0] * 10))]
    for n, stype, addr, size in sections:
        flags = 2 | (4 if n == ".text" else 1)
        heads.append(struct.pack("<10I", name_off(n), stype, flags, addr, 52, size, 0, 0,
                                 4, 0))
    nsec = len(sections) + 1
    heads.append(struct.pack("<10I", name_off(".symtab"), 2, 0, 0, 52, len(symtab),
                             nsec + 1, 1, 4, 16))
    heads.append(struct.pack("<10I", name_off(".strtab"), 3, 0, 0, 52 + len(symtab),
                             len(strtab), 0, 0, 1, 0))
    heads.append(struct.pack("<10I", name_off(".shstrtab"), 3, 0, 0,
                             52 + len(symtab) + len(strtab), len(names), 0, 0, 1, 0))
    header = b"\x7fELF\x01\x01\x01" + b"\0" * 9 + struct.pack(
        "<HHIIIIIHHHHHH", 2, 0xF3, 1, 0x80000000, 0, shoff, 0, 52, 0, 0, 40, len(heads),
        len(heads) - 1)
    with open(path, "wb") as f:
        f.write(header + body + b"\0" * (shoff - 52 - len(body)) + b"".join(heads))


def self_test(elfs):
    failures = []

    def expect(what, got, want):
        if got != want:
            failures.append(f"{what}: got {got!r}, want {want!r}")

    # Name-based attribution (LTO objects).
    expect("storage symbol", module_of_symbol("_ZN7seqslam7storage6Volume5mountEv"), "storage")
    expect("const member", module_of_symbol("_ZNK7seqslam5board3fooEv"), "hal")
    expect("local static", module_of_symbol("_ZZN7seqslam3app1fEvE1x"), "app")
    expect("core template", module_of_symbol("_ZN7seqslam10narrow_satIiEET_v"), "core")
    expect("memcpy", module_of_symbol("memcpy"), "runtime")
    expect("clone", module_of_symbol("_ZN7seqslam3fooEv.isra.0"), "core")
    expect("switch table", module_of_symbol("CSWTCH.3"), None)
    expect("section symbol", symbol_of_section(".rodata._ZN7seqslam3fooEv.str1.4"),
           "_ZN7seqslam3fooEv")
    expect("file module", module_of_file("../src/libseqslam.a(x.cpp.obj)"), "core")
    expect("session file", module_of_file("../session/libseqslam_session.a(s.cpp.obj)"),
           "session")
    expect("runtime member",
           module_of_file("../hal/board/qemu_virt/libseqslam_board.a(runtime.cpp.obj)"),
           "runtime")
    expect("strings", [is_string_section(s) for s in
                       (".rodata.str1.4", ".rodata._ZN1fEv.str1.1", ".rodata.CSWTCH.2")],
           [True, True, False])

    # RISC-V call decoding: jal, c.j, c.jal, auipc+jalr, a tail jump (assembled with GNU as).
    code = bytes.fromhex("ef00800031a0ed3f17030000e700c30001006ff0fffe")
    expect("riscv calls", riscv_call_targets(code, 0),
           [(0, 8), (4, 0x10), (6, 0), (8, 0x14), (0x12, 0)])
    expect("strip parameters", strip_params("ns::(anonymous namespace)::f(int, g(h)) const "
                                            "[clone .isra.0]"), "ns::(anonymous namespace)::f")

    tmp = tempfile.mkdtemp(prefix="size-report-test-")
    try:
        # A synthetic image and its map: every number below is known.
        elf = os.path.join(tmp, "x.elf")
        write_test_elf(elf, [(".text", 1, 0x80000000, 0x80), (".rodata", 1, 0x80000080, 0x28),
                             (".data", 1, 0x800000a8, 0x10), (".bss", 8, 0x800000b8, 0x8),
                             (".stack", 8, 0x800000c0, 0x120)],
                       [("main", 0x80000032, 0x1e, 1, True),
                        ("_ZN7seqslam3fooEv", 0x80000050, 0x10, 1, True),
                        ("g_app", 0x800000a8, 0xc, 3, False)])
        with open(elf + ".map", "w") as f:
            f.write(SELFTEST_MAP)
        r = analyse(elf, elf + ".map")
        expect("problems", r["problems"], [])
        expect("used", r["ram"]["used"], 0x1e0)
        expect("budget", r["ram"]["budget"], 0x400)
        mods = r["modules"]
        expect("hal text", mods["hal"][".text"], 0x10)
        expect("storage text", mods["storage"][".text"], 0x20)
        expect("app text", mods["app"][".text"], 0x1e)
        expect("core text (LTO by name)", mods["core"][".text"], 0x10)
        expect("runtime text", mods["runtime"][".text"], 0x1c + 4)
        expect("padding text", mods["padding"][".text"], 2)
        expect("core rodata", mods["core"][".rodata"], 9 + 0xa)
        expect("other rodata (CSWTCH)", mods["other"][".rodata"], 8)
        expect("padding rodata", mods["padding"][".rodata"], 0x28 - 9 - 0xa - 8 - 2)
        expect("padding data", mods["padding"][".data"], 4)
        expect("stack", mods["stack"]["stack"], 0x120)
        expect("strings core", r["strings"]["core"], 9 + 0xa)
        expect("strings runtime", r["strings"]["runtime"], 2)
        expect("lto", r["lto"], True)
        expect("largest symbol", r["symbols"][0]["name"], "main")
        expect("symbol module", [(s["name"], s["module"]) for s in r["symbols"]],
               [("main", "app"), ("_ZN7seqslam3fooEv", "core"), ("g_app", "app")])
        expect("libgcc", [(h["member"], h["bytes"], h["symbol"]) for h in r["libgcc"]],
               [("_udivdi3.o", 0x1e, "__udivdi3")])
        expect("discarded", r["discarded_by_link"]["core"], 0x10)

        # Bad input: exit status 2 and a message naming the problem.
        me = os.path.abspath(__file__)
        text = os.path.join(tmp, "notelf.elf")
        with open(text, "w") as f:
            f.write("hello\n")
        nomap = os.path.join(tmp, "nomap.elf")
        shutil.copy(elf, nomap)
        stale = os.path.join(tmp, "stale.elf")
        shutil.copy(elf, stale)
        with open(stale + ".map", "w") as f:
            f.write(SELFTEST_MAP.replace(".data           0x800000a8        0x10",
                                         ".data           0x800000a8        0x14"))
        garbage = os.path.join(tmp, "garbage.elf")
        shutil.copy(elf, garbage)
        with open(garbage + ".map", "w") as f:
            f.write("this is no map\n")
        for args, needle in (([os.path.join(tmp, "missing.elf")], "no such file"),
                             ([text], "not an ELF"),
                             ([nomap], "no linker map"),
                             ([stale], "does not describe"),
                             ([garbage], "not a GNU ld link map"),
                             ([elf, "--map", os.path.join(tmp, "none.map")], "no such map")):
            p = subprocess.run([sys.executable, me] + args, capture_output=True, text=True)
            expect(f"status for {needle}", p.returncode, 2)
            if needle not in p.stderr:
                failures.append(f"message for {needle}: {p.stderr.strip()!r}")
        p = subprocess.run([sys.executable, me, elf, "--json", os.path.join(tmp, "r.json")],
                           capture_output=True, text=True)
        expect("status of a good run", p.returncode, 0)
        with open(os.path.join(tmp, "r.json")) as f:
            expect("json used", json.load(f)["ram"]["used"], 0x1e0)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)

    # Real images: the sums must close.
    for e in elfs:
        try:
            r = analyse(e, e + ".map")
        except BadInput as ex:
            failures.append(f"{e}: {ex}")
            continue
        if r["problems"]:
            failures.append(f"{e}: " + "; ".join(r["problems"]))
        else:
            print(f"size-report self-test: {e}: {r['ram']['used']} bytes, modules and "
                  "sections add up")
    for f in failures:
        print(f"size-report self-test: FAIL: {f}")
    print(f"size-report self-test: {'FAIL' if failures else 'PASS'}")
    return 1 if failures else 0


# ----------------------------------------------------------------------------------------


def main(argv):
    ap = argparse.ArgumentParser(
        description="Bytes per section, module and symbol of a target image (ELF + ld map).")
    ap.add_argument("elf", nargs="*", help="the image (IMAGE.elf; its map IMAGE.elf.map)")
    ap.add_argument("--map", help="the linker map (default: ELF path + .map)")
    ap.add_argument("--json", metavar="FILE", help="also write the report as JSON")
    ap.add_argument("--top", type=int, default=20, help="largest symbols to list (20)")
    ap.add_argument("--objects", action="store_true", help="also list every object file")
    ap.add_argument("--budget", type=int,
                    help="RAM budget in bytes (default: the map's RAM region, 65456)")
    ap.add_argument("--self-test", action="store_true",
                    help="test the tool (synthetic image, bad input), then check that the "
                         "sums close for any images given")
    args = ap.parse_args(argv)
    if args.self_test:
        return self_test(args.elf)
    if len(args.elf) != 1:
        ap.print_usage(sys.stderr)
        print("size-report: give exactly one ELF image", file=sys.stderr)
        return 2
    elf = args.elf[0]
    map_path = args.map or elf + ".map"
    try:
        if not os.path.exists(elf):
            raise BadInput(f"no such file: {elf}")
        read_elf(elf)  # the ELF first: "not an ELF" before "no map"
        if not args.map and not os.path.exists(map_path):
            raise BadInput(f"no linker map for {elf}: expected {map_path} (link with "
                           f"-Wl,-Map={map_path}, as seqslam_target_executable does, or "
                           "pass --map FILE)")
        r = analyse(elf, map_path, args.budget)
    except BadInput as e:
        print(f"size-report: {e}", file=sys.stderr)
        return 2
    print_report(r, args.top, args.objects)
    if args.json:
        try:
            with open(args.json, "w") as f:
                json.dump(to_json(r, args.top), f, indent=1)
                f.write("\n")
        except OSError as e:
            print(f"size-report: cannot write {args.json}: {e.strerror}", file=sys.stderr)
            return 2
    return 1 if r["problems"] else 0


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv[1:]))
    except BrokenPipeError:  # e.g. piped into head
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        sys.exit(0)
