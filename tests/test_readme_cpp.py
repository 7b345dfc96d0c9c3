#!/usr/bin/python3
"""Every ```cpp block of every README compiles against the public headers.

A block with its own main() is a whole program: compiled as it stands (the first one, the library's
example, is also built and run by tests/install/check_install.sh). Any other block is a fragment of
calls: it is compiled as the body of a function whose parameters are the names the READMEs' fragments
use (model, data, q, v, …, PRELUDE below), its #include lines moved above. Syntax and types only
(-fsyntax-only): a call that no longer exists, a wrong argument or a renamed field fails here.

    test_readme_cpp.py CXX INCLUDE_DIR... [--list]      (an INCLUDE_DIR argument may join several with ':')
"""
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.environ.get("SOADYN_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# the names a fragment may use without declaring them
PRELUDE = """[[maybe_unused]] static void fragment(
    soadyn::Scenario& scene, soadyn::Model& model, soadyn::Data& data, soadyn::VecX& q, soadyn::VecX& v,
    soadyn::VecX& qdd, soadyn::VecX& tau, soadyn::Inputs& inputs, soadyn::MatX& Y, soadyn::MatX& dqdd_dpi) {
"""
BASE = ["soadyn/multibody/model.hpp", "soadyn/multibody/data.hpp", "soadyn/sim/scenario.hpp", "soadyn/algorithm/inputs.hpp"]


def readmes():
    out = []
    for dirpath, dirnames, files in os.walk(ROOT):
        dirnames[:] = [d for d in dirnames if not d.startswith(".") and not d.startswith("build") and d != "out"]
        out += [os.path.join(dirpath, f) for f in files if f == "README.md"]
    return sorted(out)


def blocks(path):
    text = open(path, encoding="utf-8").read()
    lines = text.split("\n")
    found = []
    for k, line in enumerate(lines):
        if line.strip() in ("```cpp", "```c++"):
            end = lines.index("```", k + 1)
            found.append((k + 2, "\n".join(lines[k + 1:end])))
    return found


def source(block):
    if re.search(r"\bint\s+main\s*\(", block):
        return block
    includes = [l for l in block.split("\n") if l.strip().startswith("#include")]
    body = [l for l in block.split("\n") if not l.strip().startswith("#include")]
    head = [f'#include "{h}"' for h in BASE] + includes
    return "\n".join(head) + "\n" + PRELUDE + "\n".join(body) + "\n}\n"


def main():
    args = [a for a in sys.argv[1:] if a != "--list"]
    found = [(os.path.relpath(p, ROOT), line, b) for p in readmes() for line, b in blocks(p)]
    if "--list" in sys.argv:
        for path, line, b in found:
            print(f"{path}:{line}: {'program' if 'main(' in b else 'fragment'}, {len(b.splitlines())} lines")
        return 0
    if len(args) < 1:
        sys.exit("usage: test_readme_cpp.py CXX INCLUDE_DIR...")
    cxx, includes = args[0], [i for a in args[1:] for i in a.split(":") if i]  # dirs may come joined by ':' 
    if len(found) < 5:
        sys.exit(f"only {len(found)} C++ blocks found in the READMEs: the extraction is broken")
    failures = []
    with tempfile.TemporaryDirectory(prefix="readme_cpp_") as d:
        for k, (path, line, b) in enumerate(found):
            f = os.path.join(d, f"block{k}.cpp")
            with open(f, "w", encoding="utf-8") as out:
                out.write(source(b))
            cmd = [cxx, "-std=c++20", "-fsyntax-only", *[f"-I{i}" for i in includes], f]
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
            print(f"{path}:{line}: {'ok' if p.returncode == 0 else 'FAILED'}")
            if p.returncode != 0:
                failures.append(f"{path}:{line}:\n{p.stderr.strip()[:3000]}")
    if failures:
        print("\n".join(["", "FAILED:"] + failures))
        return 1
    print(f"all {len(found)} C++ blocks of the READMEs compile")
    return 0


if __name__ == "__main__":
    sys.exit(main())
