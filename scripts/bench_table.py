#!/usr/bin/env python3
"""Markdown table of the criterion results (mean times) and the fitted growth exponent
alpha of cost ~ n^alpha per kernel (least squares on log t against log n).

usage: scripts/bench_table.py [CRITERION_DIR]   (default: target/criterion, or
$CARGO_TARGET_DIR/criterion)
       scripts/bench_table.py --ordering FILE    (the tab-separated output of
`cargo run --release --example ordering`: fill, numeric and solve per backend and
refinement, with their exponents)"""
import json, math, os, sys
from pathlib import Path


def slope(pts):
    """Least-squares slope of log y against log x."""
    if len(pts) < 2:
        return None
    xs = [math.log(x) for x, _ in pts]
    ys = [math.log(y) for _, y in pts]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)


def ordering_table(path):
    # system  n  nnz(A)  solver  fill  symbolic_ms  numeric_ms  solve_ms  dx
    rows = {}
    sizes = {}
    for line in open(path):
        f = line.rstrip("\n").split("\t")
        if len(f) < 9 or f[0] == "system":
            continue
        system, n, solver = f[0], int(f[1]), f[3]
        inertia = system.endswith("-inertia")
        refine = system[1:].removesuffix("-inertia")
        fill = None if f[4] == "-" else int(f[4])
        rows.setdefault((inertia, solver), {})[refine] = (n, fill, float(f[5]), float(f[6]), float(f[7]))
        sizes.setdefault(inertia, {})[refine] = n
    for inertia in sorted(sizes):
        refines = sorted(sizes[inertia], key=float)
        print("\n**" + ("with inertia (u, v, μ_as), cj = 100" if inertia else "without inertia (u, μ_as), cj = 0.1") + "**\n")
        head = " | ".join(f"refine {r} (n = {sizes[inertia][r]})" for r in refines)
        print(f"| backend | quantity | {head} | α |")
        print("|---|---|" + "---|" * len(refines) + "---|")
        for (inr, solver), d in rows.items():
            if inr != inertia:
                continue
            for qi, (q, fmt) in enumerate([("fill", lambda v: f"{v / 1e3:.0f} k"),
                                            ("symbolic", lambda v: f"{v:.3g} ms"),
                                            ("numeric", lambda v: f"{v:.3g} ms"),
                                            ("solve", lambda v: f"{v:.3g} ms")]):
                vals = [d.get(r, (None,) * 5)[1 + qi] for r in refines]
                if all(v is None for v in vals):
                    continue
                cells = " | ".join("–" if v is None else fmt(v) for v in vals)
                a = slope([(sizes[inertia][r], v) for r, v in zip(refines, vals) if v])
                print(f"| {solver} | {q} | {cells} | {'–' if a is None else f'{a:.2f}'} |")


if len(sys.argv) > 2 and sys.argv[1] == "--ordering":
    ordering_table(sys.argv[2])
    sys.exit(0)

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
    a = slope(pts)
    alpha = "–" if a is None else f"{a:.2f}"
    print(f"| {func} | {cells} | {alpha} |")
