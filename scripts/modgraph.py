#!/usr/bin/env python3
"""The module import graph of src/ (non-test code), and its cycles.

    scripts/modgraph.py            top-level modules: edges and cycles
    scripts/modgraph.py output     the modules inside src/output/
    scripts/modgraph.py --all      every module

Exits 1 when the graph at the chosen level has a cycle. A reference is any `crate::` or
`super::` path in code outside `#[cfg(test)]` modules, grouped `use` lists included."""
import os
import re
import sys

SRC = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src")


def module_of(rel):
    parts = rel[:-3].split("/")
    if parts[-1] in ("mod", "lib"):
        parts = parts[:-1]
    return tuple(parts)


def strip(text):
    """The file without comments, strings and `#[cfg(test)]` items."""
    token = re.compile(
        r"//[^\n]*|/\*[\s\S]*?\*/"  # comments
        r'|r(#*)"[\s\S]*?"\1|b?"(?:\\[\s\S]|[^"\\])*"'  # strings
        r"|b?'(?:\\[^']+|[^'\\])'"  # characters
    )
    text = token.sub(lambda m: "" if m.group(0).startswith("/") else '""', text)
    out, i = [], 0
    for m in re.finditer(r"#\[cfg\(test\)\]\s*", text):
        if m.start() < i:
            continue
        out.append(text[i : m.start()])
        j = m.end()
        # skip one item: up to the end of its braces, or to a `;` before any brace
        depth, k = 0, j
        while k < len(text):
            c = text[k]
            if c == ";" and depth == 0:
                k += 1
                break
            if c == "{":
                depth += 1
            elif c == "}":
                depth -= 1
                if depth == 0:
                    k += 1
                    break
            k += 1
        i = k
    out.append(text[i:])
    return "".join(out)


def expand(prefix, body):
    """`a::{b, c::{d, e}}` → [a::b, a::c::d, a::c::e] (the brace part only)."""
    items, depth, cur = [], 0, ""
    for c in body:
        if c == "," and depth == 0:
            items.append(cur)
            cur = ""
            continue
        if c == "{":
            depth += 1
        elif c == "}":
            depth -= 1
        cur += c
    items.append(cur)
    paths = []
    for it in items:
        it = re.sub(r"\s+", "", it)
        if not it:
            continue
        m = re.match(r"^([\w:]*?)::\{(.*)\}$", it)
        if m:
            paths += expand(prefix + "::" + m.group(1), m.group(2))
        else:
            paths.append(prefix + "::" + it.split(" as ")[0])
    return paths


def references(text):
    paths = []
    for m in re.finditer(r"\b((?:crate|super)(?:::super)*)::\{", text):
        depth, k = 1, m.end()
        while depth:
            depth += {"{": 1, "}": -1}.get(text[k], 0)
            k += 1
        paths += expand(m.group(1), text[m.end() : k - 1])
    paths += re.findall(r"\b((?:crate|super)(?:::super)*(?:::\w+)+)", text)
    return paths


def resolve(module, path, modules):
    parts = path.split("::")
    if parts[0] == "crate":
        base, rest = (), parts[1:]
    else:
        base = module
        while parts and parts[0] == "super":
            base, parts = base[:-1], parts[1:]
        rest = parts
    full = base + tuple(p for p in rest if p not in ("self", "*"))
    while full and full not in modules:
        full = full[:-1]
    return full


def level(module, scope):
    if scope == "all":
        return "::".join(module) or "lib"
    if scope == "top":
        return module[0] if module else "lib"
    if module[:1] != (scope,):
        return None
    return "::".join(module[:2])


def main():
    scope = "top"
    if len(sys.argv) > 1:
        scope = "all" if sys.argv[1] == "--all" else sys.argv[1]
    files = {}
    for root, _, names in os.walk(SRC):
        for n in names:
            if n.endswith(".rs") and n != "main.rs":
                rel = os.path.relpath(os.path.join(root, n), SRC).replace(os.sep, "/")
                files[module_of(rel)] = open(os.path.join(root, n)).read()
    modules = set(files)
    edges = {}
    for module, text in files.items():
        a = level(module, scope)
        if a is None:
            continue
        edges.setdefault(a, set())
        code = strip(text)
        children = {m[-1] for m in modules if m[:-1] == module and len(m) == len(module) + 1}
        local = [
            "::".join(("crate",) + module + (c,))
            for c in re.findall(r"(?<![\w:])(\w+)::", code)
            if c in children
        ]
        for p in references(code) + local:
            b = level(resolve(module, p, modules), scope)
            if b is not None and b != a:
                edges[a].add(b)
                edges.setdefault(b, set())
    for a in sorted(edges):
        print(f"{a} -> {', '.join(sorted(edges[a])) or '-'}")
    cycles = [c for c in sccs(edges) if len(c) > 1]
    for c in cycles:
        print("CYCLE:", " <-> ".join(sorted(c)))
    if not cycles:
        print("no cycles")
    return 1 if cycles else 0


def sccs(edges):
    index, low, stack, on, out, n = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = n[0]
        n[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
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
            out.append(comp)

    sys.setrecursionlimit(10000)
    for v in list(edges):
        if v not in index:
            visit(v)
    return out


if __name__ == "__main__":
    sys.exit(main())
