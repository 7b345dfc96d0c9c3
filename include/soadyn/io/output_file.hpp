// Files the command line writes (run logs, pages, exports): what an output path may replace, the
// lock a writer holds, and a text file written whole or not at all.
//
// The rules, for every writer:
//  - an input of the command (the same file under any name: symlink, hard link) is never an output;
//  - a path a soadyn writer holds (its "<path>.lock") is refused, naming the owner's pid, and so is
//    a file another program holds open for writing (its flock, which HDF5 takes);
//  - an existing regular file is replaced only when it is what this writer makes (a soadyn run
//    file, page or export, told by its contents) or with force; an empty file always;
//  - a device, FIFO or "-" (stdout) is written in place, never renamed over; a run file must be a
//    regular file;
//  - a regular file is built under "<path>.<pid>.tmp" and renamed onto the path when whole, so at
//    every instant the path holds the old file or the new one.
#pragma once

#include "soadyn/multibody/types.hpp"

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace soadyn {

// What a writer makes, and so what it may replace without force.
enum class OutputKind {
  Run,   // an HDF5 run file (soadyn run): root attributes soadyn_version and layout_version
  Page,  // a soadyn view page: <meta name="generator" content="soadyn view"> in its head
  Csv,   // a soadyn export: a header line starting "time [s]"
  Json,  // a soadyn export: starting {"file":
  Scenario,  // a fitted scenario (soadyn identify): starting with kFittedScenarioHeader
};
// the first line of every scenario soadyn identify writes (what tells it may replace the file)
inline constexpr const char* kFittedScenarioHeader = "# fitted by soadyn identify";
const char* to_string(OutputKind kind);

// How an output path is written, once checked.
enum class OutputTarget {
  New,      // nothing there: built under a temporary name, renamed into place
  Replace,  // a regular file this writer may replace: the same
  InPlace,  // a device or a FIFO with a reader: opened and written as it is
  Stdout,   // "-"
};

// Refuses an output path before any file is touched (the rules above).  `inputs` are the
// command's input files (empty strings are skipped).  Throws soadyn::Error naming the path and
// what to do instead.
OutputTarget check_output_path(const std::string& path, OutputKind kind, const std::vector<std::string>& inputs,
                               bool force = false);

// An exclusive lock on an output path, held for a writer's lifetime (flock on "<path>.lock", which
// holds the owner's pid).  Throws soadyn::Error naming the path and the owner when another writer
// holds it.  Once held, removes the temporary files ("<path>.<pid>.tmp") of writers killed before
// they renamed them.  Released (and the lock file removed) on destruction; the kernel releases it
// if the process dies.
class OutputLock {
 public:
  explicit OutputLock(const std::string& path);
  ~OutputLock();
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;
  const std::string& lock_path() const { return lock_path_; }

 private:
  std::string lock_path_;
  int fd_ = -1;
};

// "<path>.<pid>.tmp": the name a regular output is built under
std::string temporary_path(const std::string& path);

// One text output (a page or an export) written whole or not at all: a regular file under its
// temporary name, renamed at commit(); a device or FIFO in place; "-" to stdout.  Destroyed
// before commit(), it removes its temporary file.  Write failures throw IoError (h5log.hpp)
// naming the cause and the path.
class TextOutput {
 public:
  TextOutput(std::string path, OutputTarget target);
  ~TextOutput();
  TextOutput(const TextOutput&) = delete;
  TextOutput& operator=(const TextOutput&) = delete;

  void write(const std::string& text);
  void commit();  // flush, fsync, close, rename
  const std::string& path() const { return path_; }
  // the temporary file while one is being written (for a signal handler to remove), else ""
  const std::string& temporary() const { return tmp_; }

 private:
  [[noreturn]] void fail(int err, const char* doing);
  std::string path_, tmp_;
  int fd_ = -1;
  bool stdout_ = false;
};

}  // namespace soadyn
