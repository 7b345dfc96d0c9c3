// soadyn sweep SWEEP.yaml …: the ensemble runner lives in the Python package (it drives Dask), so
// this subcommand replaces the process with `python3 -m soadyn sweep …`, the package beside this
// executable first on PYTHONPATH: build/python beside build/soadyn in the build tree, the install's
// site-packages beside <prefix>/bin/soadyn once installed (paths from CMakeLists.txt, relative to
// the executable, so a moved install finds its own), or the site-packages holding soadyn/_bin/soadyn
// (pip's install); without any, python3's own site-packages.
#include "cli.hpp"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <unistd.h>
#include <vector>

namespace soadyn::cli {

void add_sweep(CLI::App& app) {
  // listed in --help only: main() hands `soadyn sweep …` to exec_sweep before parsing
  app.add_subcommand("sweep",
                     "Run a sweep file's cases (initial conditions × parameters × methods) on Dask, "
                     "resumably, into DIR/results.h5 (soadyn sweep --help; needs the Python module)")
      ->allow_extras();
}

namespace {

void put_package_on_path() {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return;
  for (const char* relative : {SOADYN_PYTHON_BUILD_FROM_EXE, SOADYN_PYTHON_SITE_FROM_EXE, "../.."}) {
    const std::string dir = (exe.parent_path() / relative).lexically_normal().string();
    if (fs::exists(dir + "/soadyn/__init__.py", ec)) {
      const char* old = std::getenv("PYTHONPATH");
      const std::string path = old && *old ? dir + ":" + old : dir;
      ::setenv("PYTHONPATH", path.c_str(), 1);
      return;
    }
  }
}

}  // namespace

int exec_sweep(int argc, char** argv) {
  put_package_on_path();
  const char* python = SOADYN_PYTHON_EXECUTABLE;
  std::vector<char*> args{const_cast<char*>(python), const_cast<char*>("-m"), const_cast<char*>("soadyn"),
                          const_cast<char*>("sweep")};
  for (int k = 2; k < argc; ++k) args.push_back(argv[k]);
  args.push_back(nullptr);
  ::execv(python, args.data());
  std::cerr << "soadyn: error: sweep: cannot run " << python << ": " << std::strerror(errno) << "\n";
  return 2;
}

}  // namespace soadyn::cli
