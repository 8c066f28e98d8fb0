#!/usr/bin/env python3
"""Markdown table of the criterion results (mean times) and the fitted growth exponent
alpha of cost ~ n^alpha per kernel (least squares on log t against log n).

usage: scripts/bench_table.py [CRITERION_DIR]   (default: target/criterion, or
$CARGO_TARGET_DIR/criterion)"""
import json, math, os, sys
from pathlib import Path

root = Path(sys.argv[1] if len(sys.argv) > 1 else
            Path(os.environ.get("CARGO_TARGET_DIR", "target")) / "criterion")
rows = {}
for est in root.glob("*/*/*/new/estimates.json"):
    func, param = est.parts[-4], est.parts[-3]
    if not param.isdigit():
        continue
    mean = json.load(open(est))["mean"]["point_estimate"] * 1e-9
    rows.setdefault(func, []).append((int(param), mean))

def fmt(t):
    return f"{t * 1e3:.3g} ms" if t < 1 else f"{t:.3g} s"

print("| kernel | n (unknowns): mean time | α (cost ∝ n^α) |")
print("|---|---|---|")
for func in sorted(rows):
    pts = sorted(rows[func])
    cells = ", ".join(f"{n}: {fmt(t)}" for n, t in pts)
    if len(pts) >= 2:
        xs = [math.log(n) for n, _ in pts]
        ys = [math.log(t) for _, t in pts]
        mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
        a = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
        alpha = f"{a:.2f}"
    else:
        alpha = "–"
    print(f"| {func} | {cells} | {alpha} |")
