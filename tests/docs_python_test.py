#!/usr/bin/env python3
"""The Python examples of docs/python.md run, and print what the page says they print.

Every ```python block of the page is run, in order, in one namespace, in a temporary working
directory. An expression statement whose line ends in a comment states its value: the comment,
cut at some ", " (the rest is prose: "# 6.38..., configs/default.yaml's phi_net"), must read as a
Python literal equal to the value (floats to 1e-9 relative; a tuple's parentheses may be left out).
A block with no such comment only has to run without an exception.

    tests/docs_python_test.py SRC BUILD        (PYTHONPATH=BUILD/python; test docs_python_examples)
"""
import ast
import io
import math
import os
import re
import sys
import tempfile
import tokenize


def blocks(text):
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


def comments(code):
    out = {}
    for tok in tokenize.generate_tokens(io.StringIO(code).readline):
        if tok.type == tokenize.COMMENT:
            out[tok.start[0]] = tok.string[1:].strip()
    return out


def same(a, b):
    if isinstance(a, float) or isinstance(b, float):
        try:
            return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=1e-12)
        except (TypeError, ValueError):
            return False
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return type(a) == type(b) and len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    return a == b


def stated(comment):
    """Every literal the comment may state: its prefixes cut at ', ', longest first."""
    parts = comment.split(", ")
    out = []
    for n in range(len(parts), 0, -1):
        text = ", ".join(parts[:n])
        try:
            out.append(ast.literal_eval(text))
        except (ValueError, SyntaxError):
            continue
    return out


def main():
    src = sys.argv[1]
    page = os.path.join(src, "docs", "python.md")
    with open(page, encoding="utf-8") as f:
        codes = blocks(f.read())
    if not codes:
        sys.exit(f"FAIL: no ```python block in {page}")
    checked = 0
    ns = {}
    with tempfile.TemporaryDirectory() as work:
        os.chdir(work)
        for b, code in enumerate(codes, 1):
            notes = comments(code)
            for stmt in ast.parse(code).body:
                line = code.splitlines()[stmt.lineno - 1].strip()
                note = notes.get(stmt.end_lineno)
                if isinstance(stmt, ast.Expr) and note is not None:
                    value = eval(compile(ast.Expression(stmt.value), f"<block {b}>", "eval"), ns)
                    want = stated(note)
                    if not any(same(value, w) for w in want):
                        sys.exit(f"FAIL: docs/python.md block {b}: `{line}` gives {value!r}; the page says # {note}")
                    print(f"ok: {line.split('#')[0].strip()} == {value!r}")
                    checked += 1
                else:
                    exec(compile(ast.Module([stmt], []), f"<block {b}>", "exec"), ns)
    print(f"docs_python_examples: {len(codes)} blocks ran, {checked} printed values as the page states")


if __name__ == "__main__":
    main()
