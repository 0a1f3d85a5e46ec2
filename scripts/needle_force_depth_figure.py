#!/usr/bin/env python3
"""Draws docs/figures/needle_force_depth.svg from the folder scripts/needle_force_curve.sh writes: the needle
force against depth in equilibrium (needle.csv, 10 relaxed increments), the relaxation's transient along the way
(needle_transient.csv) and the runs stopped and relaxed at each depth, with the load ramped 4 times slower than
the scene's, and the transient of the scene as shipped (one relaxation at 15 mm: the old needle.csv). Usage:
    python3 scripts/needle_force_depth_figure.py runs/needle-force-curve docs/figures/needle_force_depth.svg
"""
import csv
import json
import sys

folder, target = sys.argv[1], sys.argv[2]
curve = [(1e3 * float(r["depth_m"]), float(r["force_N"])) for r in csv.DictReader(open(f"{folder}/curve/needle.csv"))]
transient = [(1e3 * float(r["depth_m"]), float(r["transient_force_N"]))
             for r in csv.DictReader(open(f"{folder}/curve/needle_transient.csv"))]
one_shot = [(1e3 * float(r["depth_m"]), float(r["transient_force_N"]))
            for r in csv.DictReader(open(f"{folder}/default/needle_transient.csv"))]
alone = []
for k in range(1, len(curve) + 1):
    summary = json.load(open(f"{folder}/depth{k}/summary.json"))
    alone.append((1e3 * summary["needle"]["final_depth_m"], summary["needle"]["final_force_N"]))

W, H, left, right, top, bottom = 640, 420, 70, 20, 40, 55
x_max = 15.0
y_max = 1.05 * max(f for _, f in transient + one_shot + curve)


def x(v):
    return left + (W - left - right) * v / x_max


def y(v):
    return H - bottom - (H - top - bottom) * v / y_max


def polyline(points, colour, width=1.5, dash=""):
    path = " ".join(f"{x(a):.1f},{y(b):.1f}" for a, b in points if a <= x_max + 1e-9)
    extra = f' stroke-dasharray="{dash}"' if dash else ""
    return f'<polyline points="{path}" fill="none" stroke="{colour}" stroke-width="{width}"{extra}/>'


out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" '
       'font-family="DejaVu Sans, sans-serif" font-size="12">', f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<text x="{W / 2}" y="22" text-anchor="middle" font-size="14">Default scene: needle force against depth</text>']
for i in range(0, 16, 3):
    out.append(f'<line x1="{x(i):.1f}" y1="{y(0):.1f}" x2="{x(i):.1f}" y2="{y(0) + 5:.1f}" stroke="black"/>')
    out.append(f'<text x="{x(i):.1f}" y="{y(0) + 19:.1f}" text-anchor="middle">{i}</text>')
step = 0.02
for k in range(0, int(y_max / step) + 1):
    v = k * step
    out.append(f'<line x1="{x(0) - 5:.1f}" y1="{y(v):.1f}" x2="{x(x_max):.1f}" y2="{y(v):.1f}" stroke="#ddd"/>')
    out.append(f'<text x="{x(0) - 8:.1f}" y="{y(v) + 4:.1f}" text-anchor="end">{v:.2f}</text>')
out.append(f'<line x1="{x(0)}" y1="{y(0)}" x2="{x(x_max)}" y2="{y(0)}" stroke="black"/>')
out.append(f'<line x1="{x(0)}" y1="{y(0)}" x2="{x(0)}" y2="{y(y_max)}" stroke="black"/>')
out.append(f'<text x="{(left + W - right) / 2}" y="{H - 15}" text-anchor="middle">depth (mm)</text>')
out.append(f'<text transform="translate(18 {(top + H - bottom) / 2}) rotate(-90)" text-anchor="middle">force (N)</text>')
out.append(polyline(one_shot, "#d62728", 1.5, "6 4"))
out.append(polyline(transient, "#ff9896", 1.2))
out.append(polyline([(0.0, 0.0)] + curve, "#1f77b4", 2.0))
for a, b in curve:
    out.append(f'<circle cx="{x(a):.1f}" cy="{y(b):.1f}" r="3.5" fill="#1f77b4"/>')
for a, b in alone:
    out.append(f'<path d="M{x(a) - 5:.1f},{y(b) - 5:.1f} l10,10 m0,-10 l-10,10" stroke="black" stroke-width="1.5"/>')
legend = [("#1f77b4", "", "needle.csv: in equilibrium at each depth (10 relaxed increments, ramp 4x slower)"),
          ("black", "x", "a run stopped at that depth and relaxed there"),
          ("#d62728", "6 4", "the old needle.csv: the transient of one relaxation at 15 mm"),
          ("#ff9896", "", "needle_transient.csv of that run")]
for i, (colour, dash, text) in enumerate(legend):
    ly = top + 8 + 18 * i
    if dash == "x":
        out.append(f'<path d="M{x(0.6) - 5:.1f},{ly - 5} l10,10 m0,-10 l-10,10" stroke="black" stroke-width="1.5"/>')
    else:
        d = f' stroke-dasharray="{dash}"' if dash else ""
        out.append(f'<line x1="{x(0.2):.1f}" y1="{ly}" x2="{x(1.0):.1f}" y2="{ly}" stroke="{colour}" stroke-width="2"{d}/>')
    out.append(f'<text x="{x(1.3):.1f}" y="{ly + 4}">{text}</text>')
out.append("</svg>")
open(target, "w").write("\n".join(out) + "\n")
