#!/usr/bin/env python3
"""Print which top-level library module imports which (from `crate::` paths in src/).

Usage: scripts/module_graph.py [SRC_DIR]   (default: src)
Excludes src/cli and src/main.rs (the binary) and `#[cfg(test)]` code. Prints one line per module,
then the cycles between top-level modules (pairs importing each other, and
longer strongly connected components)."""
import os, re, sys

src = sys.argv[1] if len(sys.argv) > 1 else "src"
edges = {}
pat = re.compile(r"crate::([a-z_][a-z0-9_]*)")
use_group = re.compile(r"use\s+crate::\{([^;]*)\}", re.S)
top_group_item = re.compile(r"(?:^|,)\s*([a-z_][a-z0-9_]*)")
for root, _, files in os.walk(src):
    rel = os.path.relpath(root, src)
    if rel.split(os.sep)[0] == "cli":
        continue
    for f in files:
        if not f.endswith(".rs"):
            continue
        if rel == "." and f in ("main.rs", "lib.rs"):
            continue
        module = f[:-3] if rel == "." else rel.split(os.sep)[0]
        text = open(os.path.join(root, f)).read()
        text = re.sub(r"//[^\n]*", "", text)
        # test modules (at the end of a file by house convention) are not
        # part of the library's layering: drop everything from `#[cfg(test)]`.
        text = text.split("#[cfg(test)]")[0]
        targets = set(pat.findall(text))
        for g in use_group.findall(text):
            depth = 0
            item = ""
            for ch in g:
                if ch == "{":
                    depth += 1
                elif ch == "}":
                    depth -= 1
                elif ch == "," and depth == 0:
                    m = re.match(r"\s*([a-z_][a-z0-9_]*)", item)
                    if m:
                        targets.add(m.group(1))
                    item = ""
                    continue
                if depth == 0 or True:
                    item += ch if depth == 0 else ""
            m = re.match(r"\s*([a-z_][a-z0-9_]*)", item)
            if m:
                targets.add(m.group(1))
        targets.discard(module)
        targets.discard("self")
        edges.setdefault(module, set()).update(targets)

for m in sorted(edges):
    print(f"{m:12} -> {', '.join(sorted(edges[m])) or '-'}")

# strongly connected components (Tarjan)
index, low, stack, on, sccs = {}, {}, [], set(), []
def strong(v, counter=[0]):
    index[v] = low[v] = counter[0]; counter[0] += 1
    stack.append(v); on.add(v)
    for w in edges.get(v, ()):
        if w not in edges:
            continue
        if w not in index:
            strong(w); low[v] = min(low[v], low[w])
        elif w in on:
            low[v] = min(low[v], index[w])
    if low[v] == index[v]:
        comp = []
        while True:
            w = stack.pop(); on.discard(w); comp.append(w)
            if w == v:
                break
        if len(comp) > 1:
            sccs.append(sorted(comp))
sys.setrecursionlimit(10000)
for v in sorted(edges):
    if v not in index:
        strong(v)
print("cycles:", "; ".join(" <-> ".join(c) for c in sccs) if sccs else "none")
