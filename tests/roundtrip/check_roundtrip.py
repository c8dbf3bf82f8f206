#!/usr/bin/env python3
"""The round trip on a small scene (issue 19 item 2; docs/roundtrip.md): Blender 3.4 renders
8 views of a Principled v1 sphere lit by a flash (320x240, 32 samples), COLMAP poses them, clayfit
fits them. Asserts COLMAP registered all 8 views, the fits converged, the sphere and the
parameters within the tolerances below (docs/roundtrip.md states where each comes from).

usage: check_roundtrip.py CLAYFIT WORK [--check-only] [--truth name=value ...]

--check-only checks WORK/summary.json of an earlier run without running anything; --truth
replaces a truth value (roughness, specular, base_color r,g,b) to show that a check fails.
Exit 77 (skip) without blender or colmap.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROUNDTRIP = os.path.join(HERE, "..", "..", "scripts", "roundtrip.py")

# Tolerances of the flash + linear case, M2 through the exporter's v1 mapping. The measured
# errors (docs/roundtrip.md) are Burley's diffuse against Oren-Nayar, the ground's
# inter-reflection and Cycles' noise at 32 samples: roughness +8 %, Base Color +9..11 %,
# Specular +34 %, relative RMSE 10 %. The sphere's centre: 0.015-0.058 radii over runs
# (COLMAP's threads make each run's poses a little different; the similarity to Blender's
# centres alone leaves 0.03).
TOLERANCE = {"roughness": 0.15, "base_color": 0.15, "specular": 0.5, "relative_rmse": 0.13,
             "centre_radii": 0.1, "radius": 0.01}


def parse_args():
    p = argparse.ArgumentParser(prog="check_roundtrip.py")
    p.add_argument("clayfit")
    p.add_argument("work")
    p.add_argument("--check-only", action="store_true")
    p.add_argument("--truth", action="append", default=[])
    return p.parse_args()


def run_roundtrip(args, summary):
    for tool in ("blender", "colmap"):
        if not shutil.which(tool):
            print(f"SKIP: no {tool}")
            sys.exit(77)
    shutil.rmtree(args.work, ignore_errors=True)
    r = subprocess.run([sys.executable, ROUNDTRIP, args.clayfit, args.work, "--views", "8",
                        "--size", "320x240", "--samples", "32", "--encoding", "linear",
                        "--model", "M2", "--json", summary], check=False)
    if r.returncode != 0:
        print(f"FAIL: roundtrip.py exited {r.returncode}")
        sys.exit(1)


def check(summary, overrides):
    s = json.load(open(summary, encoding="utf-8"))
    truth = dict(s["truth"])
    for o in overrides:
        key, _, value = o.partition("=")
        v = [float(x) for x in value.split(",")]
        truth[key] = v if key == "base_color" else v[0]
    failures = []

    def within(what, got, want, tol):
        err = got / want - 1 if want else got
        ok = abs(err) <= tol
        print(f"{'ok' if ok else 'FAIL'}: {what}: {got:.4g} against {want:.4g} "
              f"({100 * err:+.1f} %, tolerance {100 * tol:.0f} %)")
        if not ok:
            failures.append(what)

    views, registered = s["views"], s["colmap"]["registered"]
    print(f"{'ok' if registered == views else 'FAIL'}: COLMAP registered {registered} of {views}"
          f" views (reprojection {s['colmap']['reprojection_px']:.3f} px)")
    if registered != views:
        failures.append("registered")
    case = s["cases"]["linear"]
    sphere = case["sphere"]
    for what, value, tol in (("sphere centre (radii)", sphere["centre_error_radii"], "centre_radii"),
                             ("sphere radius", sphere["radius_error"], "radius")):
        ok = abs(value) <= TOLERANCE[tol]
        print(f"{'ok' if ok else 'FAIL'}: {what} error {value:+.4f} (tolerance {TOLERANCE[tol]})")
        if not ok:
            failures.append(what)
    for model, fit in case["fits"].items():
        ok = fit["termination"] == "CONVERGENCE"
        print(f"{'ok' if ok else 'FAIL'}: fit {model} ({fit['model']}): {fit['termination']}, "
              f"relative RMSE {fit['relative_rmse']:.4f}")
        if not ok:
            failures.append(f"fit {model} converged")
    m2 = case["fits"]["M2"]
    e = m2["exported"]
    within("M2 -> Roughness", e["roughness"], truth["roughness"], TOLERANCE["roughness"])
    within("M2 -> Specular", e["specular"], truth["specular"], TOLERANCE["specular"])
    for c, name in enumerate("RGB"):
        within(f"M2 -> Base Color {name}", e["base_color"][c], truth["base_color"][c],
               TOLERANCE["base_color"])
    rmse_ok = m2["relative_rmse"] <= TOLERANCE["relative_rmse"]
    print(f"{'ok' if rmse_ok else 'FAIL'}: M2 relative RMSE {m2['relative_rmse']:.4f} "
          f"(at most {TOLERANCE['relative_rmse']})")
    if not rmse_ok:
        failures.append("relative RMSE")
    if failures:
        print("FAIL: " + ", ".join(failures))
        return 1
    print("PASS")
    return 0


def main():
    args = parse_args()
    summary = os.path.join(args.work, "summary.json")
    if not args.check_only:
        run_roundtrip(args, summary)
    elif not os.path.exists(summary):
        print(f"SKIP: no {summary} (the round trip did not run)")
        return 77
    return check(summary, args.truth)


if __name__ == "__main__":
    sys.exit(main())
