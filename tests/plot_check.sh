#!/bin/sh
# ctest tool_plot: for each "SCENARIO [run options]" JOINT pair, run the scene, plot it four ways
# (every row, --bins 20, --joints JOINT, as SVG) and check the curves and axes with
# tests/check_tools.py plot.  Needs SOADYN (the executable) in the environment.
#   plot_check.sh OUT_DIR "satellite_two_arrays --t-end 5" left ...
set -eu
here=$(dirname "$0")
root=$(cd "$here/.." && pwd)
out=$1
shift
mkdir -p "$out"
while [ $# -ge 2 ]; do
  scene=${1%% *}
  opts=${1#"$scene"}
  joint=$2
  shift 2
  o="$out/$scene"
  # shellcheck disable=SC2086
  "$SOADYN" run "$root/scenarios/$scene.yaml" $opts -q -o "$o.h5"
  /usr/bin/python3 "$root/tools/plot.py" "$o.h5" -o "$o.png" --data "$o.csv"
  /usr/bin/python3 "$root/tools/plot.py" "$o.h5" -o "$o.bins.png" --bins 20 --data "$o.bins.csv"
  /usr/bin/python3 "$root/tools/plot.py" "$o.h5" -o "$o.joint.pdf" --joints "$joint" --data "$o.joint.csv"
  /usr/bin/python3 "$root/tools/plot.py" "$o.h5" -o "$o.svg"
  head -c 8 "$o.png" | grep -q PNG && head -c 5 "$o.joint.pdf" | grep -q %PDF && grep -q "<svg" "$o.svg"
  /usr/bin/python3 "$here/check_tools.py" plot "$o.h5" "$o.csv" "$o.bins.csv" "$o.joint.csv" "$joint" "$o.svg"
done

# bad input: one line on stderr, exit status 2, nothing written
refuse() {
  status=0
  /usr/bin/python3 "$root/tools/plot.py" "$@" 2>"$out/err.txt" || status=$?
  if [ "$status" != 2 ] || [ "$(wc -l <"$out/err.txt")" != 1 ]; then
    echo "plot.py $*: exit status $status (expected 2 and one line): $(cat "$out/err.txt")" >&2
    exit 1
  fi
}
refuse "$o.h5" --joints "$joint,nope" -o "$out/no.png"
refuse "$out/absent.h5" -o "$out/no.png"
refuse "$o.h5" -o "$out/no.jpg"
test ! -e "$out/no.png" && test ! -e "$out/no.jpg"
echo "plot_check.sh: all checks passed"
