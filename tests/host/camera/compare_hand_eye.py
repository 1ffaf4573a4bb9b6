#!/usr/bin/env python3
"""The hand-eye identified with the kinematics against `kincal camera hand-eye` (issue #26).

  compare_hand_eye.py IDENTIFY_HAND_EYE CAMERA_HAND_EYE TRUE_HAND_EYE MAX_MM MAX_DEG

Reads gripper_T_camera from the three OpenCV YAML files (`identify --hand-eye`, `camera hand-eye`
on the same views with the controller's nominal poses, the simulated arm's truth), prints how far
apart they are, and fails unless the two calibrations agree within MAX_MM and MAX_DEG and the
identified one is at least as near the truth as camera hand-eye's in rotation and within 25 % of
it in translation. Neither can meet the truth exactly: the truth's flange carries its own errors of
the last link (d6, theta6), which identify holds fixed and leaves in the tool, as camera hand-eye's
nominal flange does. Camera hand-eye does not take the nominal poses as exact (issue #43: each pose
gets a correction whose noise is estimated from the data), which brings its translation near
identify's. Measured on the test rig (seed 26): the two 2.7 mm and 0.18 deg apart; against the
truth identify 2.5 mm and 0.10 deg, camera hand-eye 2.2 mm and 0.14 deg (3.2 mm and 0.20 deg at
issue #26, when it held the poses exact). Exit status 0 on success, 1 with the numbers otherwise."""
import math
import re
import sys


def gripper_T_camera(path):
    text = open(path).read()
    m = re.search(r"gripper_T_camera: !!opencv-matrix.*?data: \[(.*?)\]", text, re.S)
    if not m:
        sys.exit(f"{path}: no gripper_T_camera matrix")
    v = [float(x) for x in m.group(1).replace("\n", " ").split(",")]
    return [v[0:4], v[4:8], v[8:12]]


def apart(a, b):
    """Translation (mm) and rotation (deg) between two 3x4 [R t] rows."""
    dt = 1e3 * math.sqrt(sum((a[i][3] - b[i][3]) ** 2 for i in range(3)))
    trace = sum(a[k][i] * b[k][i] for i in range(3) for k in range(3))  # trace(Ra^T Rb)
    return dt, math.degrees(math.acos(max(-1.0, min(1.0, (trace - 1) / 2))))


def main(identified, camera, truth, max_mm, max_deg):
    i, c, t = gripper_T_camera(identified), gripper_T_camera(camera), gripper_T_camera(truth)
    both, i_truth, c_truth = apart(i, c), apart(i, t), apart(c, t)
    print(f"identify vs camera hand-eye: {both[0]:.3f} mm, {both[1]:.4f} deg")
    print(f"against the truth: identify {i_truth[0]:.3f} mm, {i_truth[1]:.4f} deg; "
          f"camera hand-eye {c_truth[0]:.3f} mm, {c_truth[1]:.4f} deg")
    ok = both[0] <= float(max_mm) and both[1] <= float(max_deg)
    ok = ok and i_truth[0] <= 1.25 * c_truth[0] and i_truth[1] <= c_truth[1]
    if not ok:
        print(f"FAILED: the two must agree within {max_mm} mm and {max_deg} deg, identify at least as near the truth "
              "in rotation and within 25 % of camera hand-eye's distance in translation")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:6]))
