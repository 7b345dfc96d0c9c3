#!/usr/bin/python3
"""The layers point one way: multibody → algorithm → sim → io.

Each layer is compiled against an include root of its own (BUILD/layers/<layer>, made by
src/CMakeLists.txt) that holds its own and the lower layers' headers only.  For every pair of layers
this compiles, from the lower layer's root, a file that includes one public and one private header
of the higher layer (it must fail, with the header not found), and one that includes every public
header of the layer itself and of those below (it must compile): an include that points up cannot build.

    check_layers.py CXX BUILD_DIR SOURCE_DIR EIGEN_INCLUDE
"""
import glob
import os
import subprocess
import sys

LAYERS = ["multibody", "algorithm", "sim", "io"]


def compiles(cxx, root, eigen, text):
    p = subprocess.run([cxx, "-std=c++20", "-fsyntax-only", "-I", root, "-isystem", eigen, "-x", "c++", "-"],
                       input=text, capture_output=True, text=True, timeout=300)
    return p.returncode == 0, p.stderr


def headers(source, layer):
    public = sorted(f'soadyn/{layer}/{os.path.basename(h)}' for h in glob.glob(f"{source}/include/soadyn/{layer}/*.hpp"))
    private = sorted(f'{layer}/{os.path.basename(h)}' for h in glob.glob(f"{source}/src/{layer}/*.hpp"))
    return public, private


def main():
    cxx, build, source, eigen = sys.argv[1:5]
    failures, checked = [], 0
    for i, low in enumerate(LAYERS):
        root = os.path.join(build, "layers", low)
        if not os.path.isdir(root):
            failures.append(f"{root}: no include root (configure the build first)")
            continue
        # the layer itself and every layer below: all their headers compile from here
        below = [h for layer in LAYERS[: i + 1] for h in headers(source, layer)[0]]
        ok, err = compiles(cxx, root, eigen, "".join(f'#include "{h}"\n' for h in below))
        checked += 1
        if not ok:
            failures.append(f"{low}: its own and lower headers do not compile from its root:\n{err[:2000]}")
        for high in LAYERS[i + 1:]:
            public, private = headers(source, high)
            for h in public[:1] + private[:1]:
                ok, err = compiles(cxx, root, eigen, f'#include "{h}"\n')
                checked += 1
                if ok or "No such file" not in err:
                    failures.append(f"{low} reached {high}'s {h}" + ("" if ok else f":\n{err[:500]}"))
    for f in failures:
        print("check_layers:", f)
    print(f"check_layers: {checked} compilations, {len(failures)} wrong")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
