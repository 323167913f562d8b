#!/usr/bin/env python3
"""Summarises the CSVs of `photonmap converge` (scripts/converge.sh writes docs/converge/*.csv).

For each scene it prints the RMSE of every method at every budget (in brackets when the render
took longer than its budget), the best method per budget, and each method's log-log slope of
RMSE against seconds, as measured and net of the reference's own noise
(sqrt(RMSE^2 - noise^2), the noise figures of the references' SCENES.md). Where the path
tracer's line and sppm's would cross if both kept their slopes, it says when.

Usage: python3 scripts/converge_summary.py [DIR (default docs/converge)]
"""
import csv
import math
import os
import sys

# Noise left in each 256x256 reference (RMSE, from batch-to-batch variance; SCENES.md).
NOISE = {"cornell": 0.0009, "caustics": 0.0048, "pointlight": 0.009, "furnace": 0.021}


def slope(points):
    pts = [(math.log(t), math.log(e)) for t, e in points if t > 0 and e > 0]
    if len(pts) < 2:
        return float("nan")
    n = len(pts)
    mx = sum(x for x, _ in pts) / n
    my = sum(y for _, y in pts) / n
    sxx = sum((x - mx) ** 2 for x, _ in pts)
    return sum((x - mx) * (y - my) for x, y in pts) / sxx if sxx > 0 else float("nan")


def main():
    d = sys.argv[1] if len(sys.argv) > 1 else "docs/converge"
    for scene, noise in NOISE.items():
        path = os.path.join(d, scene + ".csv")
        if not os.path.exists(path):
            continue
        rows = list(csv.DictReader(open(path)))
        methods = list(dict.fromkeys(r["method"] for r in rows))
        budgets = sorted({float(r["budget_seconds"]) for r in rows})
        print(f"== {scene} (reference noise {noise})")
        print(f"{'method':<16}" + "".join(f"{b:>16g}" for b in budgets))
        series = {}
        for m in methods:
            cells, pts = [], []
            for b in budgets:
                r = next(x for x in rows if x["method"] == m and float(x["budget_seconds"]) == b)
                t, e = float(r["seconds"]), float(r["rmse"])
                pts.append((t, e))
                cells.append(f"({e:.4f}, {t:.1f} s)" if t > 1.1 * b else f"{e:.4f}")
            series[m] = pts
            print(f"{m:<16}" + "".join(f"{c:>16}" for c in cells))
        best = []
        for b in budgets:
            e, m = min((float(x["rmse"]), x["method"]) for x in rows if float(x["budget_seconds"]) == b)
            best.append(f"{b:g} s: {m} {e:.4f}")
        print("best: " + "; ".join(best))
        for m, pts in series.items():
            net = [(t, math.sqrt(max(e * e - noise * noise, 1e-12))) for t, e in pts]
            print(f"slope {m:<16} measured {slope(pts):+.2f}   net of the reference noise {slope(net):+.2f}")
        if "path" in series and "sppm" in series:
            (tp, ep), (ts, es) = series["path"][-1], series["sppm"][-1]
            sp, ss = slope(series["path"]), slope(series["sppm"])
            if ep > es and sp < ss:
                cross = tp * (ep / es) ** (1.0 / (ss - sp))
                if cross < 3600:
                    print(f"path would reach sppm's error after about {cross:.0f} s (both slopes kept)")
                else:
                    print("path would not reach sppm's error within an hour (both slopes kept)")
        print()


if __name__ == "__main__":
    main()
