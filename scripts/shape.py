#!/usr/bin/env python3
"""The shape of the codebase, measured (issue 40's "before" figures).

Usage: python3 scripts/shape.py [--all] [SRC_DIR]   (default: src; run from the repository root)

Prints, for the library and binary under SRC_DIR:
  1. file-level import circles: which source file uses which (from `use` statements and
     inline `crate::`, `super::`, `self::` and child-module paths, following re-exports to
     the file that defines the item), then the strongly connected components of more than
     one file with the edges that close them (file:line of the `use`);
  2. the longest functions (brace-matched bodies, signature to closing brace, test code
     excluded), the top 15 and how many exceed 100 and 150 lines (--all: every one over 100);
  3. `mod.rs` files: total lines and lines of logic (not `mod`, `use`, attributes, comments);
  4. `src/cli` lines, and its files;
  5. visibility: `pub` items vs `pub(crate)`/`pub(super)`, public struct fields, and the
     `pub` items reachable from outside the crate (their file's every module `pub mod`);
  6. the number of test binaries (`tests/*.rs`), benches and examples;
  7. library string literals that name a CLI flag (`--word`), per file.

Comments, string literals and everything from a file's first `#[cfg(test)]` on (the house
puts test modules at the end) are left out of 1, 2 and 5. Standard library only."""
import os
import re
import sys
from collections import defaultdict

args = [a for a in sys.argv[1:] if not a.startswith("--")]
SHOW_ALL = "--all" in sys.argv
SRC = args[0] if args else "src"
ROOT = os.path.dirname(os.path.abspath(SRC))
IDENT = r"[A-Za-z_][A-Za-z0-9_]*"


# --------------------------------------------------------------------------- lexing
def blank(text):
    """Comments and string/char literal contents replaced by spaces, newlines kept, so
    line numbers and brace counts survive."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif re.match(r'b?r(#*)"', text[i:i + 40]) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'b?r(#*)"', text[i:])
            end = '"' + m.group(1)
            j = text.find(end, i + m.end())
            j = n if j < 0 else j + len(end)
            out.append('"' + re.sub(r"[^\n]", " ", text[i + 1:j - 1]) + '"')
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            out.append('"' + re.sub(r"[^\n]", " ", text[i + 1:j]) + '"')
            i = j + 1
        elif c == "'":
            m = re.match(r"'(\\.[^']*|[^\\'])'", text[i:])
            if m:  # a char literal ('{', '\n', '\u{..}'); otherwise a lifetime
                out.append("' " + " " * (m.end() - 3) + "'")
                i += m.end()
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def library_text(path):
    raw = open(path, encoding="utf-8").read()
    code = blank(raw)
    cut = code.find("#[cfg(test)]")
    return raw, (code if cut < 0 else code[:cut])


def line_of(text, pos):
    return text.count("\n", 0, pos) + 1


# --------------------------------------------------------------------------- modules
files = {}  # module path tuple -> file path
for root, _, names in os.walk(SRC):
    for f in names:
        if not f.endswith(".rs"):
            continue
        rel = os.path.relpath(os.path.join(root, f), SRC).replace(os.sep, "/")
        if rel in ("main.rs",):
            files[("<main>",)] = os.path.join(root, f)
            continue
        parts = rel[:-3].split("/")
        if parts[-1] in ("mod", "lib"):
            parts = parts[:-1]
        files[tuple(parts)] = os.path.join(root, f)
rel_of = {v: os.path.relpath(v, ROOT).replace(os.sep, "/") for v in files.values()}
code_of = {}
for mod, path in files.items():
    code_of[mod] = library_text(path)[1]

ITEM = re.compile(r"\b(?:fn|struct|enum|trait|type|const|static|union|macro_rules!)\s+(" + IDENT + ")")
defined = {m: set(ITEM.findall(c)) for m, c in code_of.items()}
USE = re.compile(r"(?<![A-Za-z0-9_])(pub(?:\s*\([^)]*\))?\s+)?use\s+([^;]+);")


def expand(tree):
    """`a::{b, c::{d, e as f}, self}` -> [(['a','b'], 'b'), (['a','c','d'], 'd'), ...]."""
    tree = re.sub(r"\s*(::|,|\{|\})\s*", r"\1", re.sub(r"\s+", " ", tree.strip()))
    out = []

    def rec(prefix, s):
        depth, items, cur = 0, [], ""
        for ch in s:
            if ch == "{":
                depth += 1
            elif ch == "}":
                depth -= 1
            if ch == "," and depth == 0:
                items.append(cur)
                cur = ""
            else:
                cur += ch
        if cur:
            items.append(cur)
        for it in items:
            if "{" in it:
                head, rest = it.split("{", 1)
                rec(prefix + [p for p in head.split("::") if p], rest[:-1])
                continue
            path, _, alias = it.partition(" as ")
            parts = prefix + [p for p in path.split("::") if p]
            if parts and parts[-1] == "self":
                parts = parts[:-1]
            if parts:
                out.append((parts, alias or parts[-1]))

    rec([], tree)
    return out


uses = {}  # module -> list of (is_pub, parts, alias, line)
for mod, code in code_of.items():
    lst = []
    for m in USE.finditer(code):
        for parts, alias in expand(m.group(2)):
            lst.append((bool(m.group(1)), parts, alias, line_of(code, m.start())))
    uses[mod] = lst


def children(mod):
    return {k[-1] for k in files if len(k) == len(mod) + 1 and k[:len(mod)] == mod}


def absolute(mod, parts):
    """A path as written in module `mod` -> absolute segments, or None if external."""
    first = parts[0]
    if first == "crate":
        return list(parts[1:])
    if first in ("self", "super"):
        segs = list(parts)
        cur = list(mod)
        while segs and segs[0] in ("self", "super"):
            if segs.pop(0) == "super":
                cur = cur[:-1]
        return cur + segs
    if first in children(mod):
        return list(mod) + list(parts)
    return None


def resolve(segs, depth=0):
    """Absolute segments -> the module (file) that defines the last item."""
    cur = ()
    for k, seg in enumerate(segs):
        if cur + (seg,) in files:
            cur = cur + (seg,)
            continue
        if seg in defined.get(cur, ()) or depth > 8:
            return cur
        # an import or re-export of this name in `cur`: follow it
        for is_pub, parts, alias, _ in uses.get(cur, ()):
            if alias == seg:
                target = absolute(cur, parts)
                if target is None:
                    return cur
                return resolve(target + list(segs[k + 1:]), depth + 1)
        for is_pub, parts, alias, _ in uses.get(cur, ()):
            if alias == "*":
                target = absolute(cur, parts[:-1])
                if target is not None:
                    t = resolve(target + [seg], depth + 1)
                    if t != tuple(target[:len(t)]) or seg in defined.get(t, ()):
                        return t
        return cur
    return cur


INLINE = re.compile(r"(?<![A-Za-z0-9_:])((?:crate|super|self)(?:::" + IDENT + r")+)")
edges = defaultdict(dict)  # file module -> {target module: first line}
for mod, code in code_of.items():
    if mod == ("<main>",):
        continue
    found = []
    for is_pub, parts, alias, line in uses[mod]:
        if is_pub:  # a re-export is not a dependency of the file's own logic
            continue
        a = absolute(mod, parts)
        if a is not None:
            found.append((resolve(a), line))
    no_use = USE.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), code)
    for m in INLINE.finditer(no_use):
        a = absolute(mod, m.group(1).split("::"))
        if a is not None:
            found.append((resolve(a), line_of(no_use, m.start())))
    kids = children(mod)
    if kids:
        for m in re.finditer(r"(?<![A-Za-z0-9_:])(" + "|".join(sorted(kids)) + r")::(" + IDENT + ")", no_use):
            found.append((resolve(list(mod) + [m.group(1), m.group(2)]), line_of(no_use, m.start())))
    for target, line in found:
        if target != mod and target in files:
            edges[mod].setdefault(target, line)


def name(mod):
    return rel_of[files[mod]]


def sccs(graph):
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]
    sys.setrecursionlimit(100000)

    def strong(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            strong(v)
    return out


lib = {m: e for m, e in edges.items() if m and m[0] != "cli"}
print("== 1. file-level import circles (library, src/cli and main.rs excluded)")
nfiles = sum(1 for m in files if m and m[0] not in ("cli", "<main>"))
nedges = sum(len(e) for e in lib.values())
print(f"library files: {nfiles}, file-to-file import edges: {nedges}")
circles = sccs(lib)
print(f"circles (strongly connected components of more than one file): {len(circles)}")
for comp in circles:
    print("  circle: " + ", ".join(name(m) for m in comp))
    for m in comp:
        for t, line in sorted(lib[m].items()):
            if t in comp:
                print(f"    {name(m)}:{line} uses {name(t)}")
cli_circles = sccs({m: e for m, e in edges.items() if m and m[0] == "cli"})
print(f"circles inside src/cli: {len(cli_circles)}")
for comp in cli_circles:
    print("  circle: " + ", ".join(name(m) for m in comp))

# --------------------------------------------------------------------------- functions
FN = re.compile(r"(?<![A-Za-z0-9_])fn\s+(" + IDENT + ")")
fns = []
for mod, path in files.items():
    code = code_of[mod]
    for m in FN.finditer(code):
        # the body's opening brace: first `{` or `;` at bracket depth 0 after the name
        i, depth = m.end(), 0
        while i < len(code):
            c = code[i]
            if c in "([<":
                depth += 1
            elif c in ")]>" and depth > 0:
                if not (c == ">" and code[i - 1] == "-"):
                    depth -= 1
            elif c == ";" and depth == 0:
                i = -1
                break
            elif c == "{" and depth == 0:
                break
            i += 1
        if i < 0 or i >= len(code):
            continue
        j, d = i, 0
        while j < len(code):
            if code[j] == "{":
                d += 1
            elif code[j] == "}":
                d -= 1
                if d == 0:
                    break
            j += 1
        start, end = line_of(code, m.start()), line_of(code, j)
        fns.append((end - start + 1, rel_of[path], start, m.group(1)))
# a nested fn is counted on its own and inside its parent, like a reader sees it
fns.sort(key=lambda f: (-f[0], f[1], f[2]))
print()
print("== 2. longest functions (lines from `fn` to its closing brace; test code excluded)")
print(f"functions: {len(fns)}; over 100 lines: {sum(1 for f in fns if f[0] > 100)}; "
      f"over 150 lines: {sum(1 for f in fns if f[0] > 150)}")
for n, path, line, fname in (fns if SHOW_ALL else fns[:15]):
    if SHOW_ALL and n <= 100:
        break
    print(f"  {n:5}  {path}:{line} {fname}()")

# --------------------------------------------------------------------------- mod.rs
print()
print("== 3. mod.rs files: total lines, lines of logic (not mod/use/attribute/comment/blank)")
for mod, path in sorted(files.items(), key=lambda kv: rel_of[kv[1]]):
    if not path.endswith("mod.rs"):
        continue
    raw, code = library_text(path)
    total = raw.count("\n")
    code = USE.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), blank(raw))
    logic = 0
    for l in code.split("\n"):
        s = l.strip()
        if not s or s.startswith("#") or re.match(r"(pub(\([^)]*\))?\s+)?mod\s+" + IDENT + r"\s*;", s):
            continue
        logic += 1
    print(f"  {total:5} {logic:5}  {rel_of[path]}")

# --------------------------------------------------------------------------- cli
print()
print("== 4. src/cli")
cli = sorted((open(p).read().count("\n"), rel_of[p]) for m, p in files.items() if m and m[0] == "cli")
print(f"src/cli: {sum(n for n, _ in cli)} lines in {len(cli)} files; over 250 lines: "
      + ", ".join(f"{p} ({n})" for n, p in sorted(cli, reverse=True) if n > 250))


def cli_kinds(text):
    """Lines of a CLI file by kind: the command line's declaration (clap
    `Args`/`Parser`/`Subcommand`/`ValueEnum` items, doc comments included:
    the `--help` text), other comments, blank, and code (parse, call, print)."""
    k = defaultdict(int)
    in_decl = pending = False
    for line in text.split("\n")[:-1]:
        t = line.strip()
        if t.startswith("#[derive(") and re.search(r"\b(Args|Parser|Subcommand|ValueEnum)\b", t):
            pending = True
        if in_decl or pending:
            k["declaration"] += 1
            if pending and re.match(r"(pub(\([^)]*\))?\s+)?(struct|enum)\b", t):
                pending, in_decl = False, not t.endswith(";")
            elif in_decl and line.startswith("}"):
                in_decl = False
        elif not t:
            k["blank"] += 1
        elif t.startswith("//"):
            k["comment"] += 1
        else:
            k["code"] += 1
    return k


cli_total = defaultdict(int)
for m, p in files.items():
    if m and m[0] == "cli":
        for kind, n in cli_kinds(open(p).read()).items():
            cli_total[kind] += n
print("src/cli by kind: " + ", ".join(f"{kind} {cli_total[kind]}" for kind in ("declaration", "code", "comment", "blank")))

# --------------------------------------------------------------------------- visibility
print()
print("== 5. visibility (library: src/ without src/cli and main.rs; test code excluded)")
pub_items = restricted = pub_fields = 0
kinds = defaultdict(int)
KIND = r"(?:fn|struct|enum|trait|type|const|static|mod|use|unsafe|async|union|extern)\b"
for mod, code in code_of.items():
    if mod and mod[0] in ("cli", "<main>"):
        continue
    for k in re.findall(r"(?<![A-Za-z0-9_])pub\s+(" + KIND[3:-4] + r")\b", code):
        kinds[k] += 1
        pub_items += 1
    restricted += len(re.findall(r"(?<![A-Za-z0-9_])pub\s*\((?:crate|super|in [^)]*)\)", code))
    pub_fields += len(re.findall(r"(?m)^\s*pub\s+" + IDENT + r"\s*:", code))
print(f"pub items: {pub_items}; pub(crate)/pub(super)/pub(in ..): {restricted}; "
      f"pub struct fields: {pub_fields}")
print("pub items by kind: " + ", ".join(f"{k} {n}" for k, n in sorted(kinds.items(), key=lambda kv: -kv[1])))


def declared_pub(mod):
    """True when `mod` is declared `pub mod` (not `pub(crate)`, not private) in its parent."""
    parent = mod[:-1]
    code = code_of.get(parent, "")
    m = re.search(r"(?m)^\s*(pub(?:\s*\([^)]*\))?\s+)?mod\s+" + re.escape(mod[-1]) + r"\s*;", code)
    return bool(m and m.group(1) and m.group(1).strip() == "pub")


reachable = 0
for mod, code in code_of.items():
    if mod and mod[0] in ("cli", "<main>"):
        continue
    if all(declared_pub(mod[:k]) for k in range(1, len(mod) + 1)):
        reachable += len(re.findall(r"(?<![A-Za-z0-9_])pub\s+(" + KIND[3:-4] + r")\b", code))
print(f"pub items reachable from outside the crate (in files whose every module is `pub mod` "
      f"from lib.rs; re-exports not followed): {reachable} of {pub_items}")

# --------------------------------------------------------------------------- binaries
print()
print("== 6. build targets")
def count(d):
    p = os.path.join(ROOT, d)
    return sorted(f for f in os.listdir(p) if f.endswith(".rs")) if os.path.isdir(p) else []
print(f"tests/*.rs (one binary each): {len(count('tests'))}; benches: {len(count('benches'))}; "
      f"examples: {len(count('examples'))}")

# --------------------------------------------------------------------------- flags
print()
print("== 7. library string literals naming a CLI flag (`--word`; src/cli, main.rs, comments, tests excluded)")
STR = re.compile(r'"((?:[^"\\]|\\.)*)"')
per_file = {}
for mod, path in files.items():
    if mod and mod[0] in ("cli", "<main>"):
        continue
    raw = open(path, encoding="utf-8").read()
    cut = raw.find("#[cfg(test)]")
    raw = raw if cut < 0 else raw[:cut]
    raw = "\n".join(l for l in raw.split("\n") if not l.strip().startswith("//"))
    n = sum(1 for m in STR.finditer(raw) if re.search(r"(?<![A-Za-z0-9-])--[a-z][a-z-]+", m.group(1)))
    if n:
        per_file[rel_of[path]] = n
print(f"literals: {sum(per_file.values())} in {len(per_file)} files: "
      + ", ".join(f"{p} {n}" for p, n in sorted(per_file.items(), key=lambda kv: -kv[1])))
