#!/usr/bin/env python3
"""The growth plot of issue 43: how `db build`'s cost grows with the frames.

    scripts/scale-plot.py MEASURED.tsv OUT.svg

MEASURED.tsv has a header line and one row per build: frames, sequences,
CPU seconds (user + system of `/usr/bin/time -v`), peak RSS in KB (its
"Maximum resident set size", KiB), and a free-text note (lines starting
with # are comments). Draws, on log-log axes, CPU seconds and peak MB
against frames, with guide lines of slope 1 (n), n log n and 2 (n²)
through the first point, and prints the table with the log-log slope of
each step (log(cost ratio) / log(frames ratio)) as Markdown. Plain SVG, no
plotting library (none is installed on the project's machine).
"""
import math
import sys


def read(path):
    rows = []
    for line in open(path):
        if not line.strip() or line.startswith("#"):
            continue
        p = line.rstrip("\n").split("\t")
        if p[0] == "frames":
            continue
        rows.append((int(p[0]), int(p[1]), float(p[2]), int(p[3]) * 1024 / 1e6, p[4] if len(p) > 4 else ""))
    rows.sort()
    return rows


def slopes(xs, ys):
    return [math.log(ys[k + 1] / ys[k]) / math.log(xs[k + 1] / xs[k]) for k in range(len(xs) - 1)]


def panel(x0, y0, w, h, xs, ys, title, unit):
    """One log-log panel at (x0, y0) of size w × h: the measurements, the
    guide lines through the first point, the step slopes."""
    lx = [math.log10(v) for v in xs]
    gx0, gx1 = math.floor(min(lx) * 2 + 0.05) / 2, math.ceil(max(lx) * 2 - 0.05) / 2
    # Guides run from the first point to the last frame count: the y range
    # covers the measurements and the n and n² guides.
    n0, c0 = xs[0], ys[0]
    guide = {
        "n": lambda n: c0 * n / n0,
        "n log n": lambda n: c0 * n * math.log(n) / (n0 * math.log(n0)),
        "n²": lambda n: c0 * (n / n0) ** 2,
    }
    ly = [math.log10(v) for v in ys] + [math.log10(guide["n"](xs[-1])), math.log10(guide["n²"](xs[-1]))]
    gy0, gy1 = math.floor(min(ly) - 0.05), math.ceil(max(ly))
    X = lambda v: x0 + (math.log10(v) - gx0) / (gx1 - gx0) * w
    Y = lambda v: y0 + h - (math.log10(v) - gy0) / (gy1 - gy0) * h
    out = [f'<rect x="{x0}" y="{y0}" width="{w}" height="{h}" fill="white" stroke="#444"/>']
    out.append(f'<text x="{x0 + w / 2}" y="{y0 - 12}" text-anchor="middle" font-size="15" font-weight="bold">{title}, {unit}</text>')
    d = gx0
    while d <= gx1 + 1e-9:
        v = 10 ** d
        px = X(v)
        if abs(d - round(d)) < 1e-9:
            out.append(f'<line x1="{px:.1f}" y1="{y0}" x2="{px:.1f}" y2="{y0 + h}" stroke="#ddd"/>')
            out.append(f'<text x="{px:.1f}" y="{y0 + h + 16}" text-anchor="middle" font-size="12">10{sup(int(round(d)))}</text>')
        else:
            out.append(f'<line x1="{px:.1f}" y1="{y0}" x2="{px:.1f}" y2="{y0 + h}" stroke="#eee"/>')
            out.append(f'<text x="{px:.1f}" y="{y0 + h + 16}" text-anchor="middle" font-size="11" fill="#666">3×10{sup(int(d))}</text>')
        d += 0.5
    for e in range(gy0, gy1 + 1):
        py = Y(10 ** e)
        out.append(f'<line x1="{x0}" y1="{py:.1f}" x2="{x0 + w}" y2="{py:.1f}" stroke="#ddd"/>')
        out.append(f'<text x="{x0 - 6}" y="{py + 4:.1f}" text-anchor="end" font-size="12">10{sup(e)}</text>')
    out.append(f'<text x="{x0 + w / 2}" y="{y0 + h + 36}" text-anchor="middle" font-size="13">frames</text>')
    colours = {"n": "#2a9d8f", "n log n": "#e9c46a", "n²": "#e76f51"}
    for k, (name, f) in enumerate(guide.items()):
        pts = [xs[0] * (xs[-1] / xs[0]) ** (t / 40) for t in range(41)]
        out.append(f'<line x1="{X(pts[0]):.1f}" y1="{Y(f(pts[0])):.1f}" x2="{X(pts[-1]):.1f}" y2="{Y(f(pts[-1])):.1f}" stroke="{colours[name]}" stroke-width="1.5" stroke-dasharray="6 4"/>' if name != "n log n" else "")
        if name == "n log n":
            for a, b in zip(pts, pts[1:]):
                out.append(f'<line x1="{X(a):.1f}" y1="{Y(f(a)):.1f}" x2="{X(b):.1f}" y2="{Y(f(b)):.1f}" stroke="{colours[name]}" stroke-width="1.5"/>')
        out.append(f'<text x="{x0 + 10}" y="{y0 + 18 + 16 * k}" font-size="12" fill="{colours[name]}">{"——" if name == "n log n" else "- - -"} {name} (through the first point)</text>')
    # Segments, not one open path: some renderers (ImageMagick's) close it.
    for k in range(len(xs) - 1):
        out.append(f'<line x1="{X(xs[k]):.1f}" y1="{Y(ys[k]):.1f}" x2="{X(xs[k + 1]):.1f}" y2="{Y(ys[k + 1]):.1f}" stroke="#1d3557" stroke-width="2.5"/>')
    for k, (a, b) in enumerate(zip(xs, ys)):
        out.append(f'<circle cx="{X(a):.1f}" cy="{Y(b):.1f}" r="4.5" fill="#1d3557"/>')
        label = f"{b:,.0f}" if b >= 100 else f"{b:.1f}"
        # Below right of each point; the first above it (the axis labels
        # are below), the last to its left (the panel's edge).
        anchor = "end" if k == len(xs) - 1 else "start"
        dx = -8 if k == len(xs) - 1 else 8
        dy = -10 if k == 0 else 18
        out.append(f'<text x="{X(a) + dx:.1f}" y="{Y(b) + dy:.1f}" text-anchor="{anchor}" font-size="12" fill="#1d3557">{label}</text>')
    for k, s in enumerate(slopes(xs, ys)):
        mx = math.sqrt(xs[k] * xs[k + 1])
        my = math.sqrt(ys[k] * ys[k + 1])
        out.append(f'<text x="{X(mx):.1f}" y="{Y(my) - 10:.1f}" text-anchor="middle" font-size="12" font-style="italic" fill="#b5179e">{s:.2f}</text>')
    return out


def sup(e):
    return "".join("⁰¹²³⁴⁵⁶⁷⁸⁹"[int(c)] if c.isdigit() else "⁻" for c in str(e))


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    rows = read(sys.argv[1])
    if len(rows) < 2:
        sys.exit(f"{sys.argv[1]}: at least two rows are needed")
    xs = [r[0] for r in rows]
    cpu = [r[2] for r in rows]
    mb = [r[3] for r in rows]  # MB, 10^6 bytes
    W, H = 980, 470
    svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif">',
           f'<rect width="{W}" height="{H}" fill="#fafafa"/>']
    svg += panel(90, 50, 380, 340, xs, cpu, "db build: CPU", "s (user + system)")
    svg += panel(580, 50, 380, 340, xs, mb, "db build: peak RSS", "MB")
    svg.append(f'<text x="{W / 2}" y="{H - 12}" text-anchor="middle" font-size="12" fill="#444">measured on the 2,600-vertex pool of scripts/scale-db.sh; italic: the log-log slope of each step (1 = n, 2 = n²)</text>')
    svg.append("</svg>")
    tmp = sys.argv[2] + ".part"
    with open(tmp, "w") as f:
        f.write("\n".join(svg) + "\n")
    import os
    os.replace(tmp, sys.argv[2])
    sc, sm = slopes(xs, cpu), slopes(xs, mb)
    print("| frames | sequences | CPU s | slope | peak MB | slope | note |")
    print("|---|---|---|---|---|---|---|")
    for k, r in enumerate(rows):
        a = f"{sc[k - 1]:.2f}" if k else "—"
        b = f"{sm[k - 1]:.2f}" if k else "—"
        print(f"| {r[0]:,} | {r[1]} | {r[2]:,.1f} | {a} | {mb[k]:,.0f} | {b} | {r[4]} |")
    whole_c = math.log(cpu[-1] / cpu[0]) / math.log(xs[-1] / xs[0])
    whole_m = math.log(mb[-1] / mb[0]) / math.log(xs[-1] / xs[0])
    print(f"\nover the whole range: CPU slope {whole_c:.2f}, peak memory slope {whole_m:.2f}")


if __name__ == "__main__":
    main()
