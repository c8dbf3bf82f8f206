#!/usr/bin/env python3
"""The solver's ablation (docs/studies/2026-11-26-solver-ablation.md):
`clayfit fit` on the bench rows with two binaries in alternating runs,
A B A B ..., and per row the medians of the wall and CPU times (user +
system of the process), of their ratios A/B taken
pair by pair, and each binary's iterations, final cost and relative RMSE.

usage: rows.py A B PAIRS --work DIR --demo CAPTURE [--diligent CAPTURE]
               [--json FILE] ROW...

DIR is `clayfit bench fit --work DIR`'s (its synthetic M4 captures), CAPTURE
the demo's (`clayfit synth -o DIR`: DIR/capture.json) and DiLiGenT's
(tests/diligent_ball.capture.json). ROW: any of the names in rows()."""
import argparse
import json
import resource
import statistics
import subprocess
import time


def rows(work, demo, diligent):
    s = lambda size: f"{work}/synth_M4_{size}/capture.json"
    centre = ["--model", "M4", "--footprint", "centre"]
    return {
        "demo": [demo],
        "s16_all": [s("16x480x360"), *centre, "--budget", "all"],
        "s16_def": [s("16x480x360"), *centre],
        "s8_all": [s("8x320x240"), *centre, "--budget", "all"],
        "s8_10k": [s("8x320x240"), *centre, "--budget", "10000"],
        "s2_all": [s("2x240x180"), *centre, "--budget", "all"],
        "dil_m4": [diligent, "--model", "M4"],
        "dil_m4_all": [diligent, "--model", "M4", "--budget", "all"],
        "dil_30k_imp": [diligent, *centre, "--budget", "30000", "--sampling", "importance"],
        "dil_10k_uni": [diligent, *centre, "--budget", "10000", "--sampling", "uniform"],
        "dil_30k_uni": [diligent, *centre, "--budget", "30000", "--sampling", "uniform"],
        "dil_30k_str": [diligent, *centre, "--budget", "30000"],
        "dil_100k_imp": [diligent, *centre, "--sampling", "importance"],
        "s8_10k_uni": [s("8x320x240"), *centre, "--budget", "10000", "--sampling", "uniform"],
        "dil_auto": [diligent],
    }


def cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(binary, args, out):
    c0, t0 = cpu_children(), time.perf_counter()
    p = subprocess.run([binary, "--quiet", "fit", *args, "-o", out],
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall, cpu = time.perf_counter() - t0, cpu_children() - c0
    if p.returncode != 0:
        return wall, cpu, {"failed": True}
    with open(f"{out}/fit.json") as f:
        doc = json.load(f)
    return wall, cpu, {"model": doc["model"]["code"], "iterations": doc["solver"]["iterations"],
                       "cost": doc["solver"]["final_cost"],
                       "rmse": doc["residuals"]["relative_rmse"],
                       "params": {k: v["value"] for k, v in doc["params"].items()},
                       "sds": {k: v.get("sd") for k, v in doc["params"].items()}}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("pairs", type=int)
    ap.add_argument("--work", required=True)
    ap.add_argument("--demo", required=True)
    ap.add_argument("--diligent", default="tests/diligent_ball.capture.json")
    ap.add_argument("--json")
    ap.add_argument("row", nargs="+")
    o = ap.parse_args()
    table, res = rows(o.work, o.demo, o.diligent), {}
    for row in o.row:
        w, c, r, fig = {"A": [], "B": []}, {"A": [], "B": []}, {"w": [], "c": []}, {}
        for _ in range(o.pairs):
            for tag, binary in (("A", o.a), ("B", o.b)):
                wall, cpu, fig[tag] = run(binary, table[row], f"/tmp/ablation_{tag}_{row}")
                w[tag].append(wall)
                c[tag].append(cpu)
            r["w"].append(w["A"][-1] / w["B"][-1])
            r["c"].append(c["A"][-1] / c["B"][-1])
        med = statistics.median
        res[row] = {"wall": [med(w["A"]), med(w["B"])], "cpu": [med(c["A"]), med(c["B"])],
                    "wall_ratio": med(r["w"]), "cpu_ratio": med(r["c"]),
                    "wall_ratios": r["w"], "cpu_ratios": r["c"], "A": fig["A"], "B": fig["B"]}
        print(f"{row:12s} wall {med(w['A']):6.2f} {med(w['B']):6.2f} s A/B {med(r['w']):5.3f} "
              f"[{min(r['w']):.2f}-{max(r['w']):.2f}]  cpu {med(c['A']):6.2f} {med(c['B']):6.2f} s "
              f"A/B {med(r['c']):5.3f}  iterations {fig['A'].get('iterations')} / "
              f"{fig['B'].get('iterations')}  cost {fig['A'].get('cost')} / {fig['B'].get('cost')}",
              flush=True)
    if o.json:
        with open(o.json, "w") as f:
            json.dump(res, f, indent=1)


if __name__ == "__main__":
    main()
