#!/usr/bin/env python3
"""Proves firmware code uses no heap, no exceptions and no RTTI, from its symbols.

  check_no_heap.py --nm NM --archive LIB.a   no object of the library refers to them
  check_no_heap.py --nm NM --image IMG.elf [--map IMG.map]
                                             the linked image contains none of them; the
                                             link map names the object that pulled each in

The images are also linked with --wrap for every allocator entry point and no wrapper
definitions (toolchain/KincalFirmwareChecks.cmake), so a heap call fails their link and the
linker names the caller; this check covers what that cannot: code the linker dropped as
unused (the library check) and symbols outside the wrap list.
"""
import argparse
import re
import subprocess
import sys

FORBIDDEN = [
    (re.compile(r"^_?(malloc|free|calloc|realloc|memalign|aligned_alloc|posix_memalign)(_r)?$"), "heap allocator"),
    (re.compile(r"^_sbrk(_r)?$"), "heap growth (sbrk)"),
    (re.compile(r"^_Zn[wa][jm]"), "operator new"),
    (re.compile(r"^_Zd[la]Pv"), "operator delete"),
    (re.compile(r"^__cxa_(allocate_exception|throw|begin_catch|end_catch|rethrow|call_unexpected)$"), "exception machinery"),
    (re.compile(r"^(__gxx_personality_v0|_Unwind_Resume|__cxa_end_cleanup)$"), "exception unwinding"),
    (re.compile(r"^_ZT[IS]"), "RTTI typeinfo"),
]


def symbols(nm, path, undefined):
    cmd = [nm, "-u" if undefined else "--defined-only", path]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return sorted({line.split()[-1] for line in out.splitlines() if line.strip() and not line.endswith(":")})


def reason(map_text, symbol):
    """The link map's 'member included to satisfy reference by file (symbol)' line for symbol."""
    lines = map_text.splitlines()
    for i, line in enumerate(lines):
        if line.strip().endswith(f"({symbol})") and i > 0:
            return f"pulled in by {line.strip()} for {lines[i - 1].strip()}"
    return ""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--nm", default="arm-none-eabi-nm")
    what = ap.add_mutually_exclusive_group(required=True)
    what.add_argument("--archive")
    what.add_argument("--image")
    ap.add_argument("--map")
    args = ap.parse_args()

    path = args.archive or args.image
    map_text = open(args.map, encoding="utf-8").read() if args.map else ""
    found = []
    for sym in symbols(args.nm, path, undefined=bool(args.archive)):
        for pattern, what_it_is in FORBIDDEN:
            if pattern.match(sym):
                found.append(f"  {sym}: {what_it_is} {reason(map_text, sym)}".rstrip())
    if found:
        print(f"NOHEAP {path}: FAILED, {'refers to' if args.archive else 'contains'}:")
        print("\n".join(found))
        sys.exit(1)
    print(f"NOHEAP {path}: ok (no heap, exception or RTTI symbols)")


if __name__ == "__main__":
    main()
