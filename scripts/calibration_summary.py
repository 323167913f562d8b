#!/usr/bin/env python3
"""The calibration table (Markdown) from the CSVs scripts/calibrate.sh writes: per scene, method
and budget, the true RMSE (against the reference, less its own noise), the render's estimate of
it from its passes, and their ratio; a final line gives the range of the ratio per method.
Usage: calibration_summary.py DIR"""
import csv
import os
import sys

d = sys.argv[1]
order = ["furnace", "cornell", "caustics", "pointlight", "sunroom", "sunroom-portal", "doorway", "bunny", "glassknot", "faraway"]
names = sorted(f[:-4] for f in os.listdir(d) if f.endswith(".csv"))
names = [n for n in order if n in names] + [n for n in names if n not in order]
print("| scene | method | budget s | passes | true RMSE | estimated RMSE | est / true |")
print("|---|---|---|---|---|---|---|")
ratios = {}
for scene in names:
    for r in csv.DictReader(open(os.path.join(d, scene + ".csv"))):
        est, true = r["estimated_rmse"], float(r["true_rmse"])
        if not est or true <= 0:
            ratio = "–"
        else:
            x = float(est) / true
            mark = "" if r["estimate_has_bias"] == "true" else "*"
            ratios.setdefault(r["method"] + mark, []).append(x)
            ratio = f"{x:.2f}{mark}"
        print(f"| {scene} | {r['method']} | {float(r['budget_seconds']):g} | {r['passes']} | {true:.5f} | {est or '–'} | {ratio} |")
print()
for m, xs in ratios.items():
    inside = sum(0.67 <= x <= 1.5 for x in xs)
    print(f"- {m}: est / true from {min(xs):.2f} to {max(xs):.2f}; {inside} of {len(xs)} rows within 0.67–1.5")
