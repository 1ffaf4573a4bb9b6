#!/usr/bin/env python3
"""Flash and RAM of a firmware image against budgets, from arm-none-eabi-size.

  check_size.py --size SIZE --flash-budget BYTES --ram-budget BYTES IMAGE.elf

Flash = text + data (initial values of .data live in flash); RAM = data + bss, where bss
includes the reserved stack. Prints both and fails when either is over its budget.
"""
import argparse
import subprocess
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="arm-none-eabi-size")
    ap.add_argument("--flash-budget", type=int, required=True)
    ap.add_argument("--ram-budget", type=int, required=True)
    ap.add_argument("image")
    args = ap.parse_args()

    out = subprocess.run([args.size, "-B", args.image], check=True, capture_output=True, text=True).stdout
    text, data, bss = (int(v) for v in out.splitlines()[1].split()[:3])
    failed = False
    for name, used, budget in (("flash", text + data, args.flash_budget), ("ram", data + bss, args.ram_budget)):
        over = used > budget
        failed |= over
        print(f"SIZE {args.image} {name}: {used} bytes of budget {budget} ({100.0 * used / budget:.1f}%)"
              f"{' OVER BUDGET' if over else ''}")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
