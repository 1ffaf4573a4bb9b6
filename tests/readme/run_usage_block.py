#!/usr/bin/env python3
"""Runs the README's "Using it" block as written, so the README cannot drift from the program.

The block is the first ```sh fence after the "## Using it" heading (before the next "## "
heading). Its lines, with backslash continuations joined, run as one bash script
(`set -Eeuo pipefail`, traced with -x, each trace line stamped with the seconds since the start)
from the repository root, so a variable one line sets ($k, $o) is there on the next; TMPDIR is a
scratch folder of the runner's, removed afterwards, so the block's `o=$(mktemp -d)` leaves nothing. The block
sets k itself; --kincal PATH puts another binary in the `k=` line in place of the README's
build/native/host/cli/kincal (ctest: the test build's own).

Exit 0 when every command exits 0; 1 naming the README line of the first command that failed, or
a file the block left in the repository root; 2 when the README has no such block.

  tests/readme/run_usage_block.py [--readme README.md] [--kincal PATH] [--root DIR]
"""

import argparse
import os
import shlex
import subprocess
import sys
import tempfile
import time

HEADING = "## Using it"
README_KINCAL = "build/native/host/cli/kincal"


def refuse(message):
    """The README (or the call) is wrong, not a command: exit 2."""
    print(message, file=sys.stderr)
    sys.exit(2)


def find_block(readme_path):
    """Returns [(README line number, line)] of the block, or exits 2 saying what is missing."""
    with open(readme_path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    try:
        start = next(i for i, line in enumerate(lines) if line.rstrip() == HEADING)
    except StopIteration:
        refuse(f"run_usage_block: {readme_path}: no '{HEADING}' heading")
    i = start + 1
    while i < len(lines) and lines[i].strip() != "```sh":
        if lines[i].startswith("## "):
            refuse(f"run_usage_block: {readme_path}:{start + 1}: no ```sh block under '{HEADING}' "
                     f"(the next heading, line {i + 1}, came first)")
        i += 1
    if i == len(lines):
        refuse(f"run_usage_block: {readme_path}:{start + 1}: no ```sh block under '{HEADING}'")
    block = []
    for j in range(i + 1, len(lines)):
        if lines[j].strip() == "```":
            return block
        block.append((j + 1, lines[j]))
    refuse(f"run_usage_block: {readme_path}:{i + 1}: the ```sh block is not closed")


def join_continuations(block):
    """Joins lines ending in a backslash with the next; keeps the first line's number."""
    commands = []
    pending = None
    for number, line in block:
        if pending is None:
            pending = [number, line]
        else:
            pending[1] = pending[1][:-1].rstrip() + " " + line.strip()
        if not pending[1].endswith("\\"):
            commands.append(tuple(pending))
            pending = None
    if pending is not None:
        refuse(f"run_usage_block: README line {pending[0]}: the block ends in a continuation")
    return commands


def point_at(commands, kincal):
    """Puts kincal in the k= line in place of the README's path."""
    out = []
    found = False
    for number, line in commands:
        if line.lstrip().startswith("k=") and README_KINCAL in line:
            line = line.replace(README_KINCAL, shlex.quote(kincal), 1)
            found = True
        out.append((number, line))
    if not found:
        refuse(f"run_usage_block: no line of the block sets k={README_KINCAL}, so --kincal has nowhere to go")
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    here = os.path.dirname(os.path.abspath(__file__))
    parser.add_argument("--readme", default=os.path.join(here, "..", "..", "README.md"))
    parser.add_argument("--kincal", help="the kincal binary to run instead of " + README_KINCAL)
    parser.add_argument("--root", help="directory the block runs in (default: the README's)")
    args = parser.parse_args()
    root = os.path.abspath(args.root or os.path.dirname(os.path.abspath(args.readme)))

    commands = join_continuations(find_block(args.readme))
    if args.kincal:
        commands = point_at(commands, os.path.abspath(args.kincal))
    if not any(line.strip() and not line.lstrip().startswith("#") for _, line in commands):
        refuse(f"run_usage_block: {args.readme}: the '{HEADING}' block has no command")

    with tempfile.TemporaryDirectory(prefix="kincal-readme-") as scratch:
        failed_at = os.path.join(scratch, "failed_at")
        script = os.path.join(scratch, "using_it.sh")
        # Line i of the script is command i - len(preamble) of the block (1-based). TMPDIR puts the
        # block's `mktemp -d` in this scratch folder, removed afterwards.
        preamble = [
            "PS4='+ [${SECONDS}s] '",  # bash takes no PS4 from the environment when run as root
            "set -Eeuo pipefail",
            f"trap 'echo \"$LINENO $?\" > {shlex.quote(failed_at)}' ERR",
        ]
        with open(script, "w", encoding="utf-8") as f:
            f.write("\n".join(preamble + [line for _, line in commands]) + "\n")
        before = set(os.listdir(root))
        env = dict(os.environ, TMPDIR=scratch)
        started = time.monotonic()
        result = subprocess.run(["bash", "-x", script], cwd=root, env=env, stdin=subprocess.DEVNULL)
        seconds = time.monotonic() - started
        where = None
        if os.path.exists(failed_at):
            with open(failed_at, encoding="utf-8") as f:
                script_line, status = (int(word) for word in f.read().split())
            number, line = commands[script_line - len(preamble) - 1]
            where = f"README line {number} exited {status}: {line.strip()}"

    print(f"run_usage_block: {len(commands)} lines of '{HEADING}' in {seconds:.1f} s", flush=True)
    if result.returncode != 0:
        print(f"run_usage_block: FAILED: {where or f'bash exited {result.returncode}'}", file=sys.stderr)
        return 1
    left = sorted(set(os.listdir(root)) - before)
    if left:
        print(f"run_usage_block: FAILED: the block wrote into {root}: {', '.join(left)} "
              "(write into a scratch directory such as \"$o\")", file=sys.stderr)
        return 1
    print("run_usage_block: every command exited 0")
    return 0


if __name__ == "__main__":
    sys.exit(main())
