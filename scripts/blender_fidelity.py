#!/usr/bin/env python3
"""Preset fidelity in Blender (docs/fidelity.md): for each fit.json, the
Blender preset rendered by Cycles against clayfit's own image formation of
the same scene, pixel by pixel inside the sphere.

usage: blender_fidelity.py CLAYFIT WORKDIR FIT.json [FIT.json ...]
           [--size WxH] [--samples S] [--supersample S] [--flash-offset x,y,z]
           [--set INPUT=VALUE ...] [--max-rmse X] [--blender BLENDER]

For each fit (named by its folder): `clayfit export --format blender`,
`clayfit synth` of one noiseless float image of the fit's model and values
(camera 0 of its orbit: distance 5, 20 degrees up; the flash at
--flash-offset in camera coordinates, default 2.5,-1.5,0: 33 degrees from the
view at the sphere), scripts/blender_render.py, scripts/blender_compare.py.
Prints one JSON line per fit and a Markdown row; WORKDIR/NAME/diff.png is the
difference image. With --max-rmse, exits 1 when a relative RMSE is above it.
Exit 77 when Blender is not installed.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def run(command, what):
    result = subprocess.run(command, capture_output=True, text=True, timeout=600)
    if result.returncode != 0:
        sys.stderr.write(result.stdout[-3000:] + result.stderr[-3000:])
        raise SystemExit(f"blender_fidelity: {what} failed (exit {result.returncode})")
    return result.stdout


def synth_params(fit):
    """--param name=value for every parameter of the fit."""
    out = []
    for name, p in fit["params"].items():
        v = p["value"]
        text = ",".join(repr(float(x)) for x in v) if isinstance(v, list) else repr(float(v))
        out += ["--param", f"{name}={text}"]
    return out


def one(a, fit_path):
    name = os.path.basename(os.path.dirname(os.path.abspath(fit_path)))
    work = os.path.join(a.workdir, name)
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    with open(fit_path, encoding="utf-8") as f:
        fit = json.load(f)
    preset = os.path.join(work, "preset.py")
    run([a.clayfit, "--quiet", "export", fit_path, "--format", "blender", "-o", preset], "export")
    synth = os.path.join(work, "synth")
    t0 = time.monotonic()
    run([a.clayfit, "--quiet", "synth", "-o", synth, "--model", fit["model"]["code"],
         *synth_params(fit), "--images", "1", "--size", a.size, "--format", "exr",
         "--no-noise", "--masks", "--supersample", str(a.supersample),
         "--flash-offset", a.flash_offset], "clayfit synth")
    t1 = time.monotonic()
    render = os.path.join(work, "blender.exr")
    sets = [x for s in a.set for x in ("--set", s)]
    blender = [a.blender, "-b", "--factory-startup", "--python-exit-code", "1", "-P"]
    run(blender + [os.path.join(HERE, "blender_render.py"), "--", "--capture", synth,
                   "--preset", preset, "--out", render, "--samples", str(a.samples), *sets],
        "blender_render.py")
    t2 = time.monotonic()
    out = run(blender + [os.path.join(HERE, "blender_compare.py"), "--", "--clayfit",
                         os.path.join(synth, "images", "000.exr"), "--mask",
                         os.path.join(synth, "masks", "000.exr"), "--render", render,
                         "--diff", os.path.join(work, "diff.png")], "blender_compare.py")
    line = next(l for l in out.splitlines() if l.startswith("blender_compare: "))
    r = json.loads(line[len("blender_compare: "):])
    r.update({"fit": name, "model": fit["model"]["code"], "synth_s": round(t1 - t0, 2),
              "blender_s": round(t2 - t1, 2)})
    return r


def main():
    p = argparse.ArgumentParser(prog="blender_fidelity.py")
    p.add_argument("clayfit")
    p.add_argument("workdir")
    p.add_argument("fits", nargs="+")
    p.add_argument("--size", default="320x240")
    p.add_argument("--samples", type=int, default=64)
    p.add_argument("--supersample", type=int, default=4)
    p.add_argument("--flash-offset", default="2.5,-1.5,0")
    p.add_argument("--set", action="append", default=[])
    p.add_argument("--max-rmse", type=float)
    p.add_argument("--blender", default=shutil.which("blender"))
    a = p.parse_args()
    if not a.blender:
        print("SKIP: blender is not installed (Debian: blender; scripts/install-deps.sh)")
        return 77
    os.makedirs(a.workdir, exist_ok=True)
    failed = False
    for fit in a.fits:
        r = one(a, fit)
        print(json.dumps(r))
        print(f"| {r['fit']} | {100 * r['relative_rmse']:.2f} % | {r['sum_ratio']:.4f} | "
              f"{100 * r['relative_rmse_after_gain']:.2f} % | {r['pixels']} |")
        if a.max_rmse is not None and not r["relative_rmse"] <= a.max_rmse:
            print(f"FAIL: {r['fit']}: relative RMSE {r['relative_rmse']:.4g} is above "
                  f"{a.max_rmse:.4g}")
            failed = True
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
