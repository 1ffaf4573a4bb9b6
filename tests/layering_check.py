#!/usr/bin/env python3
"""The arrows of DESIGN.md, checked over every #include:

  firmware/core  includes only firmware/core/, shared/, Eigen and standard headers that need
                 no heap and no OS;
  firmware/      never includes host/;
  shared/        includes only shared/ and those standard headers;
  host/session   never includes host/sim/ or host/demo/: a session is what a calibration of a
                 real robot runs; the simulator implements its interfaces from host/demo/.
  host/correct   the same: the correction of a real robot's targets (issue #24); and it never
                 includes host/session: the correction block lives in host/correct, below both.

  layering_check.py REPO_ROOT     prints each violation as FILE:LINE and exits 1 if any
"""
import pathlib
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')
FREESTANDING_STD = {
    "algorithm", "array", "bit", "cassert", "cfloat", "climits", "cmath", "compare", "concepts", "cstddef",
    "cstdint", "cstring", "initializer_list", "iterator", "limits", "numbers", "numeric", "optional", "ratio",
    "span", "tuple", "type_traits", "utility", "variant",
}
SOURCES = ("*.hpp", "*.h", "*.cpp", "*.cc", "*.c")


def allowed(rel, target):
    if rel.startswith(("host/session/", "host/correct/")) and target.startswith(("host/sim/", "host/demo/")):
        return f"{'/'.join(rel.split('/')[:2])} must not include the simulator (host/sim, host/demo)"
    if rel.startswith("host/correct/") and target.startswith("host/session/"):
        return "host/correct must not include host/session (the correction block is host/correct's)"
    if rel.startswith("firmware/") and target.startswith("host/"):
        return "firmware must not include host code"
    if rel.startswith("firmware/core/") or rel.startswith("shared/"):
        own = ("firmware/core/", "shared/") if rel.startswith("firmware/core/") else ("shared/",)
        if target.startswith(own) or target in FREESTANDING_STD:
            return None
        if rel.startswith("firmware/core/") and target.startswith("Eigen/"):
            return None
        return f"{rel.split('/')[0]}/{'core/' if rel.startswith('firmware/') else ''} may not include <{target}>"
    return None


def main(root):
    root = pathlib.Path(root)
    problems = []
    for top in ("firmware", "shared", "host/session", "host/correct"):
        for pattern in SOURCES:
            for path in sorted((root / top).rglob(pattern)):
                rel = path.relative_to(root).as_posix()
                for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                    m = INCLUDE.match(line)
                    if m:
                        why = allowed(rel, m.group(2))
                        if why:
                            problems.append(f"{rel}:{number}: {why}")
    print("\n".join(problems) if problems else "layering: ok")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "."))
