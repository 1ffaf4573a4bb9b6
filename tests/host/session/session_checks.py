"""What the recorded-session scripts (stereo_session.py, board_session.py) share: running kincal,
comparing positions, and judging a hostile recording (exit status 1 and the expected words)."""

import math
import subprocess
import sys


def run(args, expect_ok=True):
    p = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if expect_ok and p.returncode != 0:
        print("failed:", " ".join(args), "\n", p.stdout, p.stderr)
        sys.exit(1)
    return p


def rms_mm(a, b):
    return 1e3 * math.sqrt(sum((p - q) ** 2 for u, v in zip(a, b) for p, q in zip(u, v)) / len(a))


def check_refused(name, p, expected, failures):
    """A session on a hostile recording must exit 1 with every string of `expected` in its errors."""
    message = [l for l in p.stderr.splitlines() if l.startswith("kincal session:")]
    print(f"{name}: exit {p.returncode}: {message[0] if message else p.stderr}")
    if p.returncode != 1 or not all(e in p.stderr for e in expected):
        failures.append(f"{name}: expected exit 1 and {expected} in:\n{p.stderr}")


def verdict(failures):
    for f in failures:
        print("FAILED:", f)
    return 1 if failures else 0
