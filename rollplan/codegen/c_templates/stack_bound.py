#!/usr/bin/env python3
"""Worst-case stack depth of a Cortex-M ELF from its disassembly.

    stack_bound.py [--objdump TOOL] [--su DIR]... ELF ROOT [ROOT...]

For every function of the linked ELF (ours and newlib's/libm's alike, so the
library calls are covered too) its frame is the SUM of every stack-pointer
decrement in its body: push/stmdb sp!/vpush/vstmdb sp!, sub sp #imm,
str/strd/vstr with pre-decrement writeback [sp, #-n]!. Summing all of them
(instead of following one path) over-estimates a function that pushes on two
different paths, so the frame is an upper bound. Calls are the direct
``bl``/``blx <label>`` and tail calls (``b``/``b.w`` to another function's
entry). The bound of a root is its frame plus the largest bound among its
callees, the maximum over the call tree. The tool refuses (exit 1) if the tree
reachable from a root contains recursion (a cycle), an indirect call (blx/bx
to a register other than lr, ldr pc) or a dynamic stack adjustment (sub sp, rN;
mov sp, rN; alloca/VLA), since then no static bound exists; each refusal names
the function.

With --su DIR, the frames that GCC reported in -fstack-usage files (*.su) are
compared with the disassembly frames of the same functions (a cross-check of
this parser; a difference is printed, the larger value is used).

Hardware exception entry is not included: an interrupt taken while the root runs
stacks 32 bytes, 104 with the FPU context, plus its handler's own bound.
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
from pathlib import Path

HEADER = re.compile(r"^([0-9a-f]+) <([^>]+)>:$")
INSN = re.compile(r"^\s*([0-9a-f]+):\s+(\S+)\s*(.*)$")
REGLIST = re.compile(r"\{([^}]*)\}")
IMM = re.compile(r"#(-?\d+)")
DYNAMIC_SP = re.compile(r"sp,\s*(sp,\s*)?r\d|sp,\s*(sp,\s*)?(ip|fp|sl|lr)")


def reg_count(body: str) -> tuple[int, int]:
    """(core registers, bytes of FP registers) in a register list."""
    m = REGLIST.search(body)
    if not m:
        return 0, 0
    core, fp = 0, 0
    for part in m.group(1).split(","):
        part = part.strip()
        rng = re.fullmatch(r"([sd])(\d+)-[sd](\d+)", part)
        if rng:
            n = int(rng.group(3)) - int(rng.group(2)) + 1
            fp += n * (8 if rng.group(1) == "d" else 4)
        elif re.fullmatch(r"d\d+", part):
            fp += 8
        elif re.fullmatch(r"s\d+", part):
            fp += 4
        elif part:
            core += 1
    return core, fp


def parse(elf: Path, objdump: str):
    text = subprocess.run([objdump, "-d", "--no-show-raw-insn", str(elf)], check=True,
                          capture_output=True, text=True).stdout
    funcs, entry = {}, {}
    cur = None
    for line in text.splitlines():
        h = HEADER.match(line)
        if h:
            cur = h.group(2)
            funcs[cur] = {"frame": 0, "calls": set(), "problems": [], "addr": int(h.group(1), 16)}
            entry[int(h.group(1), 16)] = cur
            continue
        if cur is None:
            continue
        m = INSN.match(line)
        if not m:
            continue
        op, args = m.group(2), m.group(3).split("@")[0].strip()
        f = funcs[cur]
        base = op.split(".")[0]
        if base == "push" or (base in ("stmdb", "stmfd") and args.startswith("sp!")):
            core, fp = reg_count(args)
            f["frame"] += 4 * core + fp
        elif base in ("vpush",) or (base in ("vstmdb",) and args.startswith("sp!")):
            f["frame"] += sum(reg_count(args))
        elif base in ("sub", "subw") and re.match(r"sp,\s*(sp,\s*)?#", args):
            f["frame"] += int(IMM.search(args).group(1))
        elif base in ("sub", "subw", "mov", "add") and re.match(DYNAMIC_SP, args):
            f["problems"].append(f"dynamic stack adjustment '{op} {args}'")
        elif base in ("str", "strd", "vstr", "strb", "strh") and re.search(r"\[sp,\s*#-(\d+)\]!", args):
            f["frame"] += int(re.search(r"\[sp,\s*#-(\d+)\]!", args).group(1))
        elif base in ("bl", "blx") and "<" in args:
            target = re.search(r"<([^>+]+)(\+0x[0-9a-f]+)?>", args)
            if target and not target.group(2):
                f["calls"].add(target.group(1))
            elif target:
                f["problems"].append(f"call into the middle of {target.group(0)}")
        elif base == "blx" or (base == "bx" and args != "lr") or (base == "mov" and args.startswith("pc,")) \
                or (base == "ldr" and args.startswith("pc,") and not args.startswith("pc, [sp]")):
            f["problems"].append(f"indirect call/jump '{op} {args}'")
        elif base == "b" and "<" in args:
            target = re.search(r"<([^>+]+)(\+0x[0-9a-f]+)?>", args)
            if target and not target.group(2) and target.group(1) != cur:
                f["calls"].add(target.group(1))   # tail call
    return funcs


def read_su(dirs) -> dict:
    su = {}
    for d in dirs:
        for p in Path(d).glob("*.su"):
            for line in p.read_text().splitlines():
                loc, size, kind = line.split("\t")
                name = loc.rsplit(":", 1)[-1]
                su[name] = (int(size), kind)
    return su


def su_name(elf_name: str) -> str:
    """GCC's .su name of an ELF symbol: 'f.constprop.0' -> 'f.constprop'."""
    return re.sub(r"\.\d+$", "", elf_name)


def bound(funcs, root, su_frames):
    memo, stack, problems = {}, [], []

    def frame(name):
        f = funcs[name]["frame"]
        s = su_frames.get(su_name(name))
        return max(f, s[0]) if s else f

    def visit(name):
        if name in memo:
            return memo[name]
        if name in stack:
            problems.append(f"recursion: {' -> '.join(stack[stack.index(name):] + [name])}")
            return 0, [name]
        if name not in funcs:
            problems.append(f"unknown function {name}")
            return 0, [name]
        stack.append(name)
        for p in funcs[name]["problems"]:
            problems.append(f"{name}: {p}")
        best, path = 0, []
        for callee in sorted(funcs[name]["calls"]):
            d, pth = visit(callee)
            if d > best:
                best, path = d, pth
        stack.pop()
        memo[name] = (frame(name) + best, [name] + path)
        return memo[name]

    depth, path = visit(root)
    return depth, path, problems, frame


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objdump", default="arm-none-eabi-objdump")
    ap.add_argument("--su", action="append", default=[], help="folder of GCC -fstack-usage .su files")
    ap.add_argument("elf", type=Path)
    ap.add_argument("roots", nargs="+")
    args = ap.parse_args(argv)
    funcs = parse(args.elf, args.objdump)
    su = read_su(args.su)
    compared = 0
    for name, (_size, kind) in sorted(su.items()):
        if kind != "static":
            print(f"stack_bound: {name}: GCC reports a {kind} frame (no static bound)", file=sys.stderr)
    for elf_name, f in sorted(funcs.items()):
        if su_name(elf_name) in su:
            compared += 1
            size = su[su_name(elf_name)][0]
            if f["frame"] != size:
                print(f"stack_bound: note: {elf_name}: -fstack-usage {size} B, disassembly {f['frame']} B",
                      file=sys.stderr)
    if args.su:
        print(f"stack_bound: {compared} functions with -fstack-usage frames compared with the disassembly",
              file=sys.stderr)
    status = 0
    for root in args.roots:
        depth, path, problems, frame = bound(funcs, root, su)
        if problems:
            status = 1
            for p in sorted(set(problems)):
                print(f"stack_bound: {root}: no static bound: {p}", file=sys.stderr)
            continue
        chain = " -> ".join(f"{n}({frame(n)})" for n in path)
        print(f"{root}: {depth} bytes  [{chain}]")
    return status


if __name__ == "__main__":
    raise SystemExit(main())
