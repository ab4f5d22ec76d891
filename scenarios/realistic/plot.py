#!/usr/bin/env python3
"""e_max against one column of an ehservo results.csv, as an SVG (stdlib only).

For the studies whose axis is an array key (sensor.noise, sensor.resolution),
which `ehservo sweep` cannot plot against a number: the x value is element
--index of the array. One line per combination of the --group columns;
an unbounded run (diverged = true) is drawn as a cross on the top edge.
Rows that share x and group (noise seeds) are reduced to their worst
(largest e_max; unbounded if any is).

    python3 scenarios/realistic/plot.py RESULTS.csv --x sensor.noise --index 0 \
        --group controller.kind --logx --logy --out OUT.svg
"""
import argparse
import csv
import os
import sys
import math
import re

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from table import num, short  # noqa: E402  (one parser for both scripts)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv")
    ap.add_argument("--x", required=True)
    ap.add_argument("--index", type=int, default=0)
    ap.add_argument("--counts", action="store_true",
                    help="x is an encoder step 2π/N: plot N (counts/rev)")
    ap.add_argument("--group", default="controller.kind")
    ap.add_argument("--where", action="append", default=[], help="COL=VALUE")
    ap.add_argument("--y", default="e_max_deg")
    ap.add_argument("--logx", action="store_true")
    ap.add_argument("--logy", action="store_true")
    ap.add_argument("--xlabel", default=None)
    ap.add_argument("--title", default="")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()

    rows = list(csv.DictReader(open(a.csv, newline="")))
    for w in a.where:
        k, v = w.split("=", 1)
        rows = [r for r in rows if r[k] == v]
    groups = {}
    for r in rows:
        x = num(r[a.x], a.index)
        if a.counts:
            x = 2 * math.pi / x
        key = ", ".join(short(r[g]) for g in a.group.split(",") if g)
        div = r["diverged"] == "true" or r[a.y] == ""
        y = None if div else float(r[a.y])
        g = groups.setdefault(key, {})
        if x in g and (g[x] is None or (y is not None and y <= g[x])):
            continue
        g[x] = y
    groups = {k: sorted(v.items()) for k, v in groups.items()}

    xs = [x for g in groups.values() for x, _ in g]
    ys = [y for g in groups.values() for _, y in g if y is not None and y > 0]
    fx = (lambda v: math.log10(v)) if a.logx else (lambda v: v)
    fy = (lambda v: math.log10(v)) if a.logy else (lambda v: v)
    x0, x1 = fx(min(xs)), fx(max(xs))
    y0, y1 = (fy(min(ys)), fy(max(ys))) if ys else (0, 1)
    if a.logy:
        y0, y1 = math.floor(y0), math.ceil(y1)
    if x1 == x0:
        x1 = x0 + 1
    if y1 == y0:
        y1 = y0 + 1
    W, H, L, R, T, B = 900, 460, 80, 330, 40, 60
    px = lambda v: L + (fx(v) - x0) / (x1 - x0) * (W - L - R)
    py = lambda v: H - B - (fy(v) - y0) / (y1 - y0) * (H - T - B)
    colours = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e",
               "#8c564b", "#e377c2", "#7f7f7f", "#17becf", "#bcbd22"]
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" '
           f'font-family="sans-serif" font-size="12">',
           f'<rect width="{W}" height="{H}" fill="white"/>',
           f'<text x="{L}" y="22" font-size="14">{a.title}</text>',
           f'<rect x="{L}" y="{T}" width="{W-L-R}" height="{H-T-B}" fill="none" stroke="black"/>']
    # ticks
    if a.logy:
        for e in range(int(y0), int(y1) + 1):
            y = H - B - (e - y0) / (y1 - y0) * (H - T - B)
            out.append(f'<line x1="{L}" x2="{W-R}" y1="{y:.1f}" y2="{y:.1f}" stroke="#ddd"/>')
            out.append(f'<text x="{L-6}" y="{y+4:.1f}" text-anchor="end">1e{e}</text>')
    else:
        for k in range(6):
            v = y0 + k * (y1 - y0) / 5
            y = H - B - k / 5 * (H - T - B)
            out.append(f'<text x="{L-6}" y="{y+4:.1f}" text-anchor="end">{v:.3g}</text>')
    xt = sorted(set(xs))
    for v in xt:
        x = px(v)
        out.append(f'<line x1="{x:.1f}" x2="{x:.1f}" y1="{H-B}" y2="{H-B+4}" stroke="black"/>')
        lab = f"2^{round(math.log2(v))}" if a.counts else f"{v:.3g}"
        out.append(f'<text x="{x:.1f}" y="{H-B+18}" text-anchor="middle" font-size="10">{lab}</text>')
    out.append(f'<text x="{(L+W-R)/2}" y="{H-15}" text-anchor="middle">'
               f'{a.xlabel or a.x}</text>')
    out.append(f'<text x="18" y="{(T+H-B)/2}" transform="rotate(-90 18 {(T+H-B)/2})" '
               f'text-anchor="middle">{a.y} (unbounded: × at the top)</text>')
    for i, (key, pts) in enumerate(sorted(groups.items())):
        c = colours[i % len(colours)]
        seg = []
        for x, y in pts + [(None, None)]:
            if y is not None and y > 0:
                seg.append(f"{px(x):.1f},{py(y):.1f}")
                continue
            if len(seg) > 1:
                out.append(f'<polyline points="{" ".join(seg)}" fill="none" stroke="{c}" stroke-width="1.5"/>')
            for s in seg:
                sx, sy = s.split(",")
                out.append(f'<circle cx="{sx}" cy="{sy}" r="2.5" fill="{c}"/>')
            seg = []
            if x is not None:
                X = px(x)
                out.append(f'<path d="M{X-4:.1f},{T-4} L{X+4:.1f},{T+4} M{X-4:.1f},{T+4} L{X+4:.1f},{T-4}" stroke="{c}" stroke-width="2"/>')
        ly = T + 14 + 16 * i
        out.append(f'<line x1="{W-R+10}" x2="{W-R+30}" y1="{ly-4}" y2="{ly-4}" stroke="{c}" stroke-width="2"/>')
        out.append(f'<text x="{W-R+34}" y="{ly}" font-size="11">{key}</text>')
    out.append("</svg>")
    open(a.out, "w").write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
