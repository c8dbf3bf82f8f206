#!/usr/bin/env python3
"""Markdown rows of scripts/roundtrip.py summaries (bench/ROUNDTRIP.md, docs/roundtrip.md).

usage: scripts/roundtrip_table.py LABEL=SUMMARY.json ...
"""
import json
import sys


def pct(x):
    return f"{100 * x:+.1f} %"


def main():
    print("| case | model | Roughness | Specular | Base Color (R, G, B) | relative RMSE | "
          "COLMAP reprojection | sphere centre / radius error | seconds (render, COLMAP, "
          "sphere, fit) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for arg in sys.argv[1:]:
        label, _, path = arg.partition("=")
        s = json.load(open(path, encoding="utf-8"))
        t = s["seconds"]
        for enc, case in s["cases"].items():
            sphere = case["sphere"]
            for model, fit in case["fits"].items():
                e = fit["exported"]
                fits = sum(v for k, v in t.items() if k == f"fit_{enc}_{model}")
                print(f"| {label}, {enc} | {model} → {fit['model']} | {e['roughness']:.3f} "
                      f"({pct(fit['roughness_error'])}) | {e['specular']:.3f} "
                      f"({pct(fit['specular_error'])}) | "
                      + ", ".join(f"{b:.3f}" for b in e["base_color"])
                      + " (" + ", ".join(pct(x) for x in fit["base_color_error"]) + ") | "
                      f"{100 * fit['relative_rmse']:.1f} % | "
                      f"{s['colmap']['reprojection_px']:.3f} px ({s['colmap']['registered']}/"
                      f"{s['views']}) | {sphere['centre_error_radii']:.3f} R / "
                      f"{pct(sphere['radius_error'])} | {t.get('render', 0):.0f}, "
                      f"{t['colmap']:.0f}, {t[f'sphere_{enc}']:.1f}, {fits:.1f} |")


if __name__ == "__main__":
    main()
