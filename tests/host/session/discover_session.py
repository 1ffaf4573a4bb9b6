#!/usr/bin/env python3
"""A discovery session on the simulated Kapucu & Baysec rig, end to end (issue #14).

  discover_session.py KINCAL MODEL WORKDIR

Runs `kincal session --discover --joints 3 --home ... --prismatic 3` with the simulated Stanford
RRP arm on the stereo rig (the model file is only the arm the simulator hides): the session sweeps
each joint, discovers the arm and identifies it from there. Then the same session with the true
nominal model (circle-point analysis, then full least squares), same seed, hence the same
validation poses and noise. The discovery must find the topology (revolute, revolute, prismatic),
write both models, and its identified model must predict the held-out beacon positions within
MAX_OVER_MODEL of the session that was given the model (issue #14's goal for discovery).
Exit status 0 on success, 1 with a message saying what went wrong."""
import os
import re
import shutil
import subprocess
import sys

MAX_OVER_MODEL = 1.2
VALIDATION = re.compile(r"^validation \(\d+ poses\): (?:nominal|discovered) RMS ([0-9.]+) mm, identified RMS ([0-9.]+) mm",
                        re.M)


def session(kincal, work, name, args):
    p = subprocess.run([kincal, "session", "--rig", "stereo", "--seed", "3",
                        "--journal", os.path.join(work, name + ".journal"), *args],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        print(f"{name} session failed:\n{p.stdout}\n{p.stderr}")
        sys.exit(1)
    m = VALIDATION.search(p.stdout)
    if not m:
        print(f"{name} session printed no validation line:\n{p.stdout}")
        sys.exit(1)
    print(m.group(0))
    return p.stdout, float(m.group(2))


def main(kincal, model, work):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    discovered, identified = os.path.join(work, "discovered.yaml"), os.path.join(work, "identified.yaml")
    out, discovery_mm = session(kincal, work, "discovery",
                                ["--discover", "--model", model, "--joints", "3", "--home", "0,1.5708,0.8",
                                 "--prismatic", "3", "--discovered", discovered, "--out", identified])
    _, model_mm = session(kincal, work, "model", ["--model", model])
    failures = []
    for joint, kind in ((1, "revolute"), (2, "revolute"), (3, "prismatic")):
        if not re.search(rf"^joint {joint}: {kind};", out, re.M):
            failures.append(f"joint {joint} not discovered as {kind}")
    for path in (discovered, identified):
        if not os.path.exists(path):
            failures.append(f"{path} not written")
    print(f"held-out RMS: discovery session {discovery_mm:.3f} mm, session given the model {model_mm:.3f} mm "
          f"(ratio {discovery_mm / model_mm:.3f})")
    if not discovery_mm <= MAX_OVER_MODEL * model_mm:
        failures.append(f"the discovered arm predicts worse than {MAX_OVER_MODEL}x the model's session")
    for f in failures:
        print("FAILED:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
