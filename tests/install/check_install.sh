#!/usr/bin/env bash
# ctest install_consume: `cmake --install` into a scratch prefix, then only what it put there:
#  - include/soadyn/README.md's C++ example is tests/install/consumer.cpp, byte for byte, and the
#    top README's C++ block builds with pkg-config and runs on tests/data/arm7.urdf;
#  - consumer.cpp built with find_package(soadyn) (soadyn::soadyn, the static library) and with
#    pkg-config (the shared library), each run: both check 𝓜, bias and q̈ of a two-link arm
#    against the closed form (1e-12);
#  - the installed soadyn executable runs, and its `soadyn sweep` imports the installed Python
#    package, which imports from the prefix alone.
#   check_install.sh BUILD_DIR SOURCE_DIR CMAKE CXX LIBDIR BINDIR PYTHON_DIR
# (LIBDIR, BINDIR, PYTHON_DIR relative to the prefix; PYTHON_DIR "-" when the build has no Python
# module: its checks are left out)
# The scratch directory (BUILD_DIR/install_check) is removed when every check passes.
set -euo pipefail
build=$1 source=$2 cmake=$3 cxx=$4 libdir=$5 bindir=$6 pydir=$7
scratch=$build/install_check
prefix=$scratch/prefix
site=$prefix/$pydir
rm -rf "$scratch"
mkdir -p "$scratch"
fail() { echo "install_consume: $*" >&2; exit 1; }

echo "== include/soadyn/README.md's C++ example is tests/install/consumer.cpp"
first_cpp() { awk '/^```cpp$/ {c = 1; next} c && /^```$/ {exit} c' "$1"; }
first_cpp "$source/include/soadyn/README.md" >"$scratch/library_example.cpp"
diff -u "$scratch/library_example.cpp" "$source/tests/install/consumer.cpp" ||
  fail "the first C++ block of include/soadyn/README.md differs from tests/install/consumer.cpp"
first_cpp "$source/README.md" >"$scratch/readme_example.cpp"
[[ -s $scratch/readme_example.cpp ]] || fail "README.md has no C++ block"
second_cpp() { awk '/^```cpp$/ {n++; if (n == 2) {c = 1; next}} c && /^```$/ {exit} c' "$1"; }
second_cpp "$source/README.md" >"$scratch/readme_run.cpp"
grep -q 'soadyn::simulate(' "$scratch/readme_run.cpp" || fail "README.md's second C++ block does not call simulate"

echo "== cmake --install $build --prefix $prefix"
"$cmake" --install "$build" --prefix "$prefix" >"$scratch/install.log"
for f in include/soadyn/algorithm/algorithms.hpp include/soadyn/multibody/types.hpp "$libdir/libsoadyn.a" "$libdir/libsoadyn.so" \
  "$libdir/cmake/soadyn/soadynConfig.cmake" "$libdir/cmake/soadyn/soadynConfigVersion.cmake" \
  "$libdir/pkgconfig/soadyn.pc" "$bindir/soadyn"; do
  [[ -e $prefix/$f ]] || fail "not installed: $f"
done
[[ $(readlink "$prefix/$libdir/libsoadyn.so") =~ ^libsoadyn\.so\.[0-9] ]] || fail "libsoadyn.so is not a link to a SOVERSION'd file"

echo "== find_package(soadyn): consumer linked with soadyn::soadyn"
"$cmake" -S "$source/tests/install" -B "$scratch/cmake" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_CXX_COMPILER="$cxx" >"$scratch/cmake.log" || { cat "$scratch/cmake.log"; fail "consumer configure failed"; }
grep -qx "soadyn_DIR:PATH=$prefix/$libdir/cmake/soadyn" "$scratch/cmake/CMakeCache.txt" ||
  fail "find_package(soadyn) did not find the package in $prefix"
"$cmake" --build "$scratch/cmake" >"$scratch/build.log" || { cat "$scratch/build.log"; fail "consumer build failed"; }
"$scratch/cmake/consumer"

echo "== pkg-config soadyn: consumer linked with libsoadyn.so"
export PKG_CONFIG_PATH=$prefix/$libdir/pkgconfig
cflags=$(pkg-config --cflags soadyn) libs=$(pkg-config --libs soadyn)
echo "pkg-config --cflags --libs soadyn: $cflags $libs"
for d in EIGEN_MAX_ALIGN_BYTES=16 EIGEN_MALLOC_ALREADY_ALIGNED=0 EIGEN_RUNTIME_NO_MALLOC; do
  grep -q -- "-D$d\b" <<<"$cflags" || fail "pkg-config --cflags soadyn lacks -D$d"
done
grep -q -- "-march" <<<"$cflags" && fail "pkg-config --cflags soadyn passes on -march"
pkg-config --static --libs soadyn >/dev/null || fail "pkg-config --static --libs soadyn failed"
# shellcheck disable=SC2086  # the flags are words
"$cxx" -std=c++20 "$source/tests/install/consumer.cpp" $cflags $libs -o "$scratch/consumer_pc"
# ldd's whole output first: `ldd | grep -q` under pipefail fails whenever grep stops reading
# before ldd has written its last line (ldd then dies of SIGPIPE)
# no LD_LIBRARY_PATH: the .pc's -Wl,-rpath finds the library in the scratch prefix
loaded=$(env -u LD_LIBRARY_PATH ldd "$scratch/consumer_pc")
# (the path as the rpath spells it, prefix/lib/pkgconfig/../../lib: compared once resolved)
used=$(awk '/libsoadyn\.so/ && $2 == "=>" {print $3}' <<<"$loaded")
[[ -n $used && $(realpath "$used") == $(realpath "$prefix/$libdir/libsoadyn.so") ]] ||
  fail "the pkg-config consumer does not load the installed libsoadyn.so (ldd: ${used:-not found})"
env -u LD_LIBRARY_PATH "$scratch/consumer_pc"

echo "== README's C++ block, with pkg-config, on tests/data/arm7.urdf"
# shellcheck disable=SC2086
"$cxx" -std=c++20 "$scratch/readme_example.cpp" $cflags $libs -o "$scratch/readme_example"
env -u LD_LIBRARY_PATH "$scratch/readme_example" "$source/tests/data/arm7.urdf" | tee "$scratch/readme_example.out"
grep -q '^qdd = ' "$scratch/readme_example.out" || fail "README's C++ block printed no qdd"

echo "== README's second C++ block (simulate(scenario, options)), with pkg-config, on scenarios/three_link_arm.yaml"
# shellcheck disable=SC2086
"$cxx" -std=c++20 "$scratch/readme_run.cpp" $cflags $libs -o "$scratch/readme_run"
env -u LD_LIBRARY_PATH "$scratch/readme_run" "$source/scenarios/three_link_arm.yaml" "$scratch/readme_run.h5" |
  tee "$scratch/readme_run.out"
grep -q '^completed: [0-9]* samples' "$scratch/readme_run.out" || fail "README's simulate block did not complete"
[[ -s $scratch/readme_run.h5 ]] || fail "README's simulate block wrote no run file"

echo "== the installed soadyn executable"
env -u LD_LIBRARY_PATH "$prefix/$bindir/soadyn" --version | tee "$scratch/version.txt"
readelf -d "$prefix/$bindir/soadyn" | grep -q 'RUNPATH.*\$ORIGIN/\.\./lib' || fail "the installed soadyn has no RUNPATH \$ORIGIN/../lib"
grep -q '^soadyn [0-9]\+\.[0-9]\+\.[0-9]\+$' "$scratch/version.txt" || fail "soadyn --version"

if [[ $pydir == - ]]; then
  rm -rf "$scratch"
  echo "install_consume: every check passed (no Python module in this build: its checks left out)"
  exit 0
fi
echo "== the installed Python package"
[[ -e $site/soadyn/__init__.py ]] || fail "not installed: $pydir/soadyn/__init__.py"
ls "$site"/soadyn/_soadyn*.so >/dev/null || fail "not installed: the Python module's _soadyn*.so"
file=$(cd "$scratch" && env -u PYTHONPATH PYTHONPATH="$site" /usr/bin/python3 -c "import soadyn; print(soadyn.__file__)")
[[ $file == "$site/soadyn/__init__.py" ]] || fail "import soadyn gave $file, not the installed package"
# soadyn sweep puts the install's site-packages on PYTHONPATH itself
(cd "$scratch" && env -u PYTHONPATH PYTHONVERBOSE=1 "$prefix/$bindir/soadyn" sweep --help >"$scratch/sweep.out" 2>"$scratch/sweep.err") ||
  { tail "$scratch/sweep.err"; fail "installed soadyn sweep --help failed"; }
grep -q "usage" "$scratch/sweep.out" || fail "installed soadyn sweep --help printed no usage"
grep -q "$site/soadyn/__init__.py" "$scratch/sweep.err" || fail "installed soadyn sweep did not import $site/soadyn"

rm -rf "$scratch"
echo "install_consume: every check passed"
