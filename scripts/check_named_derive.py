#!/usr/bin/env python3
"""Checks that two texts of `lagc derive` say the same equations: OLD
written out in full, NEW with shared subexpressions named (`w1 = …`,
`v1 = …`). Every line that differs is split at ` = `; each side is
evaluated in both texts (NEW's names from their definitions) at random
values of every symbol, and must agree to 1e-9 relative to the sum of the
magnitudes of the terms (a rounding scale).

Usage: python3 scripts/check_named_derive.py OLD.txt NEW.txt [...pairs]
Exit status 1 when some line differs in value.
"""

import math
import random
import re
import sys

NAMED = re.compile(r"^\s+([wv]+\d+) = (.*)$")
SECTION = "shared subexpressions (named once, used below):"


def split_if(text: str) -> str:
    """`(if G < 0 then A else B)` → `(_sel(G, lambda: A, lambda: B))`."""
    out = []
    i = 0
    while True:
        j = text.find("(if ", i)
        if j < 0:
            out.append(text[i:])
            return "".join(out)
        out.append(text[i:j])
        # the matching parenthesis of "(if"
        depth = 0
        k = j
        while True:
            c = text[k]
            if c == "(":
                depth += 1
            elif c == ")":
                depth -= 1
                if depth == 0:
                    break
            k += 1
        inner = text[j + 4 : k]
        parts = top_level_split(inner, [" then ", " else "])
        g, a, b = parts
        g = g[: g.rindex(" < 0")]
        out.append(
            f"(_sel({split_if(g)}, lambda: {split_if(a)}, lambda: {split_if(b)}))"
        )
        i = k + 1


def top_level_split(text: str, seps):
    parts = []
    depth = 0
    start = 0
    k = 0
    want = list(seps)
    while k < len(text) and want:
        c = text[k]
        if c == "(":
            depth += 1
        elif c == ")":
            depth -= 1
        elif depth == 0 and text.startswith(want[0], k):
            parts.append(text[start:k])
            k += len(want[0])
            start = k
            want.pop(0)
            continue
        k += 1
    parts.append(text[start:])
    return parts


def pythonic(expr: str) -> str:
    expr = split_if(expr)
    expr = re.sub(r"\^\((\d+)\)", r"_d\1", expr)  # q1^(4)
    expr = expr.replace("^", "**")
    expr = re.sub(r"([A-Za-z_][A-Za-z_0-9]*)('+)", lambda m: m.group(1) + "_p" * len(m.group(2)), expr)
    return expr


FUNCS = {
    "sin": math.sin, "cos": math.cos, "tan": math.tan, "asin": math.asin,
    "acos": math.acos, "atan": math.atan, "sinh": math.sinh, "cosh": math.cosh,
    "tanh": math.tanh, "exp": math.exp, "ln": math.log, "sqrt": math.sqrt,
}


class Env(dict):
    """Symbols get random values on first use, from the point and the
    name (so the same in both texts)."""

    def __init__(self, seed):
        super().__init__(FUNCS)
        self["_sel"] = lambda g, a, b: a() if g < 0 else b()
        self["__builtins__"] = {}
        self.seed = seed


def body(lines):
    """The lines without the sections of definitions, each with the
    definitions in force there (each mode's text and the field's section
    define their own names; a later definition replaces an earlier one)."""
    out = []
    defs = {}
    for line in lines:
        if line.strip() == SECTION:
            continue
        m = NAMED.match(line)
        if m:
            defs = dict(defs)
            defs[m.group(1)] = m.group(2)
            continue
        if line.strip() == "":
            continue
        out.append((line, defs))
    return out


def sides(line):
    text = line.strip()
    label = re.match(r"^[A-Za-z_][A-Za-z_0-9']*: ", text)
    if label:
        text = text[label.end():]
    return top_level_split(text, [" = "]) if " = " in text else [text]


def value(expr, env):
    expr = expr.split("  (")[0]  # a note such as "  (fixed by the constraints)"
    code = pythonic(expr)
    for name in re.findall(r"[A-Za-z_][A-Za-z_0-9]*", code):
        if name not in env and name != "lambda":
            env[name] = random.Random(f"{env.seed}:{name}").uniform(0.2, 0.9)
    try:
        return eval(code, env)
    except (ValueError, ZeroDivisionError, OverflowError, TypeError):
        return None
    except SyntaxError:
        raise SyntaxError(f"cannot read: {expr[:200]}")


def compare(old_path, new_path, points=5):
    old = open(old_path).read().splitlines()
    new = open(new_path).read().splitlines()
    old_body, new_body = body(old), body(new)
    if len(old_body) != len(new_body):
        print(f"{new_path}: {len(old_body)} lines against {len(new_body)}")
        return False, 0
    ok = True
    checked = 0
    for (a, _), (b, defs) in zip(old_body, new_body):
        if a == b:
            continue
        sa, sb = sides(a), sides(b)
        if len(sa) != len(sb):
            print(f"{new_path}: different shape:\n  {a[:120]}\n  {b[:120]}")
            ok = False
            continue
        for p in range(points):
            env = Env(p)
            for name, d in defs.items():
                env[name] = value(d, env)
            for x, y in zip(sa, sb):
                vx, vy = value(x, env), value(y, env)
                if not (isinstance(vx, float) and isinstance(vy, float)):
                    continue
                scale = abs(vx) + abs(vy) + 1e-300
                if abs(vx - vy) > 1e-9 * max(scale, 1.0):
                    print(f"{new_path}: {vx!r} != {vy!r} in\n  {a[:160]}\n  {b[:160]}")
                    ok = False
                checked += 1
    return ok, checked


def main():
    args = sys.argv[1:]
    ok = True
    total = 0
    for old, new in zip(args[::2], args[1::2]):
        good, n = compare(old, new)
        ok &= good
        total += n
    print(f"{total} comparisons, {'all equal' if ok else 'DIFFERENCES'}")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
