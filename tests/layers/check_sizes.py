#!/usr/bin/env python3
"""Sizes a reader can hold: no source file over 800 lines and no function over 150 lines,
outside the tests (tests/, the test support and the benchmarks).

usage: check_sizes.py SOURCE_DIR | --self-test
Prints each file or function over its limit (path, line, lines, name); exit status 1 when there
is one. A function is a brace block at namespace or class level whose head ends in a parameter
list (with its qualifiers); lambdas and blocks inside it count towards it. --self-test runs the
check on a small tree and fails unless it finds exactly the seeded offenders.
"""
import os
import re
import sys
import tempfile

MAX_FILE = 800
MAX_FUNCTION = 150
FOLDERS = ("hal", "lib", "drivers", "runtime", "nav", "slam", "ssc", "cobot", "formation", "view", "firmware",
           "centre", "sim")
SOURCES = (".cpp", ".hpp", ".h", ".cc")

# Text before a '{' that opens a scope, not a function.
CONTAINER = re.compile(r'\b(namespace|class|struct|union|enum)\b[^()]*$|extern\s+"C"\s*$')
# A head that ends in a parameter list, then optional qualifiers, a trailing return type,
# or a constructor's member initialisers.
QUALIFIERS = r'(\s*(const|noexcept(\([^()]*\))?|override|final|mutable|&&?|->\s*[\w:<>,\s*&]+))*'
FUNCTION = re.compile(r'\)' + QUALIFIERS + r'\s*$')
INITIALISERS = re.compile(r'\)\s*:\s*[\w:]+\s*[({]')
# A constructor's initialiser list, and a '{' that initialises a member in it (`v_{1}`).
MEMBER_INIT = re.compile(r'\)\s*:(?!:)')
INIT_BRACE = re.compile(r'[\w>]$')
CONTROL = re.compile(r'\b(if|for|while|switch|catch)\s*\(')


def strip(text):
    """Comments, strings and character literals blanked (newlines kept, so lines still count)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
        elif c == 'R' and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == '_')):
            k = text.find("(", i + 2)
            delim = text[i + 2:k]
            j = text.find(")" + delim + '"', k)
            j = n if j < 0 else j + len(delim) + 2
            out.append('""' + "\n" * text.count("\n", i, j))
            i = j
        elif c in "\"'":
            if c == "'" and i > 0 and text[i - 1].isalnum():  # a digit separator: 1'000
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(text):
    """(first line, lines, name) of each function body at namespace or class level."""
    code = strip(text)
    found = []
    stack = []  # per open brace: "scope" (namespace/class level) or "body"/"inner"
    head_start = 0
    for i, c in enumerate(code):
        if c == "{":
            in_body = any(kind not in ("scope", "init") for kind in stack)
            head = code[head_start:i]
            flat = " ".join(head.split())
            if in_body:
                stack.append("inner")
            elif MEMBER_INIT.search(flat) and INIT_BRACE.search(flat):
                stack.append("init")  # a member initialised with braces: the head goes on
                continue
            else:
                if CONTAINER.search(flat) or not (FUNCTION.search(flat) or INITIALISERS.search(flat)) \
                        or CONTROL.search(flat.split("(")[0] + "("):
                    stack.append("scope")
                else:
                    stack.append(("body", i, flat))
            head_start = i + 1
        elif c == "}":
            if stack:
                kind = stack.pop()
                if kind == "init":
                    continue
                if isinstance(kind, tuple):
                    _, start, flat = kind
                    first = code.count("\n", 0, start) + 1
                    last = code.count("\n", 0, i) + 1
                    name = re.findall(r'([~\w:]+(?:operator\W+)?)\s*\(', flat)
                    found.append((first, last - first + 1, name[0] if name else flat[-60:]))
            head_start = i + 1
        elif c == ";" and not any(kind not in ("scope", "init") for kind in stack):
            head_start = i + 1
    return found


def check(root, out):
    bad = 0
    for folder in FOLDERS:
        for dirpath, dirs, files in os.walk(os.path.join(root, folder)):
            dirs.sort()
            for name in sorted(files):
                if not name.endswith(SOURCES):
                    continue
                path = os.path.join(dirpath, name)
                rel = os.path.relpath(path, root)
                with open(path, encoding="utf-8", errors="replace") as f:
                    text = f.read()
                lines = text.count("\n")
                if lines > MAX_FILE:
                    out.append(f"{rel}: {lines} lines (limit {MAX_FILE})")
                    bad += 1
                for first, length, fname in functions(text):
                    if length > MAX_FUNCTION:
                        out.append(f"{rel}:{first}: {fname}: {length} lines (limit {MAX_FUNCTION})")
                        bad += 1
    return bad


def self_test():
    long_body = "\n".join("  x += %d;" % k for k in range(MAX_FUNCTION))
    files = {
        "sim/a.cpp": "namespace n {\nint ok(int x) {\n  return x;\n}\n"
                     "int too_long(int x) {\n" + long_body + "\n  return x;\n}\n}  // namespace n\n",
        "sim/b.hpp": "struct S {\n  S() : v_{1} {\n" + long_body + "\n  }\n  int v_;\n};\n",
        "lib/c.cpp": "// a string with a brace \"{\" and a lambda\nint f() {\n  auto g = [] { return 1; };\n"
                     "  const char* s = \"}\";\n  return g() + s[0];\n}\n" + "\n" * (MAX_FILE + 1),
        "firmware/d.cpp": "namespace {\nstruct T { int a; };\nvoid h() const noexcept {\n"
                          + "\n".join("  if (a) { b(); }" for _ in range(10)) + "\n}\n}\n",
        "tests/e.cpp": "int t() {\n" + long_body + "\n}\n",
    }
    with tempfile.TemporaryDirectory() as root:
        for rel, text in files.items():
            os.makedirs(os.path.join(root, os.path.dirname(rel)), exist_ok=True)
            with open(os.path.join(root, rel), "w") as f:
                f.write(text)
        out = []
        check(root, out)
    expected = ["lib/c.cpp: ", "sim/a.cpp:5: too_long:", "sim/b.hpp:2: S:"]
    got = sorted(out)
    ok = len(got) == len(expected) and all(g.startswith(e) for g, e in zip(got, expected))
    print("\n".join(got))
    print("self-test", "passed" if ok else "FAILED")
    return 0 if ok else 1


def main(argv):
    if len(argv) == 2 and argv[1] == "--self-test":
        return self_test()
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    out = []
    bad = check(argv[1], out)
    print("\n".join(out) if out else "every source file and function within its limit")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
