#!/usr/bin/env python3
"""`kincal correct --urscript` on programs as PolyScope saves them (issue #42).

  polyscope_program.py KINCAL ROBOTS_DIR WORK_DIR

PolyScope writes the installation's TCP as set_tcp(p[...]) and each waypoint as two globals, its
TCP pose and its joint readings (Waypoint_1_p, Waypoint_1_q), moved to by
movej(get_inverse_kin(Waypoint_1_p, qnear=Waypoint_1_q)) and movel(Waypoint_1_p). The waypoints
here are the UR10's (ur10.yaml) at a TCP 150 mm out along the flange's z, made by `kincal predict
--at tcp` on the model with that TCP. Checked, each a failure when it does not hold:
  - without --tcp, correct aims the program's TCP (its waypoints' poses and readings agree with
    it, not with the model's tool), exits 0 and rewrites the waypoints' assignments alone, each
    motion line byte for byte; the same targets as with --tcp 0,0,0.15;
  - a program whose set_tcp is not its poses' TCP (the poses of the flange, which the model's
    tool is not either): the TCP it sets is named with the --tcp that aims it, the waypoints far
    from their readings are named, nothing is aimed at the set TCP silently, nothing is written;
  - a gripper URCap's servoj to a pose computed when the program runs: left as written and named,
    the rest corrected as without it;
  - a program made for another robot (the poses 0.2 m off their readings): each waypoint named.
Exit status 0 on success, 1 with what failed."""
import math
import os
import subprocess
import sys

kincal, robots, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
os.chdir(work)
failures = []
readings = [[0.1, -1.2, 1.4, -1.6, -1.5, 0.3], [0.4, -1.0, 1.2, -1.8, -1.4, 0.1], [-0.3, -1.4, 1.6, -1.2, -1.6, 0.8]]


def run(args, expect_ok=True):
    r = subprocess.run([kincal] + args, capture_output=True, text=True)
    if (r.returncode == 0) != expect_ok:
        failures.append(f"{' '.join(args)}: exit status {r.returncode}\n{r.stdout}{r.stderr}")
    return r.stdout + r.stderr


def rotation_vector(w, x, y, z):
    if w < 0:
        w, x, y, z = -w, -x, -y, -z
    s = math.sqrt(x * x + y * y + z * z)
    angle = 2 * math.atan2(s, w)
    return [0.0, 0.0, 0.0] if s == 0 else [angle * x / s, angle * y / s, angle * z / s]


def tcp_poses(tcp_z):
    """The nominal UR10's TCP poses at `readings` (frame 0: ur10.yaml's base is the identity)."""
    with open(os.path.join(robots, "ur10.yaml")) as f:
        model = f.read() + f"tcp:\n  translation: [0, 0, {tcp_z}]\n"
    with open("ur10_tcp.yaml", "w") as f:
        f.write(model)
    with open("readings.csv", "w") as f:
        f.write("q1,q2,q3,q4,q5,q6\n" + "".join(",".join(repr(v) for v in q) + "\n" for q in readings))
    run(["predict", "--model", "ur10_tcp.yaml", "--joints", "readings.csv", "--at", "tcp", "-o", "poses.csv"])
    rows = [line.split(",") for line in open("poses.csv").read().split("\n")[1:] if line]
    return [[float(v) for v in r[6:9]] + rotation_vector(*[float(v) for v in r[9:13]]) for r in rows]


def program(name, set_tcp_z, poses, qs):
    text = f"def cell():\n  set_tcp(p[0.0,0.0,{set_tcp_z},0.0,0.0,0.0])\n"
    for k, (p, q) in enumerate(zip(poses, qs), 1):
        text += f"  global Waypoint_{k}_p=p[{', '.join('%.12f' % v for v in p)}]\n"
        text += f"  global Waypoint_{k}_q=[{', '.join(repr(v) for v in q)}]\n"
    text += ('  while (True):\n    $ 2 "Robot Program"\n'
             "    movej(get_inverse_kin(Waypoint_1_p, qnear=Waypoint_1_q), a=1.3962634015954636, v=1.0471975511965976)\n"
             "    movel(Waypoint_2_p, a=1.2, v=0.25)\n"
             "    movej(get_inverse_kin(Waypoint_3_p, qnear=Waypoint_3_q), a=1.39, v=1.04)\n"
             "    movel(Waypoint_1_p, a=1.2, v=0.25)\n  end\nend\n")
    with open(name, "w") as f:
        f.write(text)
    return text


C = ["correct", "--model", "ur10_calibrated.yaml", "--nominal", os.path.join(robots, "ur10.yaml")]
# The calibrated arm: the UR10 with its elbow 2 mm longer and its second joint's zero 0.05 deg off.
with open(os.path.join(robots, "ur10.yaml")) as f:
    calibrated = f.read().replace("a: -0.5723,", "a: -0.5743,").replace(
        "d: 0,        theta: 0, a: -0.612,", "d: 0,        theta: 0.05, a: -0.612,")
with open("ur10_calibrated.yaml", "w") as f:
    f.write(calibrated)

at_tcp = tcp_poses(0.15)
source = program("tcp150.script", 0.15, at_tcp, readings)
log = run(C + ["--urscript", "tcp150.script", "-o", "tcp150_corrected.script"])
if "aimed the program's TCP (set_tcp, line 2" not in log:
    failures.append("the program's TCP not aimed:\n" + log)
written = open("tcp150_corrected.script").read() if os.path.exists("tcp150_corrected.script") else ""
changed = [k for k, (a, b) in enumerate(zip(source.split("\n"), written.split("\n"))) if a != b]
if len(written.split("\n")) != len(source.split("\n")) or changed != [2, 3, 4, 6, 7]:
    failures.append(f"not the waypoints' assignments alone rewritten (lines changed: {changed}; Waypoint_2_q, "
                    "which no motion names, kept):\n" + written)
run(C + ["--urscript", "tcp150.script", "--tcp", "0,0,0.15", "-o", "tcp150_given.script"])
if os.path.exists("tcp150_given.script") and open("tcp150_given.script").read() != written:
    failures.append("the program's TCP aimed differently from --tcp 0,0,0.15")

program("flange_poses.script", 0.15, tcp_poses(0.0), readings)
log = run(C + ["--urscript", "flange_poses.script", "-o", "flange_poses_corrected.script"], expect_ok=False)
if "flange_poses.script:2: warning: the program sets its TCP at 0, 0, 150 mm from the flange" not in log or \
        "give --tcp 0,0,0.15,0,0,0" not in log or "aimed the program's TCP" in log:
    failures.append("a set_tcp its poses are not of: not named, or aimed:\n" + log)

# A gripper URCap's preamble (as OnRobot's RG2 node writes it into every program of its users): a
# depth-compensating servoj to a pose computed when the program runs, left as written and named.
urcap = ("  def RG2(target_width=110, depth_compensation=False):\n    start_pose = get_forward_kin()\n"
         "    target_pose = pose_trans(start_pose, p[0, 0, -0.002, 0, 0, 0])\n"
         "    servoj(get_inverse_kin(target_pose), 0, 0, 0.008, 0.01, 2000)\n  end\n")
with open("urcap.script", "w") as f:
    f.write(source.replace("  while (True):\n", urcap + "  while (True):\n"))
log = run(C + ["--urscript", "urcap.script", "-o", "urcap_corrected.script"])
if "warning: 1 of 5 motions left as written" not in log or \
        "urcap.script:12:28: servoj's target target_pose is assigned an expression on line 11" not in log:
    failures.append("the URCap's runtime servoj not named as left as written:\n" + log)
if os.path.exists("urcap_corrected.script") and open("urcap_corrected.script").read() != \
        written.replace("  while (True):\n", urcap + "  while (True):\n"):
    failures.append("a program with a URCap's preamble not corrected as the same program without it")

far = [[p[0] + 0.2] + p[1:] for p in at_tcp]
program("other_robot.script", 0.15, far, readings)
log = run(C + ["--urscript", "other_robot.script", "-o", "other_corrected.script"], expect_ok=False)
for line in (11, 13):
    if f"other_robot.script:{line}: warning: the target pose is" not in log:
        failures.append(f"waypoint of line {line}, 0.2 m off its readings, not named:\n" + log)

for f in failures:
    print("FAILED:", f)
print(f"{len(failures)} failures")
sys.exit(1 if failures else 0)
