#!/usr/bin/env python3
"""Recall of one graph against another (issue 43): the share of the
reference graph's transitions that the compared graph has between the same
sequences at the same frames (m, n) with its cost within 5 % (the rule of
`graph::compare::agreement` with 0 frames and 0.05), overall and by the
reference's cost quartile within each ordered sequence pair's rank.

    scripts/graph-recall.py REF/.surfmotion/graph-shape.json OTHER/.../graph-shape.json [--misses]

Either argument may also be a database folder (its shape graph is read).
Sequences are matched by name, so the two databases may list them in other
orders."""
import json, os, sys


def load(p):
    if os.path.isdir(p):
        for c in (".surfmotion/graph-shape.json", "cache/graph-shape.json"):
            if os.path.isfile(os.path.join(p, c)):
                p = os.path.join(p, c)
                break
    with open(p) as f:
        g = json.load(f)
    g = g.get("graph", g)
    names = [s["name"] for s in g["sequences"]]
    ts = [(names[t["from"]], names[t["to"]], t["m"], t["n"], t["window"], t["cost"]) for t in g["transitions"]]
    return p, ts


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    if len(args) != 2:
        sys.exit(__doc__)
    (pr, ref), (pc, cmp_) = load(args[0]), load(args[1])
    by_pair = {}
    for t in cmp_:
        by_pair.setdefault((t[0], t[1]), []).append(t)
    found, misses = 0, []
    for t in ref:
        hit = any(u[2] == t[2] and u[3] == t[3] and abs(u[5] - t[5]) <= 0.05 * max(abs(t[5]), 1e-12)
                  for u in by_pair.get((t[0], t[1]), []))
        if hit:
            found += 1
        else:
            near = min(((abs(u[2] - t[2]) + abs(u[3] - t[3]), u[5] / t[5] - 1) for u in by_pair.get((t[0], t[1]), [])),
                       default=None)
            misses.append((t, near))
    costs = sorted(t[5] for t in ref)
    print(f"reference {pr}: {len(ref)} transitions; compared {pc}: {len(cmp_)}")
    print(f"found at the same frames with cost within 5 %: {found} of {len(ref)} ({100 * found / max(len(ref), 1):.1f} %)")
    for q, name in ((0.1, "cheapest tenth"), (0.25, "cheapest quarter"), (0.5, "cheapest half")):
        lim = costs[int(q * (len(costs) - 1))] if costs else 0
        sub = [t for t in ref if t[5] <= lim]
        miss = sum(1 for t, _ in misses if t[5] <= lim)
        print(f"  {name}: {len(sub) - miss} of {len(sub)}")
    pairs_ref = {(t[0], t[1]) for t in ref}
    print(f"ordered pairs with reference transitions but none compared: {len(pairs_ref - set(by_pair))}")
    if "--misses" in sys.argv:
        for t, near in misses:
            print(f"  miss {t[0]} -> {t[1]} ({t[2]}, {t[3]}) L {t[4]} cost {t[5]:.5f}; nearest in the same pair: {near}")


main()
