#!/usr/bin/env python3
"""Preset fidelity in Blender (docs/fidelity.md): for each fit.json, the
Blender preset rendered by Cycles against clayfit's own image formation of
the same scene, pixel by pixel inside the sphere.

usage: blender_fidelity.py CLAYFIT WORKDIR FIT.json [FIT.json ...]
           [--size WxH] [--samples S] [--supersample S] [--flash-offset x,y,z]
           [--set INPUT=VALUE ...] [--max-rmse X] [--blender BLENDER] [--seed N]
           [--environment EXR [--environment-lights K] [--environment-rotation R]
            [--interpolation Closest|Linear] [--rotation R] [--orientation DEG]]
           [--diffuse-only] [--synth-cache DIR]

For each fit (named by its folder): `clayfit export --format blender`,
`clayfit synth` of one noiseless float image of the fit's model and values
(camera 0 of its orbit: distance 5, 20 degrees up; the flash at
--flash-offset in camera coordinates, default 2.5,-1.5,0: 33 degrees from the
view at the sphere), scripts/blender_render.py, scripts/blender_compare.py.
Prints one JSON line per fit and a Markdown row; WORKDIR/NAME/diff.png is the
difference image. With --max-rmse, exits 1 when a relative RMSE is above it.
Exit 77 when Blender is not installed.

With --environment (the HDRI rows), the flash is replaced by the map: K
median-cut lights in clayfit (synth --environment, default K 1024), the world's
Environment Texture in Cycles, oriented by truth.json's rotation
(blender_render.py). --orientation DEG is the one-patch map check
(scene_compare.orientation) instead of the comparison. --diffuse-only renders a
Diffuse BSDF of the fit's albedo instead of the preset (the floor).
"""
import argparse
import json
import os
import shutil
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import scene_compare as sc  # noqa: E402

PROG = "blender_fidelity"


def run(command, what):
    return sc.run(command, what, PROG)


def one(a, fit_path):
    name, work, fit = sc.fit_folder(a.workdir, fit_path)
    preset = os.path.join(work, "preset.py")
    run([a.clayfit, "--quiet", "export", fit_path, "--format", "blender", "-o", preset], "export")
    synth = os.path.join(work, "synth")
    synth_s = sc.synth_scene(a, fit, synth, PROG)
    t1 = time.monotonic()
    render = os.path.join(work, "blender.exr")
    extra = [x for s in a.set for x in ("--set", s)]
    if a.diffuse_only:
        albedo = fit["params"]["albedo"]["value"]
        extra += ["--diffuse-only", *(repr(float(v)) for v in albedo)]
    if a.rotation:
        extra += ["--rotation", a.rotation]
    blender = [a.blender, "-b", "--factory-startup", "--python-exit-code", "1", "-P"]
    run(blender + [os.path.join(HERE, "blender_render.py"), "--", "--capture", synth,
                   "--preset", preset, "--out", render, "--samples", str(a.samples),
                   "--seed", str(a.seed), "--interpolation", a.interpolation, *extra],
        "blender_render.py")
    t2 = time.monotonic()
    if a.orientation is not None:
        w, h = map(int, a.size.split("x"))
        c = sc.exr_values(os.path.join(synth, "images", "000.exr"), 3, PROG)
        m = sc.exr_values(os.path.join(synth, "masks", "000.exr"), 1, PROG)
        b = sc.exr_values(render, 3, PROG)
        return sc.report_orientation(name, "Blender", c, b, m, synth, w, h, 3, a.orientation,
                                     PROG)
    out = run(blender + [os.path.join(HERE, "blender_compare.py"), "--", "--clayfit",
                         os.path.join(synth, "images", "000.exr"), "--mask",
                         os.path.join(synth, "masks", "000.exr"), "--render", render,
                         "--diff", os.path.join(work, "diff.png")], "blender_compare.py")
    line = next(l for l in out.splitlines() if l.startswith("blender_compare: "))
    r = json.loads(line[len("blender_compare: "):])
    r.update({"fit": name, "model": fit["model"]["code"], "synth_s": round(synth_s, 2),
              "blender_s": round(t2 - t1, 2)})
    return r


def main():
    p = argparse.ArgumentParser(prog="blender_fidelity.py")
    p.add_argument("clayfit")
    p.add_argument("workdir")
    p.add_argument("fits", nargs="+")
    sc.add_scene_arguments(p, "Blender", "the world's texture in Cycles")
    p.add_argument("--samples", type=int, default=64)
    p.add_argument("--seed", type=int, default=1, help="Cycles' seed")
    p.add_argument("--interpolation", default="Closest", choices=["Closest", "Linear"])
    p.add_argument("--diffuse-only", action="store_true",
                   help="a Lambert material of the fit's albedo instead of the preset")
    p.add_argument("--blender", default=shutil.which("blender"))
    a = p.parse_args()
    if not a.blender:
        print("SKIP: blender is not installed (Debian: blender; scripts/install-deps.sh)")
        return 77
    os.makedirs(a.workdir, exist_ok=True)
    failed = False
    for fit in a.fits:
        r = one(a, fit)
        if isinstance(r, bool):  # the orientation check's verdict
            failed = r or failed
            continue
        failed = sc.report(r, a.max_rmse) or failed
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
