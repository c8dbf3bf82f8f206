#!/usr/bin/env python3
"""The round trip through photos clayfit did not render (issue 19 item 2; docs/roundtrip.md).

usage: scripts/roundtrip.py CLAYFIT WORKDIR [--views N] [--size WxH] [--samples S]
           [--light flash|hdri] [--hdri MAP] [--encoding png8|linear|both]
           [--hdri-strength K] [--env-count K] [--base-color R,G,B] [--roughness R]
           [--specular S] [--arc DEG] [--bounces N] [--material principled|lambert]
           [--model M ...] [--reuse] [--json OUT.json]

Stages, each timed:
  render   Blender 3.4 builds and renders the scene (scripts/blender_scene.py): a Principled
           v1 sphere of radius 1 on a textured ground before a textured backdrop, N views;
  colmap   COLMAP 3.8 on the CPU on the 8-bit renders: feature_extractor (one PINHOLE camera
           with the known intrinsics, not refined), exhaustive_matcher, mapper,
           model_converter to text. clayfit takes the poses from this model only;
  sphere   `clayfit inspect` finds the sphere from its silhouettes in COLMAP's units; its
           known radius (1) gives the scale s (COLMAP units per Blender unit);
  fit      `clayfit fit` (the model choice on, and each --model given) of the capture whose
           flash is the scene's, in COLMAP's units: offset x s, intensity x s^2 (E = I/d^2);
           or whose environment is the map's upper half (the ground hides the lower), turned
           into COLMAP's frame by the similarity below, reduced to --env-count lights;
  compare  the fit against the Principled truth through the exporter's v1 mapping
           (`clayfit export --format blender`): Roughness = r and Specular = F0 / 0.08 exactly,
           Base Color = k x albedo per channel (the least-squares colour, linear in the albedo),
           so the albedo the truth's Base Color stands for is albedo x truth / exported.
           The sphere's centre is compared after a similarity from COLMAP's camera centres
           to Blender's (Horn's quaternion method).

Exit status: 0 when every stage ran, 1 when one failed (the message says which), 2 on bad
usage. The summary is printed and written as JSON (--json). Needs `blender` and `colmap`.
"""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

from scene_compare import camera_centre, rotation

HERE = os.path.dirname(os.path.abspath(__file__))


def parse_args():
    p = argparse.ArgumentParser(prog="roundtrip.py")
    p.add_argument("clayfit")
    p.add_argument("work")
    p.add_argument("--views", type=int, default=8)
    p.add_argument("--size", default="320x240")
    p.add_argument("--samples", type=int, default=32)
    p.add_argument("--light", choices=("flash", "hdri"), default="flash")
    p.add_argument("--hdri")
    p.add_argument("--hdri-strength", type=float, default=0.4)
    p.add_argument("--encoding", choices=("png8", "linear", "both"), default="both")
    p.add_argument("--base-color", default="0.6,0.35,0.2")
    p.add_argument("--roughness", type=float, default=0.35)
    p.add_argument("--specular", type=float, default=0.5)
    p.add_argument("--arc", type=float, default=120.0)
    p.add_argument("--material", choices=("principled", "lambert"), default="principled")
    p.add_argument("--bounces", type=int, default=4, help="Cycles' bounces (0: direct light only)")
    p.add_argument("--model", action="append", default=[],
                   help="also fit this model (auto always runs)")
    p.add_argument("--env-count", type=int, default=32, help="median-cut lights (hdri)")
    p.add_argument("--reuse", action="store_true", help="keep an earlier render and COLMAP model")
    p.add_argument("--json", help="write the summary here too")
    return p.parse_args()


class Stage:
    """A named, timed stage; its failure names it."""

    def __init__(self, times, name):
        self.times, self.name = times, name

    def __enter__(self):
        self.start = time.time()
        print(f"roundtrip: {self.name}...", flush=True)
        return self

    def __exit__(self, *exc):
        self.times[self.name] = self.times.get(self.name, 0.0) + time.time() - self.start
        return False


def run(cmd, log=None):
    with open(log, "w", encoding="utf-8") if log else open(os.devnull, "w") as out:
        r = subprocess.run(cmd, stdout=out, stderr=subprocess.STDOUT if log else None, check=False)
    if r.returncode != 0:
        raise SystemExit(f"roundtrip: failed ({r.returncode}): {' '.join(cmd)}"
                         + (f" (log: {log})" if log else ""))


def render(args, scene_dir):
    cmd = ["blender", "-b", "--factory-startup", "--python-exit-code", "1", "-P",
           os.path.join(HERE, "blender_scene.py"), "--", "--out", scene_dir,
           "--views", str(args.views), "--size", args.size, "--samples", str(args.samples),
           "--light", args.light, "--base-color", args.base_color,
           "--roughness", str(args.roughness), "--specular", str(args.specular),
           "--arc", str(args.arc), "--bounces", str(args.bounces),
           "--material", args.material]
    if args.hdri:
        cmd += ["--hdri", args.hdri, "--hdri-strength", str(args.hdri_strength)]
    run(cmd, os.path.join(scene_dir + ".log"))


def colmap(scene, scene_dir, col):
    """SfM on the 8-bit renders; returns the text model's folder and COLMAP's own figures."""
    shutil.rmtree(col, ignore_errors=True)
    os.makedirs(os.path.join(col, "sparse"))
    db, images = os.path.join(col, "db.db"), os.path.join(scene_dir, "png8")
    cam = scene["camera"]
    run(["colmap", "feature_extractor", "--database_path", db, "--image_path", images,
         "--ImageReader.camera_model", "PINHOLE", "--ImageReader.single_camera", "1",
         "--ImageReader.camera_params", ",".join(repr(x) for x in cam["params"]),
         "--SiftExtraction.use_gpu", "0", "--SiftExtraction.num_threads", "2"],
        os.path.join(col, "feature_extractor.log"))
    run(["colmap", "exhaustive_matcher", "--database_path", db, "--SiftMatching.use_gpu", "0",
         "--SiftMatching.num_threads", "2", "--SiftMatching.guided_matching", "1"],
        os.path.join(col, "exhaustive_matcher.log"))
    # min_model_size 3: COLMAP's default (10) drops every model of fewer images
    run(["colmap", "mapper", "--database_path", db, "--image_path", images,
         "--output_path", os.path.join(col, "sparse"), "--Mapper.num_threads", "2",
         "--Mapper.min_model_size", "3", "--Mapper.ba_refine_focal_length", "0",
         "--Mapper.ba_refine_principal_point", "0", "--Mapper.ba_refine_extra_params", "0"],
        os.path.join(col, "mapper.log"))
    models = sorted(os.listdir(os.path.join(col, "sparse")))
    if not models:
        raise SystemExit("roundtrip: COLMAP's mapper built no model")
    best, best_n = None, -1
    for m in models:  # the model with the most registered images
        log = os.path.join(col, f"analyzer_{m}.log")
        run(["colmap", "model_analyzer", "--path", os.path.join(col, "sparse", m)], log)
        text = open(log, encoding="utf-8").read()
        n = int(re.search(r"Registered images: (\d+)", text).group(1))
        if n > best_n:
            best, best_n, stats = m, n, text
    txt = os.path.join(col, "text")
    os.makedirs(txt, exist_ok=True)
    run(["colmap", "model_converter", "--input_path", os.path.join(col, "sparse", best),
         "--output_path", txt, "--output_type", "TXT"], os.path.join(col, "model_converter.log"))
    figures = {"models": len(models), "registered": best_n,
               "points": int(re.search(r"Points: (\d+)", stats).group(1)),
               "reprojection_px": float(re.search(r"Mean reprojection error: ([0-9.eE+-]+)px",
                                                  stats).group(1))}
    return txt, figures


def read_images_txt(txt):
    """name -> (qvec, tvec) of COLMAP's text model."""
    out = {}
    with open(os.path.join(txt, "images.txt"), encoding="utf-8") as f:
        lines = [l for l in f if not l.startswith("#")]
    for k in range(0, len(lines), 2):
        v = lines[k].split()
        if v:
            out[v[9]] = ([float(x) for x in v[1:5]], [float(x) for x in v[5:8]])
    return out


def model_for(txt, out, extension):
    """The text model with its images renamed to the encoding's files (the same photos)."""
    os.makedirs(out, exist_ok=True)
    for name in ("cameras.txt", "points3D.txt"):
        shutil.copy(os.path.join(txt, name), os.path.join(out, name))
    with open(os.path.join(txt, "images.txt"), encoding="utf-8") as f:
        lines = f.readlines()
    body = [l for l in lines if not l.startswith("#")]
    with open(os.path.join(out, "images.txt"), "w", encoding="utf-8") as f:
        f.writelines(l for l in lines if l.startswith("#"))
        for k, line in enumerate(body):
            if k % 2 == 0 and line.strip():
                v = line.split()
                v[9] = os.path.splitext(v[9])[0] + extension
                line = " ".join(v) + "\n"
            f.write(line)


def jacobi_top_eigenvector(a):
    """The eigenvector of the largest eigenvalue of a symmetric 4 x 4 matrix (Jacobi sweeps)."""
    n = 4
    a = [row[:] for row in a]
    v = [[float(i == j) for j in range(n)] for i in range(n)]
    for _ in range(100):
        off = sum(a[i][j] ** 2 for i in range(n) for j in range(n) if i != j)
        if off < 1e-30:
            break
        for p in range(n):
            for q in range(p + 1, n):
                if abs(a[p][q]) < 1e-300:
                    continue
                theta = (a[q][q] - a[p][p]) / (2 * a[p][q])
                t = math.copysign(1.0, theta) / (abs(theta) + math.sqrt(theta * theta + 1))
                c = 1 / math.sqrt(t * t + 1)
                s = t * c
                for k in range(n):
                    akp, akq = a[k][p], a[k][q]
                    a[k][p], a[k][q] = c * akp - s * akq, s * akp + c * akq
                for k in range(n):
                    apk, aqk = a[p][k], a[q][k]
                    a[p][k], a[q][k] = c * apk - s * aqk, s * apk + c * aqk
                for k in range(n):
                    vkp, vkq = v[k][p], v[k][q]
                    v[k][p], v[k][q] = c * vkp - s * vkq, s * vkp + c * vkq
    top = max(range(n), key=lambda i: a[i][i])
    return [v[k][top] for k in range(n)]


def similarity(src, dst):
    """s, R, t with dst ~ s R src + t (Horn 1987, unit quaternions)."""
    n = len(src)
    cs = [sum(p[k] for p in src) / n for k in range(3)]
    cd = [sum(p[k] for p in dst) / n for k in range(3)]
    a = [[p[k] - cs[k] for k in range(3)] for p in src]
    b = [[p[k] - cd[k] for k in range(3)] for p in dst]
    m = [[sum(a[i][r] * b[i][c] for i in range(n)) for c in range(3)] for r in range(3)]
    sxx, sxy, sxz = m[0]
    syx, syy, syz = m[1]
    szx, szy, szz = m[2]
    nmat = [[sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
            [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
            [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
            [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz]]
    q = jacobi_top_eigenvector(nmat)
    r = rotation(q)
    scale = math.sqrt(sum(x * x for p in b for x in p) / sum(x * x for p in a for x in p))
    t = [cd[k] - scale * sum(r[k][j] * cs[j] for j in range(3)) for k in range(3)]
    return scale, r, t


def apply(sim, p):
    s, r, t = sim
    return [s * sum(r[k][j] * p[j] for j in range(3)) + t[k] for k in range(3)]


def inspect_sphere(clayfit, capture_path, log):
    r = subprocess.run([clayfit, "inspect", capture_path, "--json"], capture_output=True,
                       text=True, check=False)
    with open(log, "w", encoding="utf-8") as f:
        f.write(r.stdout + r.stderr)
    if r.returncode != 0:
        raise SystemExit(f"roundtrip: clayfit inspect failed ({r.returncode}); log: {log}")
    sphere = json.loads(r.stdout)["sphere"]
    return sphere["center"], sphere["radius"]


def write_capture(path, scene, encoding, files, light, scale_units, env=None):
    """A capture in COLMAP's units; the flash (or the map) from the scene builder."""
    colour = {"encoding": "srgb"} if encoding == "png8" else {"encoding": "linear"}
    if light == "flash":
        f = scene["light"]
        lights = [{"type": "flash", "offset": [x * scale_units for x in f["offset"]],
                   "intensity": [f["intensity"] * scale_units ** 2] * 3}]
    else:
        lights = [env]
    capture = {
        "clayfit_capture": 1,
        "name": f"Blender 3.4 round trip ({light}, {encoding}, {len(files)} views)",
        "camera": {"type": "colmap", "model": f"sparse_{encoding}"},
        "images": {"directory": encoding, "files": files},
        "colour": colour,
        "radiometry": "absolute",
        "geometry": {"type": "sphere_from_silhouettes", "margin_px": 2.0},
        "scale": {"sphere_radius_m": scene["sphere"]["radius"]},
        "lights": lights,
    }
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(capture, fh, indent=1)


def read_preset(path):
    """Base Color, Roughness, Specular of the v1 branch of an exported Blender script."""
    text = open(path, encoding="utf-8").read()
    v1 = text[text.index("INPUTS_V1 = {"):]
    def value(name):
        m = re.search(r'"' + re.escape(name) + r'"\s*:\s*(\([^)]*\)|[-0-9.eE+]+)', v1)
        if not m:
            raise SystemExit(f"roundtrip: no '{name}' in {path}'s INPUTS_V1")
        return [float(x) for x in re.findall(r"[-0-9.eE+]+", m.group(1))]
    return {"base_color": value("Base Color")[:3], "roughness": value("Roughness")[0],
            "specular": value("Specular")[0]}


def compare(clayfit, fit_dir, scene):
    fit = json.load(open(os.path.join(fit_dir, "fit.json"), encoding="utf-8"))
    preset = os.path.join(fit_dir, "preset_blender.py")
    run([clayfit, "export", os.path.join(fit_dir, "fit.json"), "--format", "blender", "-o",
         preset])
    exported = read_preset(preset)
    truth = scene["principled"]
    params = {k: v["value"] if isinstance(v, dict) and "value" in v else v
              for k, v in fit["params"].items()}
    out = {"model": fit["model"]["code"], "params": params,
           "relative_rmse": fit["residuals"]["relative_rmse"],
           "termination": fit["solver"]["termination"],
           "seconds": fit.get("timing", {}).get("total_seconds"),
           "exported": exported,
           "roughness_error": exported["roughness"] / truth["roughness"] - 1,
           "specular_error": exported["specular"] / truth["specular"] - 1,
           "base_color_error": [e / t - 1 for e, t in zip(exported["base_color"],
                                                           truth["base_color"])]}
    albedo = params.get("albedo")
    if scene.get("material") == "lambert":  # the control: the albedo is the colour itself
        out["albedo_error"] = [a / t - 1 for a, t in zip(albedo, truth["base_color"])]
    elif isinstance(albedo, list):
        out["albedo_truth"] = [a * t / e for a, t, e in zip(albedo, truth["base_color"],
                                                             exported["base_color"])]
    return out


def upper_half(source, out):
    """The map with its lower half (below the horizon, hidden by the ground) set to 0: what the
    capture gives clayfit (oiiotool, from openimageio-tools)."""
    info = subprocess.run(["oiiotool", "--info", source], capture_output=True, text=True,
                          check=True).stdout
    w, h = (int(x) for x in re.search(r"(\d+) x\s*(\d+)", info).groups())
    run(["oiiotool", source, "--fill:color=0,0,0", f"{w}x{h - h // 2}+0+{h // 2}", "-o", out])
    return out


def environment(scene, sim, count, work):
    """The map's upper half in COLMAP's frame: Blender's map-to-world rotation, then Blender's
    world to COLMAP's by the similarity from the camera centres (COLMAP's frame is arbitrary;
    a user would level it with a known up direction or a chrome ball)."""
    light = scene["light"]
    r = sim[1]  # COLMAP -> Blender; its transpose takes Blender's directions to COLMAP's
    m = light["map_to_world"]
    rot = [[sum(r[k][i] * m[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    upper = upper_half(light["file"], os.path.join(work, "env_upper.exr"))
    return {"type": "environment", "file": os.path.abspath(upper),
            "rotation": [x for row in rot for x in row], "scale": light["strength"],
            "count": count}


def main():
    args = parse_args()
    os.makedirs(args.work, exist_ok=True)
    times = {}
    scene_dir = os.path.join(args.work, "scene")
    if not (args.reuse and os.path.exists(os.path.join(scene_dir, "scene.json"))):
        with Stage(times, "render"):
            render(args, scene_dir)
    scene = json.load(open(os.path.join(scene_dir, "scene.json"), encoding="utf-8"))
    col = os.path.join(args.work, "colmap")
    with Stage(times, "colmap"):
        txt, sfm = colmap(scene, scene_dir, col)
    posed = read_images_txt(txt)
    summary = {"views": len(scene["views"]), "size": args.size, "samples": args.samples,
               "light": args.light, "colmap": sfm, "truth": scene["principled"], "cases": {}}
    names = sorted(posed)
    sim = similarity([camera_centre(*posed[n]) for n in names],
                     [v["centre"] for v in scene["views"] if v["name"] + ".png" in posed])
    truth_c = {v["name"] + ".png": v["centre"] for v in scene["views"]}
    sfm["alignment_rms"] = math.sqrt(sum(
        math.dist(apply(sim, camera_centre(*posed[n])), truth_c[n]) ** 2 for n in names) / len(names))
    encodings = ["png8", "linear"] if args.encoding == "both" else [args.encoding]
    for enc in encodings:
        ext = ".png" if enc == "png8" else ".exr"
        case_dir = os.path.join(args.work, enc)
        os.makedirs(case_dir, exist_ok=True)
        link = os.path.join(case_dir, enc)
        if not os.path.exists(link):
            os.symlink(os.path.join(os.path.abspath(scene_dir), enc), link)
        model_for(txt, os.path.join(case_dir, f"sparse_{enc}"), ext)
        files = [os.path.splitext(n)[0] + ext for n in names]
        capture = os.path.join(case_dir, "capture.json")
        env = environment(scene, sim, args.env_count, args.work) if args.light == "hdri" else None
        with Stage(times, f"sphere_{enc}"):
            write_capture(capture, scene, enc, files, args.light, 1.0, env)
            centre, radius = inspect_sphere(args.clayfit, capture,
                                            os.path.join(case_dir, "inspect.json"))
        s_units = radius / scene["sphere"]["radius"]  # the known radius sets the scale
        write_capture(capture, scene, enc, files, args.light, s_units, env)
        true_c = scene["sphere"]["center"]
        c_b = apply(sim, centre)
        case = {"sphere": {"centre_error_radii": math.dist(c_b, true_c) / scene["sphere"]["radius"],
                           "centre_error_vector": [a - b for a, b in zip(c_b, true_c)],
                           "radius_error": radius * sim[0] / scene["sphere"]["radius"] - 1},
                "fits": {}}
        for model in ["auto"] + args.model:
            fit_dir = os.path.join(case_dir, "fit_" + model)
            with Stage(times, f"fit_{enc}_{model}"):
                cmd = [args.clayfit, "fit", capture, "-o", fit_dir]
                if model != "auto":
                    cmd += ["--model", model]
                run(cmd, fit_dir + ".log")
            case["fits"][model] = compare(args.clayfit, fit_dir, scene)
        summary["cases"][enc] = case
    summary["seconds"] = times
    text = json.dumps(summary, indent=1)
    print(text)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
