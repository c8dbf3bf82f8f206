#!/usr/bin/env python3
"""The HDRI rows' tests (docs/fidelity.md, "HDRI rows"), one entry for both renderers:

  check_environment.py orientation CLAYFIT WORKDIR M0_FIT --renderer blender|threejs
      [--node-modules DIR] [--wrong]
  check_environment.py fidelity CLAYFIT WORKDIR FIT --renderer blender|threejs
      --map EXR --max-rmse X [--node-modules DIR] [--samples S]

orientation: a 64 x 32 map, black but for one 2 x 2 texel patch placed (through
truth.json's rotation, read from a first tiny synth) where the world direction
(0.70, 0.45, 0.55) is; a Lambert sphere (M0's albedo) lit by it in clayfit (16
median-cut lights), and in Blender (Diffuse BSDF) or three.js (M0's glTF: Lambert).
Both images must show the light within 2 degrees of the patch
(scene_compare.orientation; measured: clayfit 0.002, Blender 0.04, three.js 0.19).
--wrong hands the renderer the rotation times a mirror of the map (the convention
clayfit had before 2026-11-27, when its map was the mirror of Blender's and
three.js'): it must fail.

fidelity: the fit's preset under MAP in the renderer against clayfit (1024
median-cut lights), through blender_fidelity.py / threejs_fidelity.py --max-rmse.

Exit 77 when MAP, oiiotool, Blender, or Chromium and the npm packages are absent
(the fidelity scripts say which).
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPTS = os.path.join(HERE, "..", "..", "scripts")
sys.path.insert(0, SCRIPTS)
import scene_compare as sc  # noqa: E402

PROG = "check_environment"
WORLD = (0.70, 0.45, 0.55)  # the patch's world direction: lit side, seen by camera 0
SIZE = "80x60"


def default_rotation(a):
    """synth's rotation, from truth.json of a tiny capture under a uniform map."""
    uniform = os.path.join(a.workdir, "uniform.exr")
    sc.run(["oiiotool", "--create", "8x4", "3", "--fill:color=1,1,1", "8x4+0+0", "-d", "half",
            "-o", uniform], "oiiotool --create", PROG)
    probe = os.path.join(a.workdir, "probe")
    shutil.rmtree(probe, ignore_errors=True)
    sc.run([a.clayfit, "--quiet", "synth", "-o", probe, "--images", "1", "--size", "16x16",
            "--format", "exr", "--no-noise", "--environment", uniform,
            "--environment-lights", "1"], "clayfit synth", PROG)
    return sc.truth_environment(probe)["rotation"]


def patch_map(a, rotation):
    """WORKDIR/patch.exr: the 2 x 2 patch centred on the texel corner nearest the map
    direction R^T WORLD."""
    norm = math.sqrt(sum(v * v for v in WORLD))
    w = [v / norm for v in WORLD]
    d = [sum(rotation[k][i] * w[k] for k in range(3)) for i in range(3)]
    x, y = sc.map_pixel(64, 32, d)
    x0, y0 = int(round(x + 0.5)) - 1, int(round(y + 0.5)) - 1
    path = os.path.join(a.workdir, "patch.exr")
    sc.run(["oiiotool", "--create", "64x32", "3", "--fill:color=200,200,200",
            f"2x2+{x0}+{y0}", "-d", "half", "-o", path], "oiiotool --create", PROG)
    return path


def renderer_command(a, script):
    if a.renderer == "blender":
        return [sys.executable, os.path.join(SCRIPTS, "blender_fidelity.py"), a.clayfit, script]
    return [sys.executable, os.path.join(SCRIPTS, "threejs_fidelity.py"), a.clayfit,
            a.node_modules, script]


def main():
    p = argparse.ArgumentParser(prog="check_environment.py")
    p.add_argument("check", choices=["orientation", "fidelity"])
    p.add_argument("clayfit")
    p.add_argument("workdir")
    p.add_argument("fit")
    p.add_argument("--renderer", required=True, choices=["blender", "threejs"])
    p.add_argument("--node-modules")
    p.add_argument("--map")
    p.add_argument("--max-rmse")
    p.add_argument("--samples", default="256")
    p.add_argument("--wrong", action="store_true")
    a = p.parse_args()
    if a.renderer == "blender" and not shutil.which("blender"):
        print("SKIP: blender is not installed (Debian: blender; scripts/install-deps.sh)")
        return 77
    if not shutil.which("oiiotool"):
        print("SKIP: no oiiotool")
        return 77
    os.makedirs(a.workdir, exist_ok=True)
    if a.check == "fidelity":
        if not a.map or not os.path.exists(a.map):
            print(f"SKIP: no map {a.map} (../shared/data/hdri is absent)")
            return 77
        cmd = renderer_command(a, os.path.join(a.workdir, "work")) + [
            a.fit, "--environment", a.map, "--max-rmse", a.max_rmse]
        if a.renderer == "blender":
            cmd += ["--samples", a.samples]
        return subprocess.run(cmd).returncode
    rotation = default_rotation(a)
    cmd = renderer_command(a, os.path.join(a.workdir, "work")) + [
        a.fit, "--environment", patch_map(a, rotation), "--environment-lights", "16",
        "--size", SIZE, "--orientation", "2"]
    if a.renderer == "blender":
        cmd += ["--samples", "16", "--diffuse-only"]
    if a.wrong:
        mirrored = sc.matmul(rotation, [[1, 0, 0], [0, 1, 0], [0, 0, -1]])
        cmd += ["--rotation", ",".join(repr(v) for row in mirrored for v in row)]
    print(json.dumps({"rotation": rotation, "wrong": a.wrong}))
    return subprocess.run(cmd).returncode


if __name__ == "__main__":
    sys.exit(main())
