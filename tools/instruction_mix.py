#!/usr/bin/env python3
"""Instructions per particle-step of one kernel, by kind, from a callgrind profile with per-instruction counts.

Profile a run with `valgrind --tool=callgrind --dump-instr=yes --callgrind-out-file=cg.out build/tools/mpm run ...`,
then give the binary, the profile, a substring of the kernel's function name (the AVX2 copy's `run_avx2_fma<...>`
wrappers hold the inlined kernels) and the number of particle-steps the run made. Example (docs/PERFORMANCE.md):

  python3 tools/instruction_mix.py build/tools/mpm cg.out 'gather<mpm::GatherFields{true, true, true}>' 320000

--stack adds the moves to and from the stack frame (register spills, locals), counted within the kinds above.
"""
import argparse
import collections
import re
import subprocess


def counts_by_address(profile, function):
    """Self cost (instructions executed) per instruction address of the functions whose name contains `function`."""
    names, current, address, skip_call_cost = {}, None, 0, False
    counts = collections.Counter()

    def position(token, previous):  # callgrind's compressed positions: absolute, +relative, -relative or '*'
        if token == "*":
            return previous
        if token[0] in "+-":
            step = int(token[1:], 16) if token[1:].startswith("0x") else int(token[1:])
            return previous + step if token[0] == "+" else previous - step
        return int(token, 16) if token.startswith("0x") else int(token)

    with open(profile) as f:
        for line in f:
            line = line.rstrip("\n")
            m = re.match(r"c?fn=\((\d+)\)(?: (.*))?", line)
            if m:
                if m.group(2):
                    names[m.group(1)] = m.group(2)
                if line.startswith("fn="):
                    current = names.get(m.group(1))
                continue
            if line.startswith("calls="):
                skip_call_cost = True  # the next cost line is the callee's inclusive cost
                continue
            if not line or line[0] not in "0123456789+-*":
                continue
            fields = line.split()
            address = position(fields[0], address)
            if skip_call_cost:
                skip_call_cost = False
                continue
            if current and function in current and "run_avx2_fma" in current:
                counts[address] += int(fields[-1])
    return counts


def kind(mnemonic):
    if mnemonic.startswith("j") or mnemonic in ("call", "ret"):
        return "branches"
    if re.match(r"v(fn?m(add|sub)\d+|add|sub|mul|div|max|min|and|andn|or|xor|cmp|sqrt|blendv|round)pd", mnemonic):
        return "FP arithmetic, packed"
    if re.match(r"v(fn?m(add|sub)\d+|add|sub|mul|div|max|min|sqrt|round)sd|v(u?comisd|cvtsi2sd|cvttsd2si)", mnemonic):
        return "FP arithmetic, scalar"
    if re.match(r"v(mov|broadcast|unpck|perm|shuf|insert|extract|punpck)", mnemonic):
        return "vector moves, loads, stores, shuffles"
    return "integer: addresses, indices, loop control"


def stack_traffic(mnemonic, operands):
    """'stack store' or 'stack load' for a move to or from the frame (%rsp or %rbp based: spills, locals), else None."""
    if not re.match(r"v?mov", mnemonic) or "(%rsp)" not in operands and "(%rbp)" not in operands:
        return None
    return "stack store" if re.search(r"\(%r[sb]p\)$", operands) else "stack load"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("binary")
    ap.add_argument("profile")
    ap.add_argument("function", help="substring of the kernel's function name")
    ap.add_argument("particle_steps", type=float)
    ap.add_argument("--stack", action="store_true",
                    help="also count the moves to and from the stack frame (register spills and locals)")
    args = ap.parse_args()
    counts = counts_by_address(args.profile, args.function)
    if not counts:
        raise SystemExit(f"instruction_mix.py: no AVX2-copy function matching {args.function!r} in {args.profile}")
    listing = subprocess.run(["objdump", "-d", "--no-show-raw-insn", f"--start-address={min(counts):#x}",
                              f"--stop-address={max(counts) + 16:#x}", args.binary],
                             check=True, capture_output=True, text=True).stdout
    by_kind, by_stack = collections.Counter(), collections.Counter()
    for line in listing.splitlines():
        address, sep, instruction = line.strip().partition(":")
        if not sep or not instruction.split():
            continue
        try:
            executed = counts.get(int(address, 16), 0) / args.particle_steps
        except ValueError:
            continue
        mnemonic, _, operands = instruction.strip().partition(" ")
        by_kind[kind(mnemonic)] += executed
        if args.stack and (traffic := stack_traffic(mnemonic, operands.strip())):
            by_stack[traffic] += executed
    print(f"{args.function}: {sum(by_kind.values()):.0f} instructions per particle-step")
    for name, value in by_kind.most_common():
        print(f"  {name:45s}{value:7.1f}")
    for name, value in sorted(by_stack.items()):
        print(f"  {'of all kinds, ' + name + 's':45s}{value:7.1f}")


if __name__ == "__main__":
    main()
