#!/usr/bin/env python3
"""clayfit's own convergence in K under an environment map (docs/captures.md,
`synth --environment`; docs/fidelity.md's HDRI rows): the fidelity scene
(camera 0, one noiseless float image, scene_compare.synth_fit) of each model
at the export tests' values (tests/export/make_fits.py VALUES), lit by each
map's K median-cut lights, against the same scene at the largest K. The
comparison is scene_compare.compare (the sphere's fully covered pixels, 2 px
inside the silhouette): relative RMSE, sum ratio.

The differences from the largest K understate the error (for a glossy lobe
under 4096 lights, by far). With --exact TOOL (the build's
tests/envmap_exact), each K is also rendered at pixel centres
(--supersample 1) and measured against the map's exact integral, every map
pixel a light, over every STRIDE-th sphere pixel: the error itself. (The
tool also takes synth's supersampled renders: envmap_exact DIR STRIDE S.)

usage: environment_convergence.py CLAYFIT WORKDIR [--map EXR ...] [--models M0,M2,M4]
           [--lights 64,256,1024,4096] [--size 320x240] [--supersample 4] [--json OUT]
           [--exact TOOL [--stride N]]
"""
import argparse
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "tests", "export"))
import scene_compare as sc  # noqa: E402
from make_fits import VALUES  # noqa: E402

PROG = "environment_convergence"


def fit_of(code):
    """The fields of a fit.json that scene_compare.synth_fit reads."""
    return {"model": {"code": code}, "params": {k: {"value": v} for k, v in VALUES[code].items()}}


def exact_error(tool, clayfit, code, map_path, k, folder, size, stride):
    """The pixel centres' relative RMSE and sum ratio against the exact integral."""
    sc.synth_fit(clayfit, fit_of(code), folder, size, 1, None, PROG,
                 environment=sc.environment_options(map_path, k, None))
    return json.loads(sc.run([tool, folder, str(stride)], "envmap_exact", PROG))


def render(clayfit, code, map_path, k, folder, size, supersample):
    t0 = time.monotonic()
    sc.synth_fit(clayfit, fit_of(code), folder, size, supersample, None, PROG,
                 environment=sc.environment_options(map_path, k, None))
    seconds = time.monotonic() - t0
    values = sc.exr_values(os.path.join(folder, "images", "000.exr"), 3, PROG)
    mask = sc.exr_values(os.path.join(folder, "masks", "000.exr"), 1, PROG)
    return values, mask, seconds


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("clayfit")
    p.add_argument("workdir")
    p.add_argument("--map", action="append")
    p.add_argument("--models", default="M0,M2,M4")
    p.add_argument("--lights", default="64,256,1024,4096")
    p.add_argument("--size", default="320x240")
    p.add_argument("--supersample", type=int, default=4)
    p.add_argument("--json")
    p.add_argument("--exact")
    p.add_argument("--stride", type=int, default=20)
    a = p.parse_args()
    maps = a.map or [os.path.join(HERE, "..", "..", "shared", "data", "hdri", n)
                     for n in ("studio.exr", "sunset.exr")]
    ks = [int(k) for k in a.lights.split(",")]
    w, h = map(int, a.size.split("x"))
    rows = []
    for map_path in maps:
        for code in a.models.split(","):
            renders = {}
            for k in ks:
                folder = os.path.join(a.workdir, f"{os.path.basename(map_path)}-{code}-{k}")
                renders[k] = render(a.clayfit, code, map_path, k, folder, a.size, a.supersample)
            ref, mask, _ = renders[ks[-1]]
            for k in ks:
                r, _, _ = sc.compare(ref, renders[k][0], mask, w, h, 2, 3, PROG)
                row = {"map": os.path.basename(map_path), "model": code, "lights": k,
                       "relative_rmse": r["relative_rmse"], "sum_ratio": r["sum_ratio"],
                       "pixels": r["pixels"], "synth_s": round(renders[k][2], 2)}
                print(f"{row['map']:12s} {code:3s} K {k:5d}: relative RMSE against K {ks[-1]} "
                      f"{100 * row['relative_rmse']:.3f} %, sum ratio {row['sum_ratio']:.5f}, "
                      f"synth {row['synth_s']:.1f} s", flush=True)
                if a.exact:
                    x = exact_error(a.exact, a.clayfit, code, map_path, k,
                                    os.path.join(a.workdir, f"{row['map']}-{code}-{k}-exact"),
                                    a.size, a.stride)
                    row.update({"exact_relative_rmse": x["relative_rmse"],
                                "exact_sum_ratio": x["sum_ratio"],
                                "exact_pixels": x["observations"]})
                    print(f"{row['map']:12s} {code:3s} K {k:5d}: against the exact integral "
                          f"{100 * x['relative_rmse']:.3f} %, sum ratio {x['sum_ratio']:.5f} "
                          f"({x['observations']} pixel centres)", flush=True)
                rows.append(row)
    if a.json:
        with open(a.json, "w", encoding="utf-8") as f:
            json.dump({"size": a.size, "supersample": a.supersample, "rows": rows}, f, indent=1)


if __name__ == "__main__":
    main()
