#!/usr/bin/env python3
"""A markdown table of one metric from an ehservo results.csv (stdlib only):
one row per value of --row, one column per combination of the --col
columns. A cell is the metric to 3 significant digits; where several runs
share a cell (noise seeds) it is "min–max"; a run that diverged is
"unbounded at t = … s" (with several runs: the first divergence and how many
of them diverged).

    python3 scenarios/realistic/table.py docs/realistic/delay/results.csv \
        --row sensor.delay --col controller.kind \
        --where simulation.computation_delay=false
"""
import argparse
import csv
import math
import re


def num(cell, index):
    cell = cell.strip()
    if cell.startswith("["):
        parts = [p for p in re.split(r"[\[\],\s]+", cell) if p]
        return float(parts[index])
    return float(cell)


def short(cell):
    m = re.match(r'\{ kind = "([a-z-]+)"(.*)\}$', cell.strip())
    if not m:
        return cell
    rest = re.sub(r"\.0\b", "", m.group(2)).replace(" = ", "=").strip(" ,")
    return f"{m.group(1)} {rest}".strip()


def g3(v):
    return f"{v:.3g}"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv")
    ap.add_argument("--row", required=True)
    ap.add_argument("--index", type=int, default=None,
                    help="the row column is an array: label it by this element")
    ap.add_argument("--counts", action="store_true",
                    help="the row is an encoder step 2π/N: label it 2^k")
    ap.add_argument("--col", default="controller.kind")
    ap.add_argument("--where", action="append", default=[],
                    help="COL=VALUE (the cell, or an estimator as short as the table shows it)")
    ap.add_argument("--metric", default="e_max_deg")
    ap.add_argument("--metrics", default=None,
                    help="several metrics as the columns (instead of --col)")
    a = ap.parse_args()
    if a.metrics:
        a.col = ""

    rows = list(csv.DictReader(open(a.csv, newline="")))
    for w in a.where:
        k, v = w.split("=", 1)
        rows = [r for r in rows if v in (r[k], short(r[k]))]
    cols, order, cells = [], [], {}
    for r in rows:
        rv = r[a.row]
        if a.counts:
            label = f"2^{round(math.log2(2 * math.pi / num(rv, 0)))}"
        elif a.index is not None:
            label = g3(num(rv, a.index))
        else:
            label = short(rv)
        if label not in order:
            order.append(label)
        for metric in (a.metrics.split(",") if a.metrics else [a.metric]):
            c = metric if a.metrics else ", ".join(short(r[k]) for k in a.col.split(",") if k)
            if c not in cols:
                cols.append(c)
            cells.setdefault((label, c), []).append((r, metric))

    head = a.row + (f"[{a.index}]" if a.index is not None else "")
    print(f"| {head} | " + " | ".join(cols) + " |")
    print("|---" * (len(cols) + 1) + "|")
    for label in order:
        out = []
        for c in cols:
            rm = cells.get((label, c), [])
            rs = [r for r, _ in rm]
            div = [r for r in rs if r["diverged"] == "true"]
            vals = [float(r[m]) for r, m in rm
                    if r["diverged"] != "true" and r[m] != ""]
            if div:
                t = min(float(r["diverged_at_s"]) for r in div)
                s = f"unbounded at t = {t:.3g} s"
                if len(rs) > 1:
                    s += f" ({len(div)}/{len(rs)})"
                out.append(s)
            elif not vals:
                out.append("–")
            elif g3(min(vals)) == g3(max(vals)):
                out.append(g3(vals[0]))
            else:
                out.append(f"{g3(min(vals))}–{g3(max(vals))}")
        print(f"| {label} | " + " | ".join(out) + " |")


if __name__ == "__main__":
    main()
