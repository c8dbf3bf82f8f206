"""Compare a Blender render with clayfit's own rendering of the same scene,
pixel by pixel inside the sphere (docs/fidelity.md). Runs in Blender's Python,
whose image loader reads OpenEXR (no other dependency):

usage: blender -b --factory-startup --python-exit-code 1 -P scripts/blender_compare.py -- \
           --clayfit CLAYFIT.exr --mask MASK.exr --render BLENDER.exr [--margin PX]
           [--diff DIFF.png] [--json OUT.json]

The pixels compared are those the mask covers fully, at least --margin pixels
(default 2, clayfit's geometry.margin_px) inside the silhouette. The relative
RMSE is clayfit's (fit_residuals.c): sqrt(sum (b - c)^2 / sum c^2) over the
pixels and channels, with c clayfit's value and b Blender's. Also printed: the
ratio of the sums (a global gain), and the relative RMSE after the best gain
(what is left is the shape). The difference image maps (b - c) to grey 0.5 +/-
0.5 at +/- 25 % of clayfit's mean value over the pixels (each channel
apart), black outside the compared pixels. The figures and the image are
scripts/scene_compare.py's, shared with threejs_fidelity.py.
"""
import argparse
import array
import json
import os
import sys

import bpy

# Plain Python, no numpy: Blender started from another Python's environment
# (a pyenv on PATH) runs that Python's site-packages, which may have none.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scene_compare as sc  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="blender_compare.py")
    p.add_argument("--clayfit", required=True)
    p.add_argument("--mask", required=True)
    p.add_argument("--render", required=True)
    p.add_argument("--margin", type=int, default=2)
    p.add_argument("--diff")
    p.add_argument("--json")
    return p.parse_args(argv)


def load(path):
    """An image's RGBA floats (w, h, values), bottom row first (Blender's order, the same
    for every file)."""
    image = bpy.data.images.load(path, check_existing=False)
    image.colorspace_settings.name = "Non-Color"  # the stored values, untouched
    w, h = image.size
    if w == 0 or h == 0:
        raise SystemExit(f"blender_compare: cannot read {path}")
    pixels = array.array("f", bytes(4 * 4 * w * h))
    image.pixels.foreach_get(pixels)
    return w, h, pixels


def write_diff(path, w, h, rgb):
    """sc.diff_values' image as a PNG through Blender (its rows bottom first)."""
    out = array.array("f", [0.0, 0.0, 0.0, 1.0] * (w * h))
    for i in range(w * h):
        out[4 * i:4 * i + 3] = array.array("f", rgb[3 * i:3 * i + 3])
    image = bpy.data.images.new("diff", w, h, alpha=False, float_buffer=False)
    image.colorspace_settings.name = "Non-Color"
    image.pixels.foreach_set(out)
    image.filepath_raw = path
    image.file_format = "PNG"
    image.save()


def main():
    a = parse_args()
    (w, h, c), (wb, hb, b), (wm, hm, m) = load(a.clayfit), load(a.render), load(a.mask)
    if (w, h) != (wb, hb) or (w, h) != (wm, hm):
        raise SystemExit(f"blender_compare: sizes differ: clayfit {w}x{h}, Blender {wb}x{hb}, "
                         f"mask {wm}x{hm}")
    result, inside, mean = sc.compare(c, b, [m[4 * i] for i in range(w * h)], w, h, a.margin,
                                      4, "blender_compare")
    if a.diff:
        write_diff(a.diff, w, h, sc.diff_values(c, b, inside, w, h, mean, 4))
    text = json.dumps(result)
    print("blender_compare:", text)
    if a.json:
        with open(a.json, "w", encoding="utf-8") as f:
            f.write(text + "\n")


main()
