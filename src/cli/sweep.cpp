// soadyn sweep SWEEP.yaml …: the ensemble runner lives in the Python package (it drives Dask), so
// this subcommand replaces the process with `python3 -m soadyn sweep …`, the build tree's package
// first on PYTHONPATH when it exists (an installed soadyn is found in site-packages).
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

int exec_sweep(int argc, char** argv) {
#ifdef SOADYN_PYTHON_BUILD_DIR
  const std::string dir = SOADYN_PYTHON_BUILD_DIR;
  std::error_code ec;
  if (std::filesystem::exists(dir + "/soadyn/__init__.py", ec)) {
    const char* old = std::getenv("PYTHONPATH");
    const std::string path = old && *old ? dir + ":" + old : dir;
    ::setenv("PYTHONPATH", path.c_str(), 1);
  }
#endif
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
