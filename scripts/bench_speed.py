#!/usr/bin/env python3
"""Whole-process times of two clayfit builds, side by side (issue 31's table
in docs/benchmarks.md): each row's command run with BEFORE and AFTER in turn,
PAIRS times each, after a warm-up run of both; the medians of each build's
wall seconds and the median of the pairs' ratios (after / before), which
keeps the ratio fair when the machine's speed drifts.

usage: bench_speed.py BEFORE AFTER [--pairs N] [--work DIR] [--rows NAME,...]

Rows (captures made with AFTER's `clayfit synth` into WORK, once):
  version     clayfit --version (the process start)
  demo        clayfit fit on the demo capture (clayfit synth's default: 16
              photos 640x480, 1.2e6 observations)
  diligent    clayfit fit tests/diligent_ball.capture.json (skipped without
              ../shared/data/diligent_ball)
  sphere96    clayfit fit on a 96-image synthetic sphere (clayfit synth
              --images 96; 7.2e6 observations)
  tone        clayfit fit on 12 8-bit sRGB photos 320x240 (clayfit synth
              --model M2 --images 12 --size 320x240) declared sRGB with
              tone_curve unknown; the after build's ratio to the same
              capture with the curve known is printed too
  report      clayfit report of the demo's fit
Prints a Markdown table to stdout."""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
DILIGENT = os.path.join(ROOT, "tests", "diligent_ball.capture.json")
SHARED = os.path.join(ROOT, "..", "shared", "data", "diligent_ball")


def run(argv):
    """Wall seconds of one process (its output thrown away)."""
    t = time.perf_counter()
    subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    return time.perf_counter() - t


def synth(clayfit, folder, args):
    if not os.path.exists(os.path.join(folder, "capture.json")):
        subprocess.run([clayfit, "--quiet", "synth", "-o", folder, *args], check=True,
                       stdout=subprocess.DEVNULL)
    return os.path.join(folder, "capture.json")


def tone_captures(clayfit, work):
    """The 8-bit capture declared sRGB with its curve known, and unknown."""
    known = synth(clayfit, os.path.join(work, "tone"),
                  ["--model", "M2", "--images", "12", "--size", "320x240", "--format", "png8",
                   "--param", "albedo=0.6,0.4,0.3", "--param", "roughness=0.3",
                   "--param", "f0=0.04", "--param", "diffuse_roughness=0.3"])
    unknown = os.path.join(work, "tone", "unknown.json")
    doc = json.load(open(known))
    doc["colour"] = dict(doc.get("colour", {}), encoding="srgb", tone_curve="unknown")
    with open(unknown, "w") as f:
        json.dump(doc, f, indent=1)
    return known, unknown


def rows(after, work):
    """name -> a function making the row's captures and returning (description, argv after
    the clayfit program); the captures are made only for the rows asked for."""
    out = os.path.join(work, "out")

    def demo():
        return synth(after, os.path.join(work, "demo"), [])

    def report():
        fitted = os.path.join(work, "demo_fit")
        subprocess.run([after, "--quiet", "fit", demo(), "-o", fitted], check=True,
                       stdout=subprocess.DEVNULL)
        return ("`clayfit report` of the demo's fit",
                ["--quiet", "report", os.path.join(fitted, "fit.json"), "-o",
                 os.path.join(work, "report")])

    table = {
        "version": lambda: ("`clayfit --version` (the process start)", ["--version"]),
        "demo": lambda: ("`clayfit fit` the demo (16 photos, 1.2·10⁶ observations)",
                         ["--quiet", "fit", demo(), "-o", out]),
        "sphere96": lambda: ("`clayfit fit` a 96-image sphere (7.2·10⁶ observations)",
                             ["--quiet", "fit", synth(after, os.path.join(work, "sphere96"),
                                                      ["--images", "96"]), "-o", out]),
        "tone": lambda: ("`clayfit fit` 12 8-bit sRGB photos, tone curve unknown",
                         ["--quiet", "fit", tone_captures(after, work)[1], "-o", out]),
        "report": report,
    }
    if os.path.isdir(SHARED):
        table["diligent"] = lambda: ("`clayfit fit` DiLiGenT's ball",
                                     ["--quiet", "fit", DILIGENT, "-o", out])
    order = ["version", "demo", "diligent", "sphere96", "tone", "report"]
    return {name: table[name] for name in order if name in table}


def pairs(first, second, count):
    """Medians of two commands' wall seconds, run in turn, and of the
    pairs' ratios second / first."""
    run(first)  # warm-up: the page cache, both commands
    run(second)
    b, a = [], []
    for _ in range(count):
        b.append(run(first))
        a.append(run(second))
    ratio = statistics.median(x / y for x, y in zip(a, b))
    return statistics.median(b), statistics.median(a), ratio


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--work", default=os.path.join(ROOT, "out", "bench_speed"))
    ap.add_argument("--rows", default="")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    table = rows(args.after, args.work)
    wanted = [r for r in args.rows.split(",") if r] or list(table)
    print("| row | before (s) | after (s) | after / before |")
    print("|---|---|---|---|")
    for name in wanted:
        description, argv = table[name]()
        b, a, ratio = pairs([args.before, *argv], [args.after, *argv], args.pairs)
        print(f"| {description} | {b:.3f} | {a:.3f} | {ratio:.2f} |")
        sys.stdout.flush()
        if name == "tone":  # the curve's cost: unknown against known, the after build
            known = tone_captures(args.after, args.work)[0]
            argv_known = ["--quiet", "fit", known, "-o", os.path.join(args.work, "out")]
            k, u, r = pairs([args.after, *argv_known], [args.after, *argv], args.pairs)
            print(f"| the same photos with the curve known (after) | | {k:.3f} | "
                  f"unknown / known: {r:.2f} |")
            sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
