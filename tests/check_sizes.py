#!/usr/bin/python3
"""No function over 80 lines, no file over 520 (the issue "The house as layers").

Every C++ function body in src/ and include/ is at most MAX_FUNCTION lines, from the line of its
opening brace to that of its closing one; every source file in src/, include/, tools/ and tests/
(.cpp, .hpp, .py, .js) is at most MAX_FILE lines.  One line per offender,

    path:line: N lines: name

then a count; the exit status is 1 when there is any (ctest sizes).

A function is found by its braces, not by a compiler: comments, string and character literals (raw
strings too) are blanked first; a brace opens a function when it is outside every function, not a
namespace, class, struct, union or enum's, and the text before it since the last brace or ';' holds
a ')' (a function's or a lambda's parameters, a constructor's initializers).  Braces inside a
function (blocks, lambdas, local classes) count towards it.

    check_sizes.py [SOURCE_DIR]      (default: the folder above this script's)
"""
import pathlib
import re
import sys

MAX_FUNCTION = 80
MAX_FILE = 520
FUNCTION_ROOTS = ["src", "include"]
FILE_ROOTS = ["src", "include", "tools", "tests"]
CXX = {".cpp", ".hpp", ".cc", ".h"}
SOURCES = {".cpp", ".hpp", ".py", ".js"}

# namespace, class, struct, union or enum without a '(' or ')' after the keyword: a scope, not a body
SCOPE = re.compile(r"\b(namespace|class|struct|union|enum)\b[^()]*$")
RAW_OPEN = re.compile(r'R"([^()\\\s"]{0,16})\(')


def blank_code(text):
    """`text` with comments and the contents of string and character literals blanked (newlines kept,
    so line numbers stay) and preprocessor lines emptied."""
    out, i, n = [], 0, len(text)
    line_start = True
    while i < n:
        c = text[i]
        if line_start and c in " \t":
            out.append(c)
            i += 1
            continue
        if line_start and c == "#":  # a preprocessor line, with its continuations
            while i < n and not (text[i] == "\n" and text[i - 1] != "\\"):
                out.append("\n" if text[i] == "\n" else " ")
                i += 1
            continue
        line_start = False
        if text.startswith("//", i):
            while i < n and text[i] != "\n":
                i += 1
            continue
        if text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
            out.append("".join("\n" for ch in text[i:end] if ch == "\n") or " ")
            i = end
            continue
        raw = RAW_OPEN.match(text, i) if c == "R" and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")) else None
        if raw:
            close = ")" + raw.group(1) + '"'
            end = text.find(close, raw.end())
            end = n if end < 0 else end + len(close)
            out.append('""' + "".join("\n" for ch in text[i:end] if ch == "\n"))
            i = end
            continue
        if c == '"' or (c == "'" and not (i > 0 and text[i - 1].isalnum())):  # not a digit separator (1'000)
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
            continue
        if c == "\n":
            line_start = True
        out.append(c)
        i += 1
    return "".join(out)


def function_name(header):
    """The function's name from the text before its brace: `H5Log::H5Log`, `operator()`, `TEST(A, B)`."""
    h = re.sub(r"\s+", " ", header).strip()
    h = re.sub(r"^template ?<[^{};]*?> ?(?=[A-Za-z_])", "", h)
    m = re.search(r"((?:[A-Za-z_]\w*::)*(?:operator ?(?:\(\)|[^\s(]+)|~?[A-Za-z_]\w*)) ?\(", h)
    if not m:
        return h[-90:]
    name = m.group(1)
    if name.isupper():  # a macro's (TEST_F): its arguments name it
        close = h.find(")", m.end())
        return h[m.start(1):close + 1] if close > 0 else name
    return name


def long_functions(path, limit):
    """(line, length, name) of every function in the C++ file `path` longer than `limit` lines."""
    code = blank_code(path.read_text(errors="replace"))
    found, stack, header, line = [], [], "", 1  # stack: (kind, first line, header); kind f, scope or block
    for ch in code:
        if ch == "{":
            h = header.strip()
            in_function = any(kind == "f" for kind, _, _ in stack)
            if in_function:
                kind = "b"
            elif SCOPE.search(h) or h.endswith('extern ""'):
                kind = "scope"
            else:
                kind = "f" if ")" in h else "b"
            stack.append((kind, line, h))
            header = ""
        elif ch == "}":
            header = ""
            if stack:
                kind, first, h = stack.pop()
                if kind == "f" and line - first + 1 > limit:
                    found.append((first, line - first + 1, function_name(h)))
                if kind == "b" and not any(k == "f" for k, _, _ in stack):
                    header = h + " {} "  # a braced initializer outside a function: a default argument's
        elif ch == ";":
            header = ""
        else:
            header += ch
        if ch == "\n":
            line += 1
    return found


def files(source, roots, suffixes):
    """The files under source/<root> ending in one of `suffixes`, hidden folders and caches left out."""
    for root in roots:
        for p in sorted((source / root).rglob("*")):
            if p.suffix in suffixes and p.is_file() and not any(part.startswith(".") or part == "__pycache__"
                                                               for part in p.relative_to(source).parts):
                yield p


def main():
    source = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent)
    functions = 0
    for p in files(source, FUNCTION_ROOTS, CXX):
        for first, length, name in long_functions(p, MAX_FUNCTION):
            print(f"{p.relative_to(source)}:{first}: {length} lines: {name}")
            functions += 1
    too_long = checked = 0
    for p in files(source, FILE_ROOTS, SOURCES):
        checked += 1
        n = len(p.read_text(errors="replace").splitlines())
        if n > MAX_FILE:
            print(f"{p.relative_to(source)}:1: {n} lines: the file (at most {MAX_FILE})")
            too_long += 1
    if functions or too_long:
        print(f"{functions} function(s) over {MAX_FUNCTION} lines in {', '.join(FUNCTION_ROOTS)}; "
              f"{too_long} file(s) over {MAX_FILE} lines in {', '.join(FILE_ROOTS)}: split them by concern")
        return 1
    if checked == 0:
        print(f"{source}: no source files under {', '.join(FILE_ROOTS)}")
        return 1
    print(f"sizes: every function in {', '.join(FUNCTION_ROOTS)} at most {MAX_FUNCTION} lines; "
          f"{checked} files at most {MAX_FILE} lines")
    return 0


if __name__ == "__main__":
    sys.exit(main())
