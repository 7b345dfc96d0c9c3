// Opening a file a user names as an input: the one way every reader opens one (a scenario, a URDF,
// an MJCF model with its <include>s and assets, a CSV table, a run file read back).  Only a
// regular file is read: a FIFO, device, directory or socket is refused with its kind, never waited
// on (a FIFO with no writer would block for ever, /dev/zero would fill the memory), and each kind
// of input has a size limit.  Every refusal is one line "PATH: reason" (an Error).
#pragma once

#include "soadyn/multibody/types.hpp"

#include <cstdint>
#include <string>
#include <string_view>

namespace soadyn {

// Size limits by kind.  A model or scenario (YAML, URDF, MJCF and its includes) and a CSV table:
// real ones are well under a megabyte, a table of 10⁶ samples a few tens of megabytes.  An MJCF
// asset (mesh, texture, height field, skin): MuJoCo keeps it whole in memory.  A run file has no
// limit (its size is the run's, bounded by --max-output-size when it was written; its readers
// read it dataset by dataset).
inline constexpr std::uint64_t kMaxModelBytes = std::uint64_t(64) << 20;
inline constexpr std::uint64_t kMaxTableBytes = std::uint64_t(64) << 20;
inline constexpr std::uint64_t kMaxAssetBytes = std::uint64_t(256) << 20;
inline constexpr std::uint64_t kNoSizeLimit = 0;

// An input file, open for reading: checked to be a regular file of at most `max_bytes` (0: any
// size).  `what` names what was expected, for the messages ("a table (CSV or run file)").  The
// file is looked at with stat before it is opened (a device is never opened), opened without
// blocking, then checked again on the open descriptor (a file swapped for a FIFO in between is
// refused too).  Reasons: "cannot open the file (No such file or directory)" (or Permission
// denied, …), "is a directory, expected …", "not a regular file (a FIFO), expected …",
// "N bytes, more than the L MiB … may have".
class InputFile {
 public:
  InputFile(const std::string& path, std::string_view what, std::uint64_t max_bytes);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  const std::string& path() const { return path_; }
  int fd() const { return fd_; }
  std::uint64_t size() const { return size_; }
  // the whole file as it was when opened (a file that grows is cut at its size then, one that
  // shrinks ends early)
  std::string read() const;
  // a name that opens this very file (/proc/self/fd/N where /proc is mounted, else the path):
  // for a library that opens files by name (HDF5), so it opens what was checked
  std::string name_for_library() const;
  // refuses the file when it is larger than max_bytes (a limit that depends on what it turns out to be)
  void check_size(std::uint64_t max_bytes, std::string_view what) const;

 private:
  std::string path_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
};

// "a FIFO", "a directory", "a character device", … for a stat mode that is not a regular file
std::string file_kind(unsigned mode);

}  // namespace soadyn
