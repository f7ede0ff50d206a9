#!/usr/bin/env python3
"""Non-test functions of src/ longer than N lines (default 60), longest first, and files longer
than 600 lines.

    scripts/fnlen.py [N] [--skip PREFIX ...]
"""
import os
import re
import sys

SRC = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src")
TOKEN = re.compile(
    r"//[^\n]*|/\*[\s\S]*?\*/"
    r'|r(#*)"[\s\S]*?"\1|b?"(?:\\[\s\S]|[^"\\])*"'
    r"|b?'(?:\\[^']+|[^'\\])'"
)


def blank(m):
    # keep line breaks so line numbers stay
    return re.sub(r"[^\n]", " ", m.group(0))


def functions(text):
    code = TOKEN.sub(blank, text)
    tests = [m.start() for m in re.finditer(r"#\[cfg\(test\)\]", code)]
    for m in re.finditer(r"\bfn\s+(\w+)", code):
        if any(t < m.start() for t in tests) and in_test(code, tests, m.start()):
            continue
        open_at = body_start(code, m.end())
        if open_at is None:
            continue
        depth, k = 0, open_at
        while k < len(code):
            if code[k] == "{":
                depth += 1
            elif code[k] == "}":
                depth -= 1
                if depth == 0:
                    break
            k += 1
        start = code.count("\n", 0, m.start()) + 1
        end = code.count("\n", 0, k) + 1
        yield m.group(1), start, end - start + 1


def body_start(code, at):
    """Where the body of the function whose signature starts at `at` opens; `None` for a
    declaration without one (`fn f();` in a trait)."""
    depth = 0
    for k in range(at, len(code)):
        c = code[k]
        if c in "([":
            depth += 1
        elif c in ")]":
            depth -= 1
        elif depth == 0 and c == "{":
            return k
        elif depth == 0 and c == ";":
            return None
    return None


def in_test(code, tests, at):
    """Whether `at` lies inside the item that follows a `#[cfg(test)]`."""
    for t in tests:
        if t > at:
            continue
        open_at = code.find("{", t)
        semi = code.find(";", t)
        if 0 <= semi < open_at:
            continue
        depth, k = 0, open_at
        while k < len(code):
            depth += {"{": 1, "}": -1}.get(code[k], 0)
            if depth == 0:
                break
            k += 1
        if open_at <= at <= k:
            return True
    return False


def main():
    args = sys.argv[1:]
    limit = int(args.pop(0)) if args and args[0].isdigit() else 60
    skip = args[args.index("--skip") + 1 :] if "--skip" in args else []
    long_fns, long_files = [], []
    for root, _, names in os.walk(SRC):
        for n in names:
            if not n.endswith(".rs"):
                continue
            path = os.path.join(root, n)
            rel = "src/" + os.path.relpath(path, SRC).replace(os.sep, "/")
            if any(rel.startswith(s) for s in skip):
                continue
            text = open(path).read()
            lines = text.count("\n")
            if lines > 600:
                long_files.append((lines, rel))
            for name, line, length in functions(text):
                if length > limit:
                    long_fns.append((length, f"{rel}:{line}", name))
    for lines, rel in sorted(long_files, reverse=True):
        print(f"file {rel}: {lines} lines")
    for length, where, name in sorted(long_fns, reverse=True):
        print(f"fn {name} ({where}): {length} lines")
    return 1 if long_files or long_fns else 0


if __name__ == "__main__":
    sys.exit(main())
