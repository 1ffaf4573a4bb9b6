#!/usr/bin/env python3
"""A real stereo session from recorded frames, end to end (issue #14).

  stereo_session.py KINCAL RENDER_STEREO_SEQUENCE MODEL WORKDIR

render_stereo_sequence records what a calibrated stereo pair would see of the simulated robot
(colour frames, stereo.yaml, colour samples, the plan, the truth); `kincal colour-table` builds
the beacon's table from the samples; `kincal session --rig stereo --left DIR --right 'PATTERN'
--stereo --colour-table --robot-cmd` reads the frames back through host/capture and identifies
the model; `kincal predict` then compares the identified and the nominal model with the truth
on the validation poses (never used by the identification). Then hostile recordings, each a copy
of the good one with one pose changed: the beacon missing from the right frame, doubled in the
left, mostly hidden in the right, a right frame missing (the counts differ). Each must fail
with exit status 1 and a message naming the pose and the camera (or the counts).
Exit status 0 on success, 1 with a message saying what went wrong."""
import csv
import os
import shutil
import sys

from session_checks import check_refused, rms_mm, run, verdict

HOSTILE_POSE = 2
# The identified model must predict the held-out points this much nearer the truth than the
# nominal one. Measured with the generator's defaults (640x480, 8 readings per joint, 6 held-out
# poses, RelWithDebInfo): seeds 1-6 gave 2.4x to 8.6x; seed 3, the one used here, 10.32 -> 2.06 mm.
MIN_IMPROVEMENT = 2.0


def predict(kincal, model, joints):
    out = run([kincal, "predict", "--model", model, "--joints", joints]).stdout.splitlines()
    rows = list(csv.DictReader(out))
    return [(float(r["x"]), float(r["y"]), float(r["z"])) for r in rows]


def session_args(kincal, d, extra=()):
    return [kincal, "session", "--model", os.path.join(d, "nominal.yaml"), "--rig", "stereo",
            "--robot-cmd", "true {q}", "--plan", os.path.join(d, "plan.csv"),
            "--validation-plan", os.path.join(d, "validation.csv"),
            "--left", os.path.join(d, "left"), "--right", os.path.join(d, "right", "*.png"),
            "--stereo", os.path.join(d, "stereo.yaml"), "--colour-table", os.path.join(d, "beacon.kcct"),
            "--journal", os.path.join(d, "session.journal"), *extra]


def main(kincal, render, model, work):
    shutil.rmtree(work, ignore_errors=True)
    good = os.path.join(work, "good")
    render_args = [render, "--model", model, "--seed", "3"]
    print(run(render_args + ["--out", good]).stdout, end="")
    print(run([kincal, "colour-table", "--positive", os.path.join(good, "beacon.png"), "--negative",
               os.path.join(good, "scene.png"), "--space", "rgb565", "-o", os.path.join(good, "beacon.kcct")]).stdout,
          end="")
    identified = os.path.join(good, "identified.yaml")
    p = run(session_args(kincal, good, ["--out", identified]))
    print("\n".join(l for l in p.stdout.splitlines() if l.startswith(("validation", "residuals", "noise"))))

    joints = os.path.join(good, "validation.csv")
    truth = predict(kincal, os.path.join(good, "truth.yaml"), joints)
    nominal_mm = rms_mm(predict(kincal, os.path.join(good, "nominal.yaml"), joints), truth)
    identified_mm = rms_mm(predict(kincal, identified, joints), truth)
    print(f"held-out beacon positions against the truth: nominal RMS {nominal_mm:.2f} mm, "
          f"identified RMS {identified_mm:.2f} mm")
    failures = []
    if not identified_mm * MIN_IMPROVEMENT < nominal_mm:
        failures.append(f"the identified model is not {MIN_IMPROVEMENT}x nearer the truth than the nominal one")

    hostile = [("missing", ["--missing-right"], [f"pose {HOSTILE_POSE}, right camera", "no beacon"]),
               ("doubled", ["--doubled-left"], [f"pose {HOSTILE_POSE}, left camera", "doubled"]),
               ("occluded", ["--occluded-right"], [f"pose {HOSTILE_POSE}, right camera", "occluded"]),
               ("dropped", ["--drop-right"], ["--left has", "--right", "one pair per pose"])]
    for name, flag, expected in hostile:
        d = os.path.join(work, name)
        shutil.copytree(good, d, ignore=shutil.ignore_patterns("*.journal", "identified.yaml"))
        run(render_args + ["--out", d, "--only", str(HOSTILE_POSE)] + flag + [str(HOSTILE_POSE)])
        p = run(session_args(kincal, d), expect_ok=False)
        check_refused(name, p, expected, failures)
    return verdict(failures)


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:5]))
