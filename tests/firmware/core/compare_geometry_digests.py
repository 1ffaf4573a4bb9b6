#!/usr/bin/env python3
"""The float geometry gives the same bits natively and on the Cortex-M4.

Runs the native geometry_digest program and its Cortex-M4 image (under QEMU, through
toolchain/qemu-mps2-an386.sh), reads their `DIGEST <name> <cases> <ok> <digest>` lines and fails
naming every function whose line differs or is missing on one side. Exit status 0 only if both
programs ran, printed the same non-empty set of functions, and every line matches.

Usage: compare_geometry_digests.py --native PROGRAM --m4 IMAGE.elf --qemu RUNNER
"""
import argparse
import subprocess
import sys


def digests(command, label):
    result = subprocess.run(command, capture_output=True, text=True, timeout=600)
    if result.returncode != 0:
        sys.exit(f"{label}: {' '.join(command)} exited with {result.returncode}\n{result.stdout}{result.stderr}")
    lines = {}
    for line in result.stdout.splitlines():
        fields = line.split()
        if not fields or fields[0] != "DIGEST":
            continue
        if len(fields) != 5:
            sys.exit(f"{label}: malformed line {line!r}")
        name = fields[1]
        if name in lines:
            sys.exit(f"{label}: function {name} printed twice")
        lines[name] = tuple(fields[2:])
    if not lines:
        sys.exit(f"{label}: no DIGEST lines in the output of {' '.join(command)}")
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--native", required=True)
    parser.add_argument("--m4", required=True)
    parser.add_argument("--qemu", required=True)
    args = parser.parse_args()

    native = digests([args.native], "native")
    m4 = digests([args.qemu, args.m4], "m4")
    differing = []
    for name in sorted(native.keys() | m4.keys()):
        here, there = native.get(name), m4.get(name)
        if here == there:
            print(f"same    {name}: {here[0]} cases, {here[1]} ok, digest {here[2]}")
            continue
        differing.append(name)
        show = lambda d: "missing" if d is None else f"{d[0]} cases, {d[1]} ok, digest {d[2]}"
        print(f"DIFFERS {name}: native {show(here)}; m4 {show(there)}")
    if differing:
        sys.exit(f"{len(differing)} of {len(native.keys() | m4.keys())} functions differ between native and "
                 f"Cortex-M4: {', '.join(differing)}")
    print(f"all {len(native)} functions give the same bits natively and on the Cortex-M4")


if __name__ == "__main__":
    main()
