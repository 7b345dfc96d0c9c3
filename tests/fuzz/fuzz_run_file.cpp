// libFuzzer target: bytes → a run file on disk → the library's reader (run_file.hpp), as `soadyn
// export`, `view`, `identify --data`, a table target and Python's read_log read it: the whole file
// (read_run_file), then /samples row by row (RunReader, as export reads it).  Seeded with real run
// files (tests/fuzz/seeds/*.h5: finished, and a killed run's SWMR file).  A crash, leak or hang,
// or an exception other than soadyn::Error, is a finding; so is a file read whole whose series do
// not all have its rows.
#include "soadyn/io/run_file.hpp"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // HDF5 reads files only: one per process, rewritten for each input
  static const std::string path = "/tmp/soadyn_fuzz_run_file." + std::to_string(::getpid()) + ".h5";
  if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
    const bool ok = std::fwrite(data, 1, size, f) == size;
    std::fclose(f);
    if (!ok) return 0;
  } else {
    return 0;
  }
  try {
    const soadyn::RunContents c = soadyn::read_run_file(path);
    for (const soadyn::RunSeries& s : c.series)
      if (s.values.rows() != c.rows()) std::abort();  // every series has the file's rows
  } catch (const soadyn::Error&) {
  }
  try {
    const soadyn::RunReader r(path);
    std::vector<double> row(r.column_names().size());
    for (std::uint64_t k = 0; k < r.rows() && k < 64; ++k) r.read_rows(k, 1, row.data());
  } catch (const soadyn::Error&) {
  }
  return 0;
}
