"""`python -m soadyn COMMAND …` and the `soadyn` entry point pip installs: the soadyn command line.

`sweep` runs here (it is Python: soadyn._sweep); every other command and `--version`/`--help` run
the compiled `soadyn` executable that belongs to this package, with the same arguments, exit
status and signals (the process is replaced by it).  The executable is looked for where each way
of installing puts it: soadyn/_bin/soadyn (pip, the wheel), build/soadyn beside build/python
(a CMake build tree), <prefix>/bin/soadyn beside <prefix>/lib/pythonX.Y/*-packages (`cmake
--install`); SOADYN_EXECUTABLE overrides them.
"""
import os
import sys


def executable():
    """the path of the soadyn executable of this package, or None"""
    here = os.path.dirname(os.path.abspath(__file__))
    candidates = [os.environ.get("SOADYN_EXECUTABLE", ""),
                  os.path.join(here, "_bin", "soadyn"),
                  os.path.join(here, os.pardir, os.pardir, "soadyn"),
                  os.path.join(here, os.pardir, os.pardir, os.pardir, os.pardir, "bin", "soadyn")]
    for c in candidates:
        if c and os.path.isfile(c) and os.access(c, os.X_OK):
            return os.path.normpath(c)
    return None


def main(argv=None):
    """run the soadyn command line with argv (default: sys.argv[1:]); returns sweep's exit status,
    otherwise does not return (the executable replaces this process)"""
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["sweep"]:
        from ._sweep import main as sweep
        return sweep(argv[1:])
    exe = executable()
    if exe is None:
        print("soadyn: the soadyn executable of this package is missing (looked in soadyn/_bin, the build tree "
              "and <prefix>/bin; set SOADYN_EXECUTABLE): reinstall with `pip install .`", file=sys.stderr)
        return 2
    sys.stdout.flush()
    sys.stderr.flush()
    os.execv(exe, ["soadyn"] + argv)
    return 0  # not reached


if __name__ == "__main__":
    sys.exit(main())
