#!/usr/bin/env python3
"""Fails when a C++ function under the given folders is too long (issue 24: every subcommand a thin layer).

Usage: function-lengths.py [--max-lines N] [--list K] [--exclude-dir NAME]... PATH...
  PATH          folders (searched for *.cpp, *.cxx, *.h) or single files
  --exclude-dir skip folders of this name (e.g. test: GoogleTest bodies are checked elsewhere)
  --max-lines the longest a function may be, lines (default 59: "under 60 lines")
  --list      also print the K longest functions

A function's length counts its lines from the first line of its declaration (after the previous
declaration's end, blank lines and comments skipped) to its closing brace, both included. Member
functions defined in a class body, GoogleTest TEST bodies and lambdas at namespace scope count as
functions; a lambda or local class inside a function counts towards that function.

The parser is a brace matcher over the text with comments, string and character literals and
preprocessor lines blanked out (no compiler needed, so the check runs in a second on any machine).
It knows namespaces, classes/structs/unions/enums, extern "C" blocks and brace initialisers; what it
cannot classify counts as a function, so a mistake errs towards a failing check, never a silent pass.
Exit status: 0 when every function is short enough, 1 when one is not (each named on one line with its
file, line and length), 2 for bad usage.
"""
import argparse
import os
import re
import sys

SOURCE_SUFFIXES = (".cpp", ".cxx", ".cc", ".h", ".hpp", ".hxx")
SCOPE_KEYWORDS = re.compile(r"\b(namespace|class|struct|union|enum)\b")


def blank_out(text):
    """The text with comments, literals and preprocessor lines replaced by spaces (newlines kept)."""
    out = []
    i, n = 0, len(text)
    at_line_start = True
    while i < n:
        c = text[i]
        if at_line_start and c == "#":
            # A preprocessor line, with its backslash continuations.
            while i < n and text[i] != "\n":
                if text[i] == "\\" and i + 1 < n and text[i + 1] == "\n":
                    out.append(" \n")
                    i += 2
                    continue
                out.append(" ")
                i += 1
            continue
        if c in " \t":
            out.append(c)
            i += 1
            continue
        if c == "\n":
            out.append(c)
            at_line_start = True
            i += 1
            continue
        at_line_start = False
        if text.startswith("//", i):
            while i < n and text[i] != "\n":
                out.append(" ")
                i += 1
            continue
        if text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
            out.append(re.sub(r"[^\n]", " ", text[i:end]))
            i = end
            continue
        raw = re.match(r'(?:u8|u|U|L)?R"([^(\s]*)\(', text[i:i + 32])
        if raw and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            close = ")" + raw.group(1) + '"'
            end = text.find(close, i + raw.end())
            end = n if end < 0 else end + len(close)
            out.append('"' + re.sub(r"[^\n]", " ", text[i + 1:end - 1]) + '"')
            i = end
            continue
        if c in "\"'":
            # A digit separator (1'000'000) is not a character literal.
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and text[i + 1].isalnum():
                out.append(" ")
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + " " * (min(j, n) - i - 1) + (c if j < n else ""))
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


def classify(header):
    """What a '{' opens, from the code before it: 'scope' (descend), 'init' (skip), 'member-init' (a brace
    initialiser in a constructor's initialiser list: skip, the header goes on) or 'function'."""
    h = " ".join(header.split())
    h = re.sub(r"^((public|protected|private)\s*:\s*)+", "", h)
    if not h or h.startswith(","):
        return "init"  # a bare block does not occur at scope level; ", b{...}" is the next declarator's initialiser
    if re.search(r'\bextern\s+"', h):
        return "scope"
    if SCOPE_KEYWORDS.search(h) and "(" not in h.split(":")[0]:
        return "scope"
    if re.search(r"\]\s*(\([^)]*\))?\s*(mutable\s*)?(->[^{]*)?$", h) and "[" in h:
        return "function"  # a lambda at namespace scope
    if re.search(r"(?<![=!<>+\-*/%&|^])=(?!=)", h) and "operator" not in h:
        return "init"
    if "(" not in h:
        return "init"  # Type name{...}: a variable's brace initialiser
    if re.search(r"\)\s*:\s*[A-Za-z_]", h) and not re.search(r"\)\s*(const|noexcept|override|final|\s)*$", h):
        return "member-init"
    return "function"


def functions(path):
    """(name, first line, last line) of each function defined in the file."""
    with open(path, encoding="utf-8", errors="replace") as f:
        text = blank_out(f.read())
    line_of = []
    line = 1
    for ch in text:
        line_of.append(line)
        if ch == "\n":
            line += 1
    found = []
    stack = []  # kinds of the open braces at scope level ('scope'); a function's braces are skipped whole
    header_start = 0
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c in ";}":
            if c == "}" and stack:
                stack.pop()
            header_start = i + 1
            i += 1
            continue
        if c == "{":
            header = text[header_start:i]
            kind = classify(header)
            name_header = re.sub(r"^\s*((public|protected|private)\s*:\s*)+", "", header)
            if kind == "scope":
                stack.append("scope")
                header_start = i + 1
                i += 1
                continue
            # Skip to the matching brace.
            depth, j = 0, i
            while j < n:
                if text[j] == "{":
                    depth += 1
                elif text[j] == "}":
                    depth -= 1
                    if depth == 0:
                        break
                j += 1
            if kind == "member-init":
                i = j + 1  # the constructor's header goes on to its body
                continue
            if kind == "function":
                start = header_start + (len(header) - len(name_header.lstrip()))
                name = re.sub(r"\s+", " ", name_header.strip())
                name = name[:90] + ("..." if len(name) > 90 else "")
                found.append((name, line_of[min(start, n - 1)], line_of[min(j, n - 1)]))
            # An initialiser ends at its ';', which resets the header; a function body ends here.
            header_start = j + 1
            i = j + 1
            continue
        i += 1
    return found


def source_files(paths, excluded):
    for p in paths:
        if os.path.isfile(p):
            yield p
            continue
        for root, dirs, files in os.walk(p):
            dirs[:] = sorted(d for d in dirs if d not in excluded)
            for name in sorted(files):
                if name.endswith(SOURCE_SUFFIXES):
                    yield os.path.join(root, name)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("paths", nargs="+")
    parser.add_argument("--max-lines", type=int, default=59)
    parser.add_argument("--list", type=int, default=0)
    parser.add_argument("--exclude-dir", action="append", default=[])
    args = parser.parse_args()
    missing = [p for p in args.paths if not os.path.exists(p)]
    if missing:
        print("function-lengths.py: " + missing[0] + " does not exist; give folders or files to check", file=sys.stderr)
        return 2
    everything = []
    for path in source_files(args.paths, set(args.exclude_dir)):
        for name, first, last in functions(path):
            everything.append((last - first + 1, path, first, name))
    everything.sort(key=lambda f: (-f[0], f[1], f[2]))
    for length, path, first, name in everything[: args.list]:
        print(f"{length:4d} lines  {path}:{first}  {name}")
    too_long = [f for f in everything if f[0] > args.max_lines]
    for length, path, first, name in too_long:
        print(f"{path}:{first}: function is {length} lines, longer than {args.max_lines}: {name} "
              "(split it, or move its work into the module that owns it)", file=sys.stderr)
    print(f"function-lengths.py: {len(everything)} functions, longest {everything[0][0] if everything else 0} lines; "
          f"{len(too_long)} longer than {args.max_lines}")
    return 1 if too_long else 0


if __name__ == "__main__":
    sys.exit(main())
