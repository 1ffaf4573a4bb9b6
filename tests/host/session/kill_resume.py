#!/usr/bin/env python3
"""A session killed with SIGKILL mid-way and resumed gives the same dataset as an uninterrupted one.

  kill_resume.py KINCAL MODEL WORKDIR

Runs `kincal session` (simulated ARID platform rig: the firmware in-process on the loopback bus)
once without interruption, then again, killing it with SIGKILL once a third of the poses are in
its journal, and resumes it with --resume; the two dataset CSVs must be equal byte for byte.
Exit status 0 on success, 1 with a message saying what differed."""
import os
import signal
import subprocess
import sys
import time

POSES, VALIDATION = 12, 3


def session(kincal, model, work, name, resume=False):
    args = [kincal, "session", "--model", model, "--poses", str(POSES), "--validation", str(VALIDATION),
            "--seed", "3", "--journal", os.path.join(work, name + ".journal"),
            "--dataset", os.path.join(work, name + ".csv")]
    return args + (["--resume"] if resume else [])


def records(path):
    try:
        with open(path, "rb") as f:
            return max(0, f.read().count(b"\n") - 1)  # the header is the first line
    except FileNotFoundError:
        return 0


def main(kincal, model, work):
    os.makedirs(work, exist_ok=True)
    for name in ("whole", "killed"):
        for suffix in (".journal", ".csv"):
            if os.path.exists(os.path.join(work, name + suffix)):
                os.remove(os.path.join(work, name + suffix))
    subprocess.run(session(kincal, model, work, "whole"), check=True, stdout=subprocess.DEVNULL)

    journal = os.path.join(work, "killed.journal")
    victim = subprocess.Popen(session(kincal, model, work, "killed"), stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    total = POSES + VALIDATION
    while records(journal) < total // 3 and victim.poll() is None:
        time.sleep(0.01)
    victim.send_signal(signal.SIGKILL)
    victim.wait()
    done = records(journal)
    if victim.returncode != -signal.SIGKILL or done >= total:
        print(f"the session was not killed mid-way (exit {victim.returncode}, {done} of {total} poses)")
        return 1
    print(f"killed with {done} of {total} poses in the journal")

    subprocess.run(session(kincal, model, work, "killed", resume=True), check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(work, "whole.csv"), "rb") as a, open(os.path.join(work, "killed.csv"), "rb") as b:
        whole, resumed = a.read(), b.read()
    if whole != resumed:
        print("the resumed session's dataset differs from the uninterrupted one's")
        return 1
    rows = whole.count(b"\n") - 1
    print(f"the resumed dataset equals the uninterrupted one ({rows} rows)")
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
