#!/usr/bin/env python3
"""Instruction mix of the hot loops in an object file (docs/bench.md, "Looking inside the step").

Finds every loop (a backward conditional jump) of at least --min instructions
in the functions whose name contains --function, and counts its instructions
by kind: vector shuffles (with a folded load or store), floating-point
arithmetic, loads, stores, integer and mask work. On a machine without
hardware counters this is how one sees what a loop spends its issue slots
on; compare the counts with scripts/simd_throughput.cpp's rates.

    python3 scripts/loop_mix.py build/core/CMakeFiles/organsim_core.dir/sim/cpu_kernel_simd.cpp.o --function N_AVX3
"""
import argparse
import collections
import re
import subprocess

SHUFFLES = ("vunpck", "vshuf", "vperm", "vinsert", "vextract", "valign", "vblend", "vbroadcastf", "vpshufb")
ARITH = ("fmadd", "fmsub", "fnmadd", "fnmsub", "mul", "add", "sub", "rsqrt", "div", "max", "min", "sqrt")


def kind(op, args):
    if op.startswith("j"):
        return "branch"
    memory = "(" in args
    store = memory and args.rstrip().endswith(")")  # AT&T: the destination is last
    if op.startswith(SHUFFLES):
        return "shuffle" + ("+store" if store else "+load" if memory else "")
    if op.startswith("v") and any(a in op for a in ARITH):
        return "fp" + ("+load" if memory else "")
    if op.startswith(("vcmp", "vpcmp", "k")):
        return "mask"
    if memory:
        return "store" if store else "load"
    return "move" if op.startswith("vmov") else "int"


def functions(obj):
    text = subprocess.run(["objdump", "-d", "--no-show-raw-insn", "-C", obj], check=True, capture_output=True,
                          text=True).stdout
    name, out = None, collections.OrderedDict()
    for line in text.splitlines():
        m = re.match(r"^[0-9a-f]+ <(.*)>:$", line)
        if m:
            name = m.group(1)
            out[name] = []
            continue
        m = re.match(r"^\s+([0-9a-f]+):\s+(\S+)\s*(.*)$", line)
        if m and name:
            out[name].append((int(m.group(1), 16), m.group(2), m.group(3)))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("object")
    ap.add_argument("--function", default="", help="only functions whose name contains this")
    ap.add_argument("--min", type=int, default=60, help="smallest loop reported, instructions")
    args = ap.parse_args()
    seen = set()
    for name, ins in functions(args.object).items():
        if args.function not in name:
            continue
        index = {a: i for i, (a, _, _) in enumerate(ins)}
        for i, (a, op, operands) in enumerate(ins):
            m = re.match(r"([0-9a-f]+)", operands)
            if not (op.startswith("j") and op != "jmp" and m):
                continue
            target = int(m.group(1), 16)
            if target >= a or target not in index or i - index[target] + 1 < args.min:
                continue
            body = ins[index[target]:i + 1]
            mix = collections.Counter(kind(o, x) for _, o, x in body)
            line = f"{len(body):4d} instructions  " + "  ".join(f"{k} {v}" for k, v in sorted(mix.items()))
            if (name, line) not in seen:
                seen.add((name, line))
                print(f"{name[:100]}\n    {line}")


if __name__ == "__main__":
    main()
