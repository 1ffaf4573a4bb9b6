#!/usr/bin/env python3
"""Hostile and careless inputs to every writing subcommand of kincal (issue #16).

Each case runs the kincal binary and checks: the exit status, a message matching a pattern (the
options, numbers and likely cause), that no input file changed (SHA-256 before and after), and
that no temporary file was left beside an output. Prints the number of cases per subcommand.

usage: hostile_inputs.py KINCAL KINCAL_PLATFORM ROBOTS_DIR CAMERA_IMAGES_DIR WORK_DIR
"""
import csv, hashlib, math, os, random, re, shutil, struct, subprocess, sys, zlib
from collections import Counter

kincal, platform, robots, camera_dir, work = sys.argv[1:6]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
os.chdir(work)
puma = os.path.join(robots, "puma560.yaml")
failures, counts = [], Counter()


def sha(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def case(name, args, pattern, rc_ok=False, protect=(), exe=None, timeout=300):
    counts[name.split(":")[0]] += 1
    before = {p: sha(p) for p in protect}
    try:
        r = subprocess.run([exe or kincal] + args, capture_output=True, text=True, timeout=timeout)
        out, rc = r.stdout + r.stderr, r.returncode
    except subprocess.TimeoutExpired:
        failures.append(f"{name}: did not finish within {timeout} s")
        return
    if (rc == 0) != rc_ok:
        failures.append(f"{name}: exit status {rc}\n{out[-600:]}")
    if pattern and not re.search(pattern, out, re.S):
        failures.append(f"{name}: no /{pattern}/ in:\n{out[-600:]}")
    if rc < 0 or "terminate called" in out or "Assertion" in out:
        failures.append(f"{name}: crashed\n{out[-600:]}")
    for p, h in before.items():
        if sha(p) != h:
            failures.append(f"{name}: input {p} changed")
    leftovers = [f for f in os.listdir(".") if ".kincal-" in f]
    if leftovers:
        failures.append(f"{name}: temporary files left: {leftovers}")


def run(args):
    subprocess.run([kincal] + args, check=True, capture_output=True)


def write_csv(name, header, rows):
    with open(name, "w") as f:
        f.write(",".join(header) + "\n")
        for r in rows:
            f.write(",".join(repr(v) for v in r) + "\n")


# --- data: a plan, the model's exact predictions, and careless variants of them
run(["plan", "--model", puma, "-n", "40", "--pool", "300", "-o", "q.csv"])
run(["predict", "--model", puma, "--joints", "q.csv", "-o", "exact.csv"])
rows = list(csv.reader(open("exact.csv")))
header, exact = rows[0], [[float(x) for x in r] for r in rows[1:]]
random.seed(16)
noisy = [r[:6] + [v + random.gauss(0, 2e-4) for v in r[6:9]] + r[9:] for r in exact]
write_csv("d.csv", header, noisy)
write_csv("deg.csv", header, [[v * 180 / math.pi for v in r[:6]] + r[6:] for r in noisy])
write_csv("mm.csv", header, [r[:6] + [v * 1000 for v in r[6:9]] + r[9:] for r in noisy])
write_csv("xyzw.csv", header, [r[:9] + [r[10], r[11], r[12], r[9]] for r in noisy])
write_csv("huge.csv", header, [r[:6] + [1e308] + r[7:] for r in noisy])
shutil.copy("d.csv", "held.csv")
os.link("d.csv", "d_link.csv")
os.mkdir("sub")

ident = ["identify", "--model", puma]
inputs = ["d.csv", "held.csv", "q.csv", "exact.csv"]
# outputs over inputs, by every spelling
case("identify:out=data", ident + ["--data", "d.csv", "--out", "d.csv"], r"--out d\.csv is the same file as --data d\.csv", protect=inputs)
case("identify:out=data via ..", ident + ["--data", "d.csv", "--out", "sub/../d.csv"], r"same file as --data", protect=inputs)
case("identify:out=data hard link", ident + ["--data", "d.csv", "--out", "d_link.csv"], r"same file as --data", protect=inputs)
case("identify:out=model", ident + ["--data", "d.csv", "--out", puma], r"same file as --model", protect=inputs + [puma])
case("identify:urdf=validate", ident + ["--data", "d.csv", "--out", "o.yaml", "--validate", "held.csv", "--urdf", "held.csv"],
     r"--urdf held\.csv is the same file as --validate", protect=inputs)
case("identify:urdf=out", ident + ["--data", "d.csv", "--out", "o.yaml", "--urdf", "o.yaml"], r"another output", protect=inputs)
case("identify:out in missing dir", ident + ["--data", "d.csv", "--out", "no/such/dir/o.yaml"], r"no/such/dir/o\.yaml", protect=inputs)
# numbers
for opt, val, msg in [("--outlier-probability", "nan", "not a finite number"), ("--outlier-probability", "inf", "not a finite"),
                      ("--outlier-probability", "0.9", r"0\.9 is too large: must be <= 0\.5"), ("--outlier-probability", "-1", "too small"),
                      ("--sigma", "nan", "not a finite"), ("--sigma", "1e400", "not a finite"), ("--sigma", "-1", "too small"),
                      ("--sigma", "0", "too small"), ("--sigma", "abc", "not a number"), ("--orientation-sigma-deg", "nan", "not a finite"),
                      ("--orientation-sigma-deg", "1e308", r"1e\+308 is too large: must be <= 180$")]:
    case(f"identify:{opt} {val}", ident + ["--data", "d.csv", "--out", "o.yaml", opt, val], msg.rstrip("$"), protect=inputs)
# plausibility
case("identify:degrees", ident + ["--data", "deg.csv", "--out", "o.yaml"], r"likely degrees given as radians.*--accept-implausible", protect=inputs)
case("identify:millimetres", ident + ["--data", "mm.csv", "--out", "o.yaml"], r"1000 times as far.*likely millimetres given as metres")
case("identify:xyzw", ident + ["--data", "xyzw.csv", "--out", "o.yaml"], r"likely quaternions in x,y,z,w order")
case("identify:1e308", ident + ["--data", "huge.csv", "--out", "o.yaml"], r"farther than 1000 m.*1e\+308")
case("identify:exact fit", ident + ["--data", "exact.csv", "--out", "o.yaml"], r"reproduces every measured point")
case("identify:exact fit, --sigma", ident + ["--data", "exact.csv", "--out", "o.yaml", "--sigma", "1e-4"], r"wrote o\.yaml", rc_ok=True)
case("identify:plausible", ident + ["--data", "d.csv", "--out", "o.yaml", "--validate", "held.csv"], r"wrote o\.yaml", rc_ok=True, protect=inputs)
case("identify:not a dataset", ident + ["--data", puma, "--out", "o.yaml"], r"puma560\.yaml", protect=[puma])

# --- predict, plan, urdf
case("predict:out=joints", ["predict", "--model", puma, "--joints", "q.csv", "-o", "q.csv"], r"-o q\.csv is the same file as --joints", protect=["q.csv"])
case("predict:out=model", ["predict", "--model", puma, "--joints", "q.csv", "-o", puma], r"same file as --model", protect=[puma])
case("plan:out=model", ["plan", "--model", puma, "-n", "5", "-o", puma], r"same file as --model", protect=[puma])
case("plan:progress on stderr", ["plan", "--model", puma, "-n", "40", "--pool", "300"], r"exchange sweep 1: 40 of 40", rc_ok=True)
case("plan:count 0", ["plan", "--model", puma, "-n", "0"], r"-n|count")
case("urdf:out=model", ["urdf", "--model", puma, "-o", puma], r"same file as --model", protect=[puma])
case("urdf:out is a directory", ["urdf", "--model", puma, "-o", "sub"], r"sub")

# --- session: the journal is never destroyed
run(["session", "--model", os.path.join(robots, "arid_prrr.yaml"), "--poses", "12", "--validation", "3", "--journal", "s.journal"])
sess = ["session", "--model", os.path.join(robots, "arid_prrr.yaml"), "--poses", "12", "--validation", "3", "--resume",
        "--journal", "s.journal"]
for opt in ["--report", "--out", "--dataset"]:
    case(f"session:{opt}=journal", sess + [opt, "s.journal"], opt + r" s\.journal is the same file as --journal s\.journal", protect=["s.journal"])
case("session:dataset=model", sess + ["--dataset", os.path.join(robots, "arid_prrr.yaml")], r"same file as --model",
     protect=["s.journal", os.path.join(robots, "arid_prrr.yaml")])
case("session:report=out", sess + ["--report", "r.html", "--out", "r.html"], r"another output", protect=["s.journal"])
case("session:puma on the platform rig", ["session", "--model", puma, "--poses", "3", "--journal", "p.journal"],
     r"0 of [0-9]+ random configurations of puma560.*in view", timeout=120)
run(["plan", "--model", os.path.join(robots, "arid_prrr.yaml"), "-n", "20", "-o", "arid_plan.csv"])
case("session:plan outside the rig's rail", ["session", "--model", os.path.join(robots, "arid_prrr.yaml"), "--plan", "arid_plan.csv",
     "--journal", "a.journal"], r"narrows its model's limits \(SI units\) to rail \[0, 0\.1\] instead of \[0, 18\.24\]",
     protect=["arid_plan.csv"])
case("session:poses 0", ["session", "--model", puma, "--poses", "0", "--journal", "p.journal"], r"--poses")
case("session:puma's sweeps behind the stereo pair", ["session", "--model", puma, "--rig", "stereo", "--sweeps", "5",
     "--validation", "0", "--journal", "q.journal"], r"pose [0-9]+: the beacon is .* behind or at the cameras", timeout=120)

# --- colour-table
bg, crop = os.path.join(camera_dir, "views"), None
pngs = sorted(f for f in os.listdir(bg) if f.endswith(".png"))
img = os.path.join(bg, pngs[0])
shutil.copy(img, "pos.png")
shutil.copy(os.path.join(bg, pngs[1]), "neg.png")
ct = ["colour-table", "--positive", "pos.png", "--negative", "neg.png"]
case("colour-table:out=positive", ct + ["-o", "pos.png"], r"-o pos\.png is the same file as --positive", protect=["pos.png", "neg.png"])
case("colour-table:out=negative", ct + ["-o", "neg.png"], r"same file as --negative", protect=["pos.png", "neg.png"])
case("colour-table:max-distance nan", ct + ["-o", "t.kcct", "--max-distance", "nan"], r"not a finite number")
case("colour-table:max-distance 1e308", ct + ["-o", "t.kcct", "--max-distance", "1e308"], r"1e\+308 is too large: must be <= 10\b")


# --- images over the size limit (a valid 20000 x 20000 PNG of a few hundred kB) and a PGM whose header lies
def big_png(name, w, h):
    z, row = zlib.compressobj(9), b"\0" * (w + 1)
    data = b"".join(z.compress(row) for _ in range(h)) + z.flush()
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    with open(name, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)) + chunk(b"IDAT", data) + chunk(b"IEND", b""))


big_png("huge.png", 20000, 20000)
board = ["--board", "chessboard:9x6:0.03"]
case("camera:calibrate 20000x20000", ["camera", "calibrate"] + board + ["huge.png", "-o", "c.yaml"], r"20000 x 20000 pixels is over the limit")
case("blobs:20000x20000", ["blobs", "huge.png"], r"20000 x 20000 pixels is over the limit")
with open("lie.pgm", "wb") as f:
    f.write(b"P5\n65535 65535\n255\n" + b"\0" * 100)
case("kincal_platform:PGM header 65535x65535", ["--can", "vcan-none", "--frames", "lie.pgm"], r"truncated: the header says 65535 x 65535",
     exe=platform)
# one-pixel blobs, every other pixel: far more than --max-blobs
with open("dots.pgm", "wb") as f:
    f.write(b"P5\n512 512\n255\n" + bytes((255 if (x % 2 == 0 and y % 2 == 0) else 0) for y in range(512) for x in range(512)))
case("blobs:too many", ["blobs", "--threshold", "128", "--max-blobs", "1000", "dots.pgm"], r"65536 blobs, more than --max-blobs 1000")

# --- camera: outputs over input images and files
views = [os.path.join(bg, p) for p in pngs[:6]]
for i, v in enumerate(views[:3]):
    shutil.copy(v, f"v{i}.png")
mine = ["v0.png", "v1.png", "v2.png"]
case("camera:calibrate out=image", ["camera", "calibrate"] + board + mine + ["-o", "v1.png"], r"-o v1\.png is the same file as image v1\.png", protect=mine)
case("camera:stereo out=left", ["camera", "stereo"] + board + ["--left", "v0.png", "--right", "v1.png", "-o", "v0.png"],
     r"same file as --left", protect=mine)
case("camera:stereo tolerance nan", ["camera", "stereo"] + board + ["--left", "v0.png", "--right", "v1.png", "-o", "s.yaml", "--tolerance", "nan"],
     r"not a finite")
shutil.copy("exact.csv", "poses.csv")
case("camera:hand-eye out=poses", ["camera", "hand-eye"] + board + ["--camera", "c.yaml", "--poses", "poses.csv", "--images", "v0.png", "-o", "poses.csv"],
     r"same file as --poses", protect=["poses.csv"])

# --- camera: degenerate input refused with the numbers
case("camera:one image three times", ["camera", "calibrate"] + board + ["v0.png", "v0.png", "v0.png", "-o", "c3.yaml"],
     r"a near-duplicate of v0\.png \(the same corners within 0\.000 px RMS", protect=mine)
run(["camera", "calibrate"] + board + [os.path.join(bg, p) for p in pngs] + ["-o", "cam.yaml"])
case("camera:stereo same images", ["camera", "stereo"] + board + ["--left", bg, "--right", bg, "--left-camera", "cam.yaml",
     "--right-camera", "cam.yaml", "-o", "s.yaml"], r"baseline 0\.0000[0-9]* m is 0\.0[0-9]* % of the board's median distance")
pose_rows = open(os.path.join(camera_dir, "poses.csv")).read().splitlines()
with open("poses_shuffled.csv", "w") as f:  # the images' poses, one row late
    f.write("\n".join([pose_rows[0]] + pose_rows[2:] + [pose_rows[1]]) + "\n")
case("camera:hand-eye poses of other images", ["camera", "hand-eye"] + board + ["--camera", "cam.yaml", "--poses", "poses_shuffled.csv",
     "--images", bg, "-o", "he.yaml"], r"do not belong together: AX = XB residual [0-9.]+ degrees / [0-9.]+ mm RMS")
case("camera:hand-eye consistent", ["camera", "hand-eye"] + board + ["--camera", "cam.yaml", "--poses", os.path.join(camera_dir, "poses.csv"),
     "--images", bg, "-o", "he.yaml"], r"wrote he\.yaml", rc_ok=True)

big_png("tiny.png", 1, 1)
case("camera:1x1 image", ["camera", "calibrate"] + board + ["tiny.png"] * 3 + ["-o", "t.yaml"], r"image 1x1 too small for the chessboard:9x6:0\.03 board")
case("camera:2x2 board", ["camera", "calibrate", "--board", "chessboard:2x2:0.03", "v0.png", "-o", "t.yaml"], r"must be 3\.\.100")

# --- others
case("dbc:out is a directory", ["dbc", "-o", "sub"], r"sub: is a directory")
case("monitor:duration nan", ["monitor", "--replay", "q.csv", "--duration-s", "nan"], r"not a finite")

print("hostile cases per subcommand:", ", ".join(f"{k} {v}" for k, v in sorted(counts.items())), f"(total {sum(counts.values())})")
if failures:
    print("\n\n".join(failures))
    sys.exit(1)
print("all hostile inputs refused or handled")
