#!/usr/bin/env python3
"""Write one fit.json per model M0..M4, M2T, M4T (data_schema/fit.schema.json) with
chosen parameters, as `clayfit fit --model Mk` would, without fitting: the
fixtures of the export tests. The parameter table comes from
`clayfit models --json`. M4 uses oil (film_f0 0.06, above glTF's fixed
clear-coat F0 0.04) so that the range warnings are exercised.

usage: make_fits.py CLAYFIT OUTDIR
"""
import json
import subprocess
import sys

VALUES = {
    "M0": {"albedo": [0.6, 0.45, 0.3]},
    "M1": {"albedo": [0.55, 0.4, 0.3], "diffuse_roughness": 0.35},
    "M2": {"albedo": [0.5, 0.4, 0.3], "diffuse_roughness": 0.3, "roughness": 0.3, "f0": 0.05},
    "M3": {"albedo": [0.5, 0.4, 0.3], "diffuse_roughness": 0.2, "roughness": 0.4, "f0": 0.04,
           "coat_weight": 0.7, "coat_gloss": 0.8},
    "M4": {"albedo": [0.62, 0.41, 0.28], "diffuse_roughness": 0.5, "film_roughness": 0.12,
           "film_f0": 0.06, "optical_depth": [0.3, 0.2, 0.1], "base_roughness": 0.55,
           "base_f0": 0.004},
}
# The tailed twins (docs/presets.md, "Tailed lobes in GGX-only formats"): the
# twin's values and a long tail; M2T-tail2 at tail 2, where the GGX written
# is the fit's own (r, F0) and the loss 0.
VALUES["M2T"] = dict(VALUES["M2"], tail=1.7)
VALUES["M4T"] = dict(VALUES["M4"], tail=1.8)
TAIL2 = {"M2T-tail2": ("M2T", dict(VALUES["M2"], tail=2.0))}


def fit_json(model, values):
    params = {}
    slots = []
    for p in model["parameters"]:
        v = values[p["name"]]
        sd = [0.001, 0.002, 0.003] if p["components"] == 3 else 0.001
        params[p["name"]] = {"value": v, "sd": sd, "unit": p["unit"], "status": "fitted",
                             "lower": p["lower"], "upper": p["upper"], "meaning": p["meaning"]}
        if p["components"] == 3:
            slots += [f"{p['name']}[{c}]" for c in "rgb"]
        else:
            slots.append(p["name"])
    derived = None
    if model["code"] in ("M4", "M4T"):
        tau = values["optical_depth"]
        d = sum(tau) / 3 / 0.8
        derived = {"density": d, "convention": "mean absorption 0.8 (docs/model.md §3.6)",
                   "absorption": [t / d for t in tau]}
    n = len(slots)
    start = {k: v for k, v in values.items()}
    return {
        "clayfit_fit": 1, "clayfit_version": "0.1.0", "model_version": 2,
        "created": "2026-11-22T12:00:00Z",
        "capture": {"path": "capture.json", "name": "fixture", "images": 2,
                    "observations": 1000, "radiometry": "absolute"},
        "model": {"code": model["code"], "name": model["name"]},
        "params": params, "derived": derived,
        "scale": {"value": 1.0, "sd": 0.0, "fitted": False},
        "correlation": {"parameters": slots,
                        "matrix": [[1.0 if a == b else 0.0 for b in range(n)] for a in range(n)]},
        "held": [], "not_constrained": [], "at_bound": [],
        "noise": {"model": "capture", "sigma": 0.0},
        "loss": {"type": "huber", "scale_sigma": 3.0},
        "residuals": {"count": 3000, "censored": 0, "rejected": 0, "rmse": 0.001,
                      "relative_rmse": 0.01,
                      "per_image": [{"name": f"{k:03d}.exr", "rmse": 0.001, "relative_rmse": 0.01,
                                     "exposure": 1.0} for k in range(2)],
                      "highlight_cores": {"radius_px": 3.0, "count": 40, "rmse": 0.002,
                                          "relative_rmse": 0.02,
                                          "rest": {"count": 2960, "rmse": 0.001,
                                                   "relative_rmse": 0.01},
                                          "meaning": "fixture"}},
        "solver": {"iterations": 5, "solves": 1, "termination": "CONVERGENCE", "seconds": 0.1,
                   "final_cost": 1.0},
        "starts": [{"start": start, "end": start, "cost": 1.0, "iterations": 5, "stopped": False}],
        "best_start": 0, "warnings": [],
        "timing": {"load_s": 0.1, "fit_s": 0.2, "total_s": 0.3, "choice_s": 0.0,
                   "stages": {"start": 0.0, "refine": 0.0, "solve": 0.1, "statistics": 0.0}},
        "choice": {"mode": "forced", "chosen": model["code"], "candidates": []},
        "footprint": {"mode": "centre", "samples_per_side": 0, "tolerance": 0.002,
                      "observations": 0, "samples": 0, "max_samples_per_side": 1,
                      "meaning": "fixture"},
        "response": {"value": 1.0, "sd": 0.0, "fitted": False, "meaning": "fixture"},
        "sample": None,
    }


def main():
    clayfit, out = sys.argv[1], sys.argv[2]
    models = json.loads(subprocess.run([clayfit, "models", "--json"], check=True,
                                       capture_output=True, text=True).stdout)["models"]
    import os
    for model in models:
        folder = os.path.join(out, model["code"])
        os.makedirs(folder, exist_ok=True)
        with open(os.path.join(folder, "fit.json"), "w", encoding="utf-8") as f:
            json.dump(fit_json(model, VALUES[model["code"]]), f, indent=2)
    by_code = {m["code"]: m for m in models}
    for name, (code, values) in TAIL2.items():
        os.makedirs(os.path.join(out, name), exist_ok=True)
        with open(os.path.join(out, name, "fit.json"), "w", encoding="utf-8") as f:
            json.dump(fit_json(by_code[code], values), f, indent=2)
    # a fit.json with a wrong type, for the error tests
    bad = fit_json(models[2], VALUES["M2"])
    bad["params"]["roughness"]["value"] = "0.3"
    os.makedirs(os.path.join(out, "bad"), exist_ok=True)
    with open(os.path.join(out, "bad", "fit.json"), "w", encoding="utf-8") as f:
        json.dump(bad, f, indent=2)
    # model versions (docs/model.md, top): a fit.json of version 1, written
    # before the key existed (Schlick's Fresnel), and one of an unknown version
    for name, version in (("M2-v1", None), ("M2-v3", 3)):
        old = fit_json(models[2], VALUES["M2"])
        del old["model_version"]
        if version is not None:
            old["model_version"] = version
        os.makedirs(os.path.join(out, name), exist_ok=True)
        with open(os.path.join(out, name, "fit.json"), "w", encoding="utf-8") as f:
            json.dump(old, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
