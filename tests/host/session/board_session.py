#!/usr/bin/env python3
"""A real camera-and-board session from recorded views, end to end (issue #26).

  board_session.py KINCAL MAKE_BOARD_RIG_VIEWS WORKDIR

make_board_rig_views records what a camera on a simulated UR5's flange sees of a 9x6 chessboard
fixed in the cell (views/view_NN.png at the plan's readings joints.csv, the camera file, the rig's
nominal model, and the true device_T_tool at held-out readings, held_out.csv); `kincal session
--rig camera --mount hand --source views --robot-cmd` reads the views back through host/capture,
measures each as a full pose with its 6x6 covariance, journals them into the dataset's 6x6
columns and identifies the arm with the board's place (base) and the camera's (tool). Its
identified model must predict the held-out tool positions nearer the truth than the registered
nominal model (`kincal identify --validate` on the session's dataset gives that figure: the
nominal with only the base registration identified). Then hostile recordings, each the good one
with one view changed or a wrong option: the board missing from view 3, half out of view 4, a
board of another size, a view missing (the counts differ). Each must fail with exit status 1 and
a message naming the pose and the frame's origin (or the counts).
Exit status 0 on success, 1 with a message saying what went wrong."""
import csv
import os
import re
import shutil
import sys

from session_checks import check_refused, rms_mm, run, verdict


def positions(rows):
    return [(float(r["x"]), float(r["y"]), float(r["z"])) for r in rows]


def session_args(kincal, d, views, extra=()):
    return [kincal, "session", "--rig", "camera", "--model", os.path.join(d, "nominal.yaml"),
            "--camera", os.path.join(d, "camera.yaml"), "--board", "chessboard:9x6:0.03", "--mount", "hand",
            "--robot-cmd", "true {q}", "--plan", os.path.join(d, "joints.csv"), "--source", views,
            "--journal", os.path.join(views + ".journal"), *extra]


def main(kincal, make_views, work):
    shutil.rmtree(work, ignore_errors=True)
    print(run([make_views, work, "hand"]).stdout, end="")
    views = os.path.join(work, "views")
    dataset = os.path.join(work, "dataset.csv")
    identified = os.path.join(work, "identified.yaml")
    hand_eye = os.path.join(work, "session_hand_eye.yaml")
    p = run(session_args(kincal, work, views, ["--dataset", dataset, "--out", identified, "--hand-eye", hand_eye]))
    failures = []
    # The hand-eye beside the model, in camera hand-eye's keys (cli.board_rig_hand_eye_agree
    # judges its values against camera hand-eye and the truth).
    with open(hand_eye) as f:
        text = f.read()
    if "gripper_T_camera: !!opencv-matrix" not in text or "base_T_target: !!opencv-matrix" not in text:
        failures.append(f"the session's --hand-eye file lacks gripper_T_camera or base_T_target:\n{text}")

    with open(dataset) as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    if len(rows) != 24 or "crzrz" not in rows[0] or "cxrx" not in rows[0]:
        failures.append(f"the session's dataset has {len(rows)} rows (24 expected) or lacks the 6x6 columns")

    # The session's identified model against the truth at the held-out readings.
    held_out = os.path.join(work, "held_out.csv")
    with open(held_out) as f:
        truth_rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    predicted = list(csv.DictReader(run([kincal, "predict", "--model", identified, "--joints", held_out])
                                    .stdout.splitlines()))
    identified_mm = rms_mm(positions(predicted), positions(truth_rows))
    # The registered nominal's figure on the same held-out truth, from the same dataset.
    p = run([kincal, "identify", "--model", os.path.join(work, "nominal.yaml"), "--data", dataset,
             "--validate", held_out, "--out", os.path.join(work, "identify.yaml")])
    m = re.search(r"predicts held-out positions ([0-9.]+) times better \(([0-9.]+) mm RMS registered nominal, "
                  r"([0-9.]+) mm calibrated\)", p.stdout)
    if not m:
        failures.append("identify --validate printed no held-out comparison:\n" + p.stdout)
    else:
        registered_mm = float(m.group(2))
        print(f"held-out tool positions against the truth: registered nominal {registered_mm:.3f} mm, "
              f"session's identified model {identified_mm:.3f} mm, identify on the session's dataset "
              f"{float(m.group(3)):.3f} mm")
        if not identified_mm < registered_mm:
            failures.append("the session's identified model is not nearer the truth than the registered nominal")

    hostile_views = os.path.join(work, "hostile")
    cases = [("missing", 3, [], ["pose 3 (", "view_03.png): the board's view is refused: pattern not found"]),
             ("half_out", 4, [], ["pose 4 (", "view_04.png): the board's view is refused"]),
             ("wrong_board", None, ["--board", "chessboard:8x6:0.03"],
              ["pose 0 (", "view_00.png): the board's view is refused"]),
             ("dropped", "drop", [], ["--source has 23 images", "the plan 24 poses"])]
    for name, pose, extra, expected in cases:
        d = os.path.join(work, name)
        shutil.copytree(views, d)
        if pose == "drop":
            os.remove(os.path.join(d, "view_23.png"))
        elif pose is not None:
            shutil.copy(os.path.join(hostile_views, f"view_{pose:02d}.png"), os.path.join(d, f"view_{pose:02d}.png"))
        args = session_args(kincal, work, d)
        if extra:
            args[args.index("chessboard:9x6:0.03")] = extra[1]
        p = run(args, expect_ok=False)
        check_refused(name, p, expected, failures)
    return verdict(failures)


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
