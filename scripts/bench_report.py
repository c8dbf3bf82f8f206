#!/usr/bin/env python3
"""Writes bench/RESULTS.md and the speed-against-error plot (SVG) from the
outputs of `clayfit bench eval --json`, `clayfit bench fit --json` and
bench/PEERS.md. usage: bench_report.py EVAL.json FIT.json PEERS.md RESULTS.md PLOT.svg"""
import datetime
import json
import math
import os
import platform
import sys


DEFAULT_BUDGET = 100000  # include/clayfit/fit.h CF_FIT_DEFAULT_BUDGET


def cpu():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def plot(runs, path):
    """Relative RMSE (all pixels) against wall time, log-log, one colour
    per capture, the Pareto front joined."""
    w, h, left, top, pw, ph = 720, 470, 80, 50, 600, 360
    ok = [r for r in runs if r["seconds"] > 0 and r["relative_rmse"] > 0]
    t0, t1 = min(r["seconds"] for r in ok) / 1.3, max(r["seconds"] for r in ok) * 1.3
    e0, e1 = min(r["relative_rmse"] for r in ok) / 1.05, max(r["relative_rmse"] for r in ok) * 1.05
    px = lambda t: left + (math.log(t) - math.log(t0)) / (math.log(t1) - math.log(t0)) * pw
    py = lambda e: top + ph - (math.log(e) - math.log(e0)) / (math.log(e1) - math.log(e0)) * ph
    colours = ["#1040c0", "#c02020", "#10a040", "#a060c0", "#d08000"]
    marks = {"all": "circle", "uniform": "square", "stratified": "diamond", "importance": "triangle"}
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">',
           f'<rect width="100%" height="100%" fill="white"/><text x="{w/2}" y="22" text-anchor="middle" font-size="14">clayfit: relative RMSE on all pixels against wall time</text>',
           f'<rect x="{left}" y="{top}" width="{pw}" height="{ph}" fill="none" stroke="black"/>']
    for i in range(6):
        t = math.exp(math.log(t0) + (math.log(t1) - math.log(t0)) * i / 5)
        e = math.exp(math.log(e0) + (math.log(e1) - math.log(e0)) * i / 5)
        out.append(f'<text x="{px(t):.1f}" y="{top+ph+16}" text-anchor="middle">{t:.3g}</text>')
        out.append(f'<text x="{left-6}" y="{py(e)+4:.1f}" text-anchor="end">{100*e:.3g} %</text>')
    out.append(f'<text x="{left+pw/2}" y="{h-12}" text-anchor="middle">wall time of the fit, s (log)</text>')
    out.append(f'<text transform="translate(16 {top+ph/2}) rotate(-90)" text-anchor="middle">relative RMSE (log)</text>')
    captures = sorted({r["capture"] for r in ok}, key=lambda c: [r["observations"] for r in ok if r["capture"] == c][0])
    for ci, cap in enumerate(captures):
        colour = colours[ci % len(colours)]
        mine = [r for r in ok if r["capture"] == cap]
        front = sorted([r for r in mine if r["pareto"]], key=lambda r: r["seconds"])
        if len(front) > 1:
            pts = " ".join(f"{px(r['seconds']):.1f},{py(r['relative_rmse']):.1f}" for r in front)
            out.append(f'<polyline points="{pts}" fill="none" stroke="{colour}" stroke-width="1.5"/>')
        for r in mine:
            x, y = px(r["seconds"]), py(r["relative_rmse"])
            shape = marks.get(r["sampling"], "circle")
            if shape == "circle":
                out.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="5" fill="{colour}"/>')
            elif shape == "square":
                out.append(f'<rect x="{x-4:.1f}" y="{y-4:.1f}" width="8" height="8" fill="{colour}"/>')
            elif shape == "diamond":
                out.append(f'<polygon points="{x:.1f},{y-6:.1f} {x+6:.1f},{y:.1f} {x:.1f},{y+6:.1f} {x-6:.1f},{y:.1f}" fill="{colour}"/>')
            else:
                out.append(f'<polygon points="{x:.1f},{y-6:.1f} {x+6:.1f},{y+5:.1f} {x-6:.1f},{y+5:.1f}" fill="{colour}"/>')
        out.append(f'<text x="{left+pw-10}" y="{top+18+16*ci}" text-anchor="end" fill="{colour}">{cap}</text>')
    out.append(f'<text x="{left}" y="{top-6}" font-size="11">circle: all observations; square: uniform; diamond: stratified; triangle: importance; line: Pareto front</text>')
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def main():
    eval_path, fit_path, peers_path, results_path, plot_path = sys.argv[1:6]
    start_seconds = float(sys.argv[6]) if len(sys.argv) > 6 else None
    cli_runs = []
    if len(sys.argv) > 7 and os.path.exists(sys.argv[7]):
        with open(sys.argv[7]) as f:
            cli_runs = json.load(f)["runs"]
    with open(fit_path) as f:
        fit = json.load(f)
    with open(eval_path) as f:
        ev = json.load(f)
    runs = fit["runs"]
    plot(runs, plot_path)
    lines = [f"# clayfit: speed against error",
             "",
             f"Measured {datetime.date.today().isoformat()} on {os.cpu_count()} cores ({cpu()}), "
             f"Release build, by `bash scripts/bench.sh`. Each fit is a process of its own (wall time "
             "includes loading the capture; peak memory is the process's). Synthetic captures: "
             "`clayfit synth` float EXR, one sample per pixel, the default noise, the model at its "
             "default parameters; the worst error is over every parameter, in units of "
             "max(|truth|, range width). The machine is shared: runs vary by up to about 1.5x.",
             "",
             f"![speed against error]({os.path.basename(plot_path)})",
             "",
             "| capture | observations | budget | sampling | time (s) | peak memory (MB) | relative RMSE, all pixels | worst parameter error | solve stage (s) | iterations | Pareto | default |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    def is_default(r):  # the tool's default: a budget of 1e5, stratified
        if r["observations"] <= DEFAULT_BUDGET:
            return not r["budget"]
        return r["budget"] == DEFAULT_BUDGET and r["sampling"] == "stratified"
    for r in runs:
        we = "" if r["worst_error"] is None else f"{r['worst_error']:.3g}"
        lines.append(f"| {r['capture']} | {r['observations']} | {r['budget'] or 'all'} | {r['sampling']} | "
                     f"{r['seconds']:.2f} | {r['peak_mb']:.0f} | {100*r['relative_rmse']:.4f} % | {we} | "
                     f"{r['solve_seconds']:.2f} | {r['iterations']} | {'*' if r['pareto'] else ''} | "
                     f"{'default' if is_default(r) else ''} |")
    lines += ["", f"The tool's default (`CF_FIT_DEFAULT_BUDGET`) is a budget of {DEFAULT_BUDGET} "
              "observations, stratified by half-angle: every observation where there are fewer.", "",
              "Against the fit with every observation, per capture (time ratio; relative RMSE "
              "over all pixels, the default's against every observation's):", ""]
    for cap in dict.fromkeys(r["capture"] for r in runs):
        rows = [r for r in runs if r["capture"] == cap and r["relative_rmse"] is not None]
        full = [r for r in rows if not r["budget"]]
        dflt = [r for r in rows if is_default(r)]
        if full and dflt and dflt[0] is not full[0]:
            f0, d0 = full[0], dflt[0]
            lines.append(f"- {cap}: {f0['seconds']:.2f} s / {d0['seconds']:.2f} s = "
                         f"{f0['seconds']/d0['seconds']:.1f}x faster; "
                         f"{100*d0['relative_rmse']:.4f} % against {100*f0['relative_rmse']:.4f} % "
                         f"({100*(d0['relative_rmse']/f0['relative_rmse']-1):+.2f} %)")
    lines += ["",
              "## The evaluator's floor", "",
              "| capture | one value+gradient pass (s) | iterations | floor (s) | solve stage (s) | overhead |",
              "|---|---|---|---|---|---|"]
    for fl in fit["floor"]:
        lines.append(f"| {fl['capture']} | {fl['pass_seconds']:.4f} | {fl['iterations']} | {fl['floor_seconds']:.3f} | "
                     f"{fl['solve_seconds']:.2f} | {100*(fl['solve_seconds']/fl['floor_seconds']-1):.0f} % |")
    sc = fit["scaling"]
    fmt = lambda v, f: "n/a" if v is None else format(v, f)
    lines += ["", "## Scaling", "",
              f"Over the synthetic captures with every observation: time ~ n^{fmt(sc['time_exponent'], '.2f')}, "
              f"peak memory ~ n^{fmt(sc['memory_exponent'], '.2f')}, "
              f"{fmt(sc['bytes_per_observation'], '.0f')} bytes of peak memory per observation.", "",
              *(["## `clayfit fit` as a user runs it", "",
                 "The runs above evaluate pixel centres (`o.footprint = 1`), to compare budgets "
                 "alone. `clayfit fit` integrates a pixel where a lobe is narrower than it "
                 "(`--footprint auto`, Gauss-Legendre pairs); on DiLiGenT's highlight that is "
                 "most of the solve. `scripts/bench_cli.py`, each a process of its own:", "",
                 "| capture | arguments | wall (s) | load (s) | start (s) | refine (s) | solve (s) | iterations | integrated observations | samples | largest S | relative RMSE |",
                 "|---|---|---|---|---|---|---|---|---|---|---|---|",
                 *[f"| {c['capture']} | `{c['arguments']}` | {c['wall_seconds']:.2f} | "
                   f"{c['timing']['load_s']:.2f} | {c['timing']['stages']['start']:.2f} | "
                   f"{c['timing']['stages']['refine']:.2f} | {c['timing']['stages']['solve']:.2f} | "
                   f"{c['iterations']} | {c['footprint_observations']} | {c['footprint_samples']} | "
                   f"{c['footprint_max']} | {100*c['relative_rmse']:.4f} % |" for c in cli_runs],
                 ""] if cli_runs else []),
              *([f"## Process start", "",
                 f"Starting a `clayfit` process (`clayfit --version`, the best of 5) takes "
                 f"{start_seconds:.2f} s, almost all of it the dynamic loader binding "
                 "OpenImageIO's shared libraries (Debian's build links about 260, FFmpeg, "
                 "OpenVDB, GDAL and DCMTK among them). Every `clayfit` command pays it once; "
                 "the times above do not include it (each run is a child forked from a "
                 "process that has already loaded them).", ""] if start_seconds is not None else []),
              "## The evaluator alone (`clayfit bench eval`)", "",
              "```", json.dumps(ev, indent=1)[:3000], "```", ""]
    if os.path.exists(peers_path):
        with open(peers_path) as f:
            lines += ["## The peers (from bench/PEERS.md)", "", f.read()]
    with open(results_path, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
