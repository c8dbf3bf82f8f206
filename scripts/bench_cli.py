#!/usr/bin/env python3
"""`clayfit fit` as a user runs it (issue 6's benchmark, from scripts/bench.sh):
the forced M4 fit of a capture with the default pixel footprints (auto) and
pixel budget, and with every observation, each a process of its own; wall
time, fit.json's stage times and footprint tally. Writes JSON to stdout.

usage: bench_cli.py CLAYFIT WORK CAPTURE..."""
import json
import subprocess
import sys
import time


def run(clayfit, work, capture, extra):
    out = f"{work}/cli_fit"
    t = time.perf_counter()
    subprocess.run([clayfit, "--quiet", "fit", capture, "-o", out, "--model", "M4", *extra],
                   stdout=subprocess.DEVNULL, check=True)
    wall = time.perf_counter() - t
    with open(f"{out}/fit.json") as f:
        fit = json.load(f)
    return {"capture": capture, "arguments": " ".join(["--model", "M4", *extra]),
            "wall_seconds": wall, "timing": fit["timing"], "iterations": fit["solver"]["iterations"],
            "relative_rmse": fit["residuals"]["relative_rmse"],
            "footprint_observations": fit["footprint"]["observations"],
            "footprint_samples": fit["footprint"]["samples"],
            "footprint_max": fit["footprint"]["max_samples_per_side"]}


def main():
    clayfit, work, captures = sys.argv[1], sys.argv[2], sys.argv[3:]
    runs = []
    for capture in captures:
        for extra in ([], ["--budget", "all"]):
            runs.append(run(clayfit, work, capture, extra))
    json.dump({"runs": runs}, sys.stdout, indent=1)


if __name__ == "__main__":
    main()
