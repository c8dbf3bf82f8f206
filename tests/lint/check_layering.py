#!/usr/bin/env python3
"""The layering the build enforces (docs/design.md, "Layers").

Usage: check_layering.py ROOT BUILD_DIR

Each layer under ROOT/src exports only its include/ folder; a header beside
a layer's sources is private to it. Checks, and exits 1 on any failure:
  1. no source under src/ includes a path with "..";
  2. no CMake file under src/ gives a target ROOT/src itself as an include
     directory (which would make every private header reachable again);
  3. the build rejects a private header: the probe target
     clayfit_layering_probe_private (a target on clayfit_export including
     model's private model/terms.h) fails to compile, on exactly that
     header, while clayfit_layering_probe_interface (the same target,
     including core's interface core/file.h) compiles.
"""
import os
import re
import subprocess
import sys

DOTDOT = re.compile(r'^\s*#\s*include\s*"[^"]*\.\./')
SRC_DIR = re.compile(r"\$\{PROJECT_SOURCE_DIR\}/src(\s|\))")


def sources(root, exts):
    for base, _, files in os.walk(os.path.join(root, "src")):
        for name in sorted(files):
            if name.endswith(exts):
                yield os.path.join(base, name)


def check_includes(root):
    bad = []
    for path in sources(root, (".c", ".h", ".cpp", ".hpp")):
        with open(path, encoding="utf-8") as f:
            for number, line in enumerate(f, 1):
                if DOTDOT.search(line):
                    bad.append(f"{os.path.relpath(path, root)}:{number}: includes through '..'")
    return bad


def check_cmake(root):
    bad = []
    for path in sources(root, ("CMakeLists.txt", ".cmake")):
        with open(path, encoding="utf-8") as f:
            for number, line in enumerate(f, 1):
                if not line.lstrip().startswith("#") and SRC_DIR.search(line):
                    bad.append(f"{os.path.relpath(path, root)}:{number}: "
                               "src/ itself as an include directory")
    return bad


def build(build_dir, target):
    run = subprocess.run(["cmake", "--build", build_dir, "--target", target],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    return run.returncode, run.stdout


def check_build(build_dir):
    bad = []
    code, out = build(build_dir, "clayfit_layering_probe_interface")
    if code != 0:
        bad.append("the probe with core's interface header did not compile:\n" + out[-2000:])
    code, out = build(build_dir, "clayfit_layering_probe_private")
    if code == 0:
        bad.append("the probe including model's private model/terms.h compiled: "
                   "the build does not enforce the layering")
    elif not re.search(r"model/terms\.h.*(No such file|not found)", out):
        bad.append("the private probe failed, but not on model/terms.h:\n" + out[-2000:])
    return bad


def main():
    if len(sys.argv) != 3:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    root, build_dir = sys.argv[1], sys.argv[2]
    bad = check_includes(root) + check_cmake(root) + check_build(build_dir)
    for line in bad:
        print(line)
    if bad:
        return 1
    print("layering: no '..' include, no src/ include directory, a private header rejected "
          "by the build and an interface header accepted")
    return 0


if __name__ == "__main__":
    sys.exit(main())
