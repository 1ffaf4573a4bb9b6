#!/usr/bin/env python3
"""`kincal identify --report` on the shared UR10 laser-tracker set (issue #23).

  identify_report.py KINCAL EXPORT UR10_URDF WORK_DIR

The export imported as the README's worked example does; the first 100 rows train (with an id
column, as `kincal import --id` writes it: "rec-NNNN", and two rows moved 8 mm in x so that
rejection has something to find), the next 200 are held out. One identify run with model
selection on (100 rows: the smallest set it runs on) writes the report, which must hold the
model selection table, the parameter table with each prior, the accuracy on the held-out rows,
one residual plot per joint with the rejected rows marked, and the rejected rows with their
lines and ids. Then the refusals: a report path that is the data file, and one in a directory
that does not exist, are refused by name before any solve.
"""
import csv
import pathlib
import re
import subprocess
import sys

TRAIN_ROWS, HELD_ROWS = 100, 200
MOVED = (17, 63)  # 0-based training rows moved 8 mm in x
JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
          "wrist_3_joint"]

failures = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        failures.append(what)


def run(args):
    done = subprocess.run([str(a) for a in args], capture_output=True, text=True)
    return done.returncode, done.stdout, done.stderr


def main(kincal, export, urdf, work):
    work = pathlib.Path(work)
    work.mkdir(parents=True, exist_ok=True)
    imported = work / "ur10.csv"
    code, out, err = run([kincal, "import", export, "-o", imported, "--joints", ",".join(JOINTS), "--joint-unit", "rad",
                          "--position", "measurement_x,measurement_y,measurement_z", "--position-unit", "mm",
                          "--position-std", "measurement_std_x,measurement_std_y,measurement_std_z"])
    if code != 0:
        print(out + err)
        return 1
    with open(imported, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    header, data = rows[0], rows[1:]
    x = header.index("x")
    train, held = work / "train.csv", work / "held_out.csv"
    lines = {}  # id -> line in train.csv
    with open(train, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header + ["id"])
        for k, r in enumerate(data[:TRAIN_ROWS]):
            r = list(r)
            if k in MOVED:
                r[x] = repr(float(r[x]) + 0.008)
            ident = "rec-%04d" % k
            lines[ident] = k + 2
            w.writerow(r + [ident])
    with open(held, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        w.writerows(data[TRAIN_ROWS:TRAIN_ROWS + HELD_ROWS])

    report = work / "report.html"
    report.unlink(missing_ok=True)
    code, out, err = run([kincal, "identify", "--model", urdf, "--tip-link", "tracker_probe", "--data", train,
                          "--validate", held, "--out", work / "calibrated.yaml", "--report", report])
    print(out + err)
    check(code == 0, "identify --report exits 0")
    check(f"wrote {report} (the HTML report)" in out, "identify says it wrote the report")
    html = report.read_text(encoding="utf-8") if report.exists() else ""
    check(html.startswith("<!DOCTYPE html>") and html.rstrip().endswith("</html>"), "the report is a whole page")
    check("<script" not in html and "src=" not in html and "href=\"http" not in html,
          "self-contained: no scripts, no outside files")

    selection = re.search(r"<h3>Model selection</h3>(.*?)</section>", html, re.S)
    check(selection is not None, "the model selection table")
    if selection:
        body = selection.group(1)
        for name in ("registration", "joint-offsets", "geometry", "geometry-noprior"):
            check(f"<td>{name}</td>" in body, f"the selection table lists {name}")
        check(body.count("<td>chosen</td>") == 1, "one candidate marked chosen")
        chosen = re.search(r"model: ([a-z0-9+.-]+) \(chosen by cross-validation\)", html)
        printed = re.search(r"chosen: ([a-z0-9+.-]+)", out)
        check(chosen is not None and printed is not None and printed.group(1).startswith(chosen.group(1)),
              "the report's chosen model is the one identify printed")
        check("out-of-range fold" in body, "the table says how it scored")

    model = re.search(r"<table class=\"model\">(.*?)</table>", html, re.S)
    check(model is not None and "<th>prior sigma</th>" in model.group(1) and "<th>from data</th>" in model.group(1),
          "the parameter table has each parameter's prior sigma and its share from the data")
    if model:
        parameters = re.findall(r"<tr><td>([a-z_0-9]+)</td>", model.group(1))
        check(len(parameters) >= 20 and "a2" in parameters and "base_x" in parameters,
              f"the parameter table lists the identified parameters ({len(parameters)})")
        check(len(re.findall(r"<td class=\"n\">[0-9.]+ %</td>", model.group(1))) == len(parameters),
              "every parameter has its data share in %")

    accuracy = re.search(r"<table class=\"accuracy\">(.*?)</table>", html, re.S)
    check("<h3>Accuracy on the rows used and the held-out rows</h3>" in html, "the accuracy section says its rows")
    check(accuracy is not None and "calibrated: held out" in accuracy.group(1)
          and "nominal, registered: rows used" in accuracy.group(1),
          "accuracy of the baseline and the calibration, on the rows used and held out")
    held_rms = re.search(r"calibrated: held out[^<]*</td><td class=\"n\">200</td><td class=\"n\">[0-9.]+ mm</td>"
                         r"<td class=\"n\">([0-9.]+) mm</td>", html)
    printed_rms = re.search(r"validation \(.*?calibrated *: position mean [0-9.]+ mm, rms ([0-9.]+) mm", out, re.S)
    check(held_rms is not None and printed_rms is not None
          and abs(float(held_rms.group(1)) - float(printed_rms.group(1))) < 1e-3,
          "the held-out RMS is the one identify printed")

    residuals = re.search(r"<section class=\"fit-residuals\"(.*?)</section>", html, re.S)
    check(residuals is not None, "the residuals section")
    if residuals:
        body = residuals.group(1)
        check(body.count("<svg class=\"plot\"") == 6, "one residual plot per joint (6)")
        for k, joint in enumerate(JOINTS):
            check(f"Joint {k + 1} ({joint})" in body, f"a plot against {joint}")
        check(body.count(">rejected</text>") == 6, "each plot marks the rejected rows")

    rejected = re.search(r"<h3>Rejected rows</h3>(.*?)</section>", html, re.S)
    check(rejected is not None, "the rejected rows table")
    if rejected:
        table = rejected.group(1)
        for k in MOVED:
            ident = "rec-%04d" % k
            check(f"<tr><td>{lines[ident]}</td><td>{ident}</td>" in table,
                  f"the moved row {ident} is listed with its line {lines[ident]} and its id")
            check(f"rejected line {lines[ident]} (id {ident})" in out, f"identify printed {ident} rejected too")
        gate = re.search(r"\(paired t (-?[0-9.]+)\)", out)
        check(gate is not None and f"(paired t {float(gate.group(1)):.2f})" in table and "RMS: they stand." in table,
              "the rejected rows' note has the rejection gate's t and verdict, as identify printed them")

    # Refusals: before any solve (no table printed), naming --report.
    for path, what in ((train, "the data file"), (work / "no_such_dir" / "r.html", "a missing directory")):
        code, out, err = run([kincal, "identify", "--model", urdf, "--tip-link", "tracker_probe", "--data", train,
                              "--out", work / "refused.yaml", "--report", path])
        check(code != 0 and "--report" in err and "model selection" not in out and "method:" not in out,
              f"a report path that is {what} is refused before the solve: {err.strip()}")
    check(not (work / "refused.yaml").exists(), "a refused run writes no model")

    print("identify_report: " + ("ok" if not failures else f"{len(failures)} FAILED"))
    return 0 if not failures else 1


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:5]))
