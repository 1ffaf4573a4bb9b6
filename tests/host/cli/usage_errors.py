#!/usr/bin/env python3
"""kincal's command line as the ecosystem's tools treat it (issue #21): usage errors exit 2 and
name the word that is wrong with the nearest valid one; help and version exit 0; bare `kincal`
prints the help on standard error and exits 2 (issue #44: it ran nothing). Usage: usage_errors.py KINCAL ROBOTS_DIR"""
import subprocess
import sys

kincal, robots = sys.argv[1], sys.argv[2]

# (arguments, exit status, text that must be in stdout + stderr, text that must not be)
cases = [
    ([], 2, ["Usage:", "identify", "Run 'kincal COMMAND --help'"], []),
    (["--version"], 0, ["."], []),
    (["identify", "--help"], 0, ["--model", "--validate"], []),
    (["nosuch"], 2, ["kincal: unknown command 'nosuch'", "Run 'kincal --help' for the commands"], ["did you mean"]),
    (["idnetify"], 2, ["unknown command 'idnetify' (did you mean identify?)"], []),
    (["calibrate"], 2, ["unknown command 'calibrate'"], []),
    (["identify", "--mdoel", "x"], 2, ["kincal identify: unknown option '--mdoel' (did you mean --model?)"],
     ["is required"]),
    (["identify", "--bogus"], 2, ["unknown option '--bogus'"], ["is required"]),
    (["identify", "--validate=x", "--mdoel=y"], 2, ["unknown option '--mdoel'"], []),
    (["plan", "-n", "abc"], 2, ["'abc' is not a whole number in [1, 100000]"], ["not in range"]),
    (["plan", "--model", f"{robots}/puma560.yaml", "-n", "0"], 2, ["0 is out of range: must be in [1, 100000]"], []),
    (["plan", "-x"], 2, ["unknown option '-x'"], []),
    (["identify"], 2, ["kincal identify:", "--model", "required", "Run 'kincal identify --help'"], []),
    (["camera"], 2, ["kincal camera: give a command: calibrate, stereo, hand-eye"], []),
    (["camera", "calibrte"], 2, ["kincal camera: unknown command 'calibrte' (did you mean calibrate?)"], []),
    (["camera", "calibrate", "--bord", "x"], 2, ["unknown option '--bord' (did you mean --board?)"], []),
    (["demo", "--no-such-option"], 2, ["unknown option '--no-such-option'"], []),
    # An option's value may look like an option or a negative number; it is not judged as one.
    (["plan", "--model", f"{robots}/puma560.yaml", "-n", "2", "--seed", "-3"], None, [], ["unknown option"]),
    # Not a usage error: the input is wrong (exit 1, saying why).
    # Options that mean nothing with the others given (issue #44): the option needed or excluded is named.
    (["import", "x.csv", "-o", "o.csv", "--joints", "q1", "--joint-unit", "rad", "--position", "x,y,z", "--position-unit",
      "m", "--euler", "intrinsic-xyz"], 2, ["kincal import: --euler requires --orientation"], []),
    (["monitor", "--replay", "x.log", "--log", "y.log"], 2, ["kincal monitor: --log requires --can"], []),
    (["export", "--format", "ur-kinematics", "--model", f"{robots}/puma560.yaml"], 1,
     ["is not a Universal Robots arm: axes 3 and 4 are 90.0 deg apart"], []),
]

failures = 0
for args, status, wanted, unwanted in cases:
    run = subprocess.run([kincal] + args, capture_output=True, text=True, timeout=300)
    text = run.stdout + run.stderr
    problems = []
    if not args and run.stdout:  # the usage of a bare `kincal` is a usage error's: on standard error
        problems.append("bare kincal printed on standard output")
    if status is not None and run.returncode != status:
        problems.append(f"exit {run.returncode}, expected {status}")
    problems += [f"missing {w!r}" for w in wanted if w not in text]
    problems += [f"unexpected {u!r}" for u in unwanted if u in text]
    if problems:
        failures += 1
        print(f"FAIL kincal {' '.join(args)}: {'; '.join(problems)}\n--- output:\n{text}---")
    else:
        print(f"ok   kincal {' '.join(args)} -> {run.returncode}")
print(f"{len(cases) - failures} of {len(cases)} cases passed")
sys.exit(1 if failures else 0)
