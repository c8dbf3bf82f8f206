#!/usr/bin/env python3
"""Write a small orthographic capture whose sphere comes from its silhouette.

usage: make_ortho_capture.py DIR

DIR/capture.json: an orthographic camera, geometry sphere_from_silhouettes,
one 8-bit photo (a Lambertian sphere lit from the camera) and its mask, a
disc of radius 24 px about pixel (50, 40) (pixel centres at +0.5), in a
96 x 80 image. clayfit synth renders only COLMAP orbits, hence this script.
"""
import json
import math
import os
import shutil
import struct
import sys
import zlib

WIDTH, HEIGHT = 96, 80
CX, CY, RADIUS = 50.0, 40.0, 24.0


def write_png(path, rows):
    """An 8-bit greyscale PNG of rows (lists of 0..255)."""
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))
    raw = b"".join(b"\x00" + bytes(row) for row in rows)
    header = struct.pack(">IIBBBBB", len(rows[0]), len(rows), 8, 0, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) +
                chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def main():
    out = sys.argv[1]
    shutil.rmtree(out, ignore_errors=True)  # no leftover of an earlier run
    os.makedirs(out)
    photo, mask = [], []
    for y in range(HEIGHT):
        photo_row, mask_row = [], []
        for x in range(WIDTH):
            r2 = ((x + 0.5 - CX) ** 2 + (y + 0.5 - CY) ** 2) / RADIUS ** 2
            inside = r2 <= 1.0
            nz = math.sqrt(1.0 - r2) if inside else 0.0
            photo_row.append(round(20 + 200 * nz) if inside else 10)
            mask_row.append(255 if inside else 0)
        photo.append(photo_row)
        mask.append(mask_row)
    write_png(os.path.join(out, "photo.png"), photo)
    write_png(os.path.join(out, "mask.png"), mask)
    capture = {
        "clayfit_capture": 1,
        "name": "orthographic sphere from its silhouette",
        "camera": {"type": "orthographic", "view": [0, 0, 1]},
        "images": {"files": ["photo.png"], "mask": "mask.png"},
        "colour": {"encoding": "linear"},
        "geometry": {"type": "sphere_from_silhouettes", "margin_px": 1},
        "lights": [{"type": "directional", "direction": [0, 0, 1], "irradiance": [1, 1, 1]}],
    }
    with open(os.path.join(out, "capture.json"), "w", encoding="utf-8") as f:
        json.dump(capture, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
