"""PEP 517 build backend of soadyn: setuptools, with the compiled parts built by CMake.

pyproject.toml names this module (backend-path tools/pybuild).  It is setuptools' own backend
with one difference: `build_py` runs CMake on the source tree (targets soadyn_python, the module
soadyn._soadyn, and soadyn_cli, the `soadyn` executable) and puts what CMake made into the
package: build/python/soadyn/* as it is importable there, and the executable as soadyn/_bin/soadyn,
which the `soadyn` entry point and `python -m soadyn` run.  The wheel is tagged for this platform
and interpreter (it holds compiled code).

The CMake build directory is build-pip/ in the source tree (ignored by git), configured at each
install (SOADYN_CMAKE_ARGS adds configure arguments, shell words) and kept between installs; ccache
is used when it is on PATH.  SOADYN_CMAKE_BUILD_DIR names a build directory instead: one already
configured (tools/setup.sh's build/, say) is used as it is, only the two targets brought up to date.
"""
import os
import shlex
import shutil
import subprocess
import sys

from setuptools import build_meta as _orig
from setuptools import setup
from setuptools.command.build_py import build_py as _build_py
from setuptools.dist import Distribution

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


class BinaryDistribution(Distribution):
    """holds compiled code: the wheel is platlib, tagged cpXY-cpXY-<platform>"""

    def has_ext_modules(self):
        return True


class CMakeBuildPy(_build_py):
    """build_py that builds the package with CMake and copies it whole into build_lib"""

    def run(self):
        given = os.environ.get("SOADYN_CMAKE_BUILD_DIR")
        build = os.path.abspath(given) if given else os.path.join(SOURCE, "build-pip")
        args = ["cmake", "-S", SOURCE, "-B", build, "-DCMAKE_BUILD_TYPE=Release", "-DSOADYN_BUILD_TESTS=OFF",
                "-DSOADYN_BUILD_BENCH=OFF", "-DSOADYN_PYTHON=ON", f"-DPython_EXECUTABLE={sys.executable}"]
        if shutil.which("ccache"):
            args.append(f"-DCMAKE_CXX_COMPILER_LAUNCHER=env;CCACHE_BASEDIR={SOURCE};ccache")
        args += shlex.split(os.environ.get("SOADYN_CMAKE_ARGS", ""))
        jobs = str(os.cpu_count() or 1)
        steps = [["cmake", "--build", build, "-j", jobs, "--target", "soadyn_python", "soadyn_cli"]]
        if not (given and os.path.isfile(os.path.join(build, "CMakeCache.txt"))):
            steps.insert(0, args)
        for cmd in steps:
            print("soadyn build:", " ".join(cmd), flush=True)
            subprocess.run(cmd, check=True)
        # the package as CMake laid it out (module, pure-Python files, stub, py.typed), then the executable
        target = os.path.join(self.build_lib, "soadyn")
        if os.path.isdir(target):
            shutil.rmtree(target)
        shutil.copytree(os.path.join(build, "python", "soadyn"), target,
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        os.makedirs(os.path.join(target, "_bin"))
        exe = os.path.join(target, "_bin", "soadyn")
        shutil.copy2(os.path.join(build, "soadyn"), exe)
        os.chmod(exe, 0o755)

    def get_outputs(self, include_bytecode=1):
        root = os.path.join(self.build_lib, "soadyn")
        return [os.path.join(d, f) for d, _, fs in os.walk(root) for f in fs]


class _Backend(_orig._BuildMetaBackend):
    def run_setup(self, setup_script="setup.py"):
        # setuptools' scratch folders under build-pip/, not beside pyproject.toml
        scratch = os.path.join("build-pip", "setuptools")
        os.makedirs(scratch, exist_ok=True)
        setup(cmdclass={"build_py": CMakeBuildPy}, distclass=BinaryDistribution,
              options={"build": {"build_base": scratch}, "egg_info": {"egg_base": "build-pip"}})


_BACKEND = _Backend()
get_requires_for_build_wheel = _BACKEND.get_requires_for_build_wheel
get_requires_for_build_sdist = _BACKEND.get_requires_for_build_sdist
prepare_metadata_for_build_wheel = _BACKEND.prepare_metadata_for_build_wheel
build_wheel = _BACKEND.build_wheel
build_sdist = _BACKEND.build_sdist
