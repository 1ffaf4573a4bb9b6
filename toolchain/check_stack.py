#!/usr/bin/env python3
"""Worst-case stack of firmware entry points, from GCC's call graphs (-fcallgraph-info=su).

  check_stack.py --budget BYTES [--entry SYMBOL]... [--entries-from ARCHIVE --nm NM]
                 [--wrap SYMBOL]... CI...

Reads the CI files (one per object file: functions, their own frame size, and their calls), then prints for each entry point the deepest path's total and fails when it
is over the budget, or when it cannot be bounded: recursion, an indirect call, a dynamic frame
(alloca, VLA) or a call to a function with no known frame. Entry points are the SYMBOLs given,
plus every global function that ARCHIVE defines (the public functions of a library). --wrap
follows the linker's option of that name: a call to SYMBOL reaches __wrap_SYMBOL, a call to
__real_SYMBOL reaches SYMBOL.
"""
import argparse
import pathlib
import re
import subprocess
import sys

NODE = re.compile(r'node: \{ title: "([^"]+)" label: "([^"]*)"')
EDGE = re.compile(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"')
FRAME = re.compile(r'\\n(\d+) bytes \(([a-z,]+)\)')

# Run-time library routines (libgcc, newlib-nano) that are compiled without call-graph info,
# with a bound on their stack including their own callees. Read off the disassembly of Debian's
# thumb/v7e-m+fp/hard multilib: the deepest is __aeabi_ldivmod (16 bytes) calling __udivmoddi4
# (32 bytes); memset, memmove and memcmp push at most 16 bytes, memcpy and strlen none.
RUNTIME_LEAF_BYTES = 64
RUNTIME_LEAVES = re.compile(
    r"^(__aeabi_\w+|__udivmoddi4|__divdi3|__udivdi3|__moddi3|__umoddi3|__clzdi2|__ctzdi2|"
    r"mem(cpy|move|set|cmp)|str(len|cmp|ncmp))$")


class Graph:
    def __init__(self):
        self.frame = {}   # symbol -> (bytes, qualifier)
        self.label = {}
        self.calls = {}   # symbol -> set of callees
        self.comdat = {}  # plain symbol -> titles "FILE:SYMBOL" of its copies

    def wrap(self, symbol):
        """Redirects the calls as the linker's --wrap=symbol does."""
        real, wrapper = "__real_" + symbol, "__wrap_" + symbol
        for callees in self.calls.values():
            if symbol in callees:
                callees.discard(symbol)
                callees.add(wrapper)
            if real in callees:
                callees.discard(real)
                callees.add(symbol)

    def read(self, path):
        for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
            m = NODE.search(line)
            if m:
                title, label = m.groups()
                f = FRAME.search(label)
                if f:
                    self.frame[title] = (int(f.group(1)), f.group(2))
                    self.label[title] = label.split("\\n")[0]
                    if ":" in title:
                        self.comdat.setdefault(title.rsplit(":", 1)[1], set()).add(title)
                continue
            m = EDGE.search(line)
            if m:
                self.calls.setdefault(m.group(1), set()).add(m.group(2))

    def worst(self, symbol, stack=()):
        """(bytes, path) of the deepest call chain from symbol; raises ValueError if unbounded."""
        if symbol in stack:
            raise ValueError("recursion: " + " -> ".join(stack + (symbol,)))
        if symbol == "__indirect_call":
            raise ValueError("indirect call from " + stack[-1])
        if symbol not in self.frame:
            # A complete-object constructor or destructor (C1, D1) that GCC emitted as an alias of
            # the base-object one (C2, D2): the call graph has a node only for the latter.
            alias = re.sub(r"([CD])1(E|I)", r"\g<1>2\2", symbol, count=1)
            if alias != symbol and (alias in self.frame or alias in self.comdat):
                return self.worst(alias, stack)
        if symbol not in self.frame and symbol in self.comdat:
            # An inline or template function that GCC emitted out of line (a weak, COMDAT
            # symbol): the call graphs title each copy "FILE:SYMBOL". The linker keeps one of
            # them, so the worst copy bounds it.
            return max((self.worst(title, stack) for title in sorted(self.comdat[symbol])), key=lambda r: r[0])
        if symbol not in self.frame:
            if RUNTIME_LEAVES.match(symbol):
                return RUNTIME_LEAF_BYTES, [symbol]
            raise ValueError(f"no frame size for {symbol} (called from {stack[-1] if stack else 'nobody'})")
        own, qualifier = self.frame[symbol]
        if qualifier == "dynamic":
            raise ValueError(f"unbounded dynamic frame in {self.label[symbol]}")
        deepest, path = 0, []
        for callee in sorted(self.calls.get(symbol, ())):
            total, sub = self.worst(callee, stack + (symbol,))
            if total > deepest:
                deepest, path = total, sub
        return own + deepest, [symbol] + path


def archive_globals(nm, archive):
    out = subprocess.run([nm, "--defined-only", "-g", archive], check=True, capture_output=True, text=True).stdout
    return sorted({parts[2] for parts in (l.split() for l in out.splitlines())
                   if len(parts) == 3 and parts[1] in "TW"})


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--budget", type=int, required=True, help="bytes allowed per entry point")
    ap.add_argument("--entry", action="append", default=[], help="an entry-point symbol")
    ap.add_argument("--entries-from", help="a static library whose global functions are entry points")
    ap.add_argument("--nm", default="arm-none-eabi-nm")
    ap.add_argument("--name", default="", help="what the report is about")
    ap.add_argument("--wrap", action="append", default=[], help="a symbol the link --wrap's")
    ap.add_argument("callgraphs", nargs="+", type=pathlib.Path, help=".ci files")
    args = ap.parse_args()

    graph = Graph()
    for p in args.callgraphs:
        if not p.is_file():
            sys.exit(f"check_stack: missing call graph {p} (is -fcallgraph-info=su on for its target?)")
        graph.read(p)
    for symbol in args.wrap:
        graph.wrap(symbol)
    entries = list(args.entry)
    if args.entries_from:
        entries += archive_globals(args.nm, args.entries_from)
    if not entries:
        sys.exit("check_stack: no entry points")

    failures = 0
    for entry in entries:
        try:
            total, path = graph.worst(entry)
        except ValueError as e:
            print(f"STACK {args.name} {entry}: cannot be bounded: {e}")
            failures += 1
            continue
        verdict = "ok" if total <= args.budget else "OVER BUDGET"
        print(f"STACK {args.name} {graph.label.get(entry, entry)}: {total} bytes (budget {args.budget}) {verdict}")
        print("      deepest path: " + " -> ".join(graph.label.get(s, s) for s in path))
        failures += total > args.budget
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
