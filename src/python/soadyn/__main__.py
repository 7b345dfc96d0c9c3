"""python3 -m soadyn sweep SWEEP.yaml …: what the `soadyn sweep` command runs."""
import sys

if len(sys.argv) >= 2 and sys.argv[1] == "sweep":
    from ._sweep import main
    sys.exit(main(sys.argv[2:]))
print("usage: python3 -m soadyn sweep SWEEP.yaml [options]  (python3 -m soadyn sweep --help)", file=sys.stderr)
sys.exit(2)
