// HDF5 helpers for the run file, its writer (h5log.cpp) and its reader (run_file.cpp): the one
// move-only owner of HDF5 ids, every return code checked, the cause of a failure (the errno the
// file driver recorded) kept for the message, the attribute and dataset writers the layout uses and
// the readers that take them back.  Internal to the library.
#pragma once

#include "soadyn/multibody/types.hpp"

#include <hdf5.h>

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace soadyn::h5 {

// the cause of the last failed HDF5 call: the errno its file driver recorded (0: none) and its text
extern int last_errno;
extern std::string last_cause;

// Records why the HDF5 call that just failed did so; must run before any other HDF5 call, which
// would clear the library's error stack.
void record_cause();

struct Failure : Error {
  Failure(const std::string& what, std::string cause) : Error(what), cause(std::move(cause)) {}
  std::string cause;
};

[[noreturn]] void fail(const std::string& what);
inline void check(herr_t status, const std::string& what) {
  if (status < 0) fail(what);
}

// A move-only owner of one HDF5 id, closed with the function for its kind.  release() gives the id
// up without closing it: after a failed write the library must not touch the file again.
class Id {
 public:
  Id() = default;
  Id(hid_t id, herr_t (*close)(hid_t), const std::string& what) : id_(id), close_(close) {
    if (id < 0) fail(what);
  }
  Id(Id&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
  Id& operator=(Id&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = o.id_;
      close_ = o.close_;
      o.id_ = -1;
    }
    return *this;
  }
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  ~Id() { reset(); }
  void reset() {
    if (id_ >= 0 && close_) close_(id_);
    id_ = -1;
  }
  void release() { id_ = -1; }
  operator hid_t() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

Id group(hid_t parent, const char* name);

// a fixed-length string type of `size` bytes, UTF-8 when the text is valid UTF-8
Id string_type(size_t size, bool utf8);

// Attributes, written once before SWMR writing starts.  Strings are fixed-length (the longest
// string's bytes, null-padded), UTF-8, ASCII-tagged if the text is not valid UTF-8: nothing in the
// global heap, which HDF5 reads without checks (one changed byte there crashes the reader), so all
// a reader follows is in checksummed metadata.  h5py reads them as bytes (.decode()).
void attribute(hid_t obj, const char* name, double value);
void attribute(hid_t obj, const char* name, long value);
void attribute(hid_t obj, const char* name, const std::string& value);
void attribute(hid_t obj, const char* name, const std::vector<std::string>& values);  // 1-D, one per entry
void attribute(hid_t obj, const char* name, const std::vector<double>& values);

// a scalar dataset of one fixed-length string of any size (a file's text), UTF-8 when it is valid UTF-8
Id text_dataset(hid_t parent, const char* name, const std::string& text);
// a 1-D dataset of ints, and of fixed-length UTF-8 strings (h5py: .asstr()[...] gives str)
void int_dataset(hid_t parent, const char* name, const std::vector<int>& values, const std::string& units);
void string_dataset(hid_t parent, const char* name, const std::vector<std::string>& values);
// a 1-D dataset of unsigned bytes (a file's bytes, as they are)
Id byte_dataset(hid_t parent, const char* name, const std::string& bytes);
// its bytes back: a 1-D dataset of 1-byte integers of at most `max_bytes`, else soadyn::Error
std::string bytes(hid_t obj, const char* name, std::uint64_t max_bytes, const std::string& where);

// A scalar dataset whose storage is allocated at creation: later writes overwrite its bytes in
// place and change no metadata, which SWMR allows at any time.
struct Scalar {
  Id dset, type;
  size_t size = 0;  // strings: fixed length in bytes
  Scalar() = default;
  Scalar(hid_t parent, const char* name, hid_t mem_type, Id file_type = Id());
  void write(double x);
  void write(long x);
  void write(std::string s);  // cut at a character boundary to the fixed length, "..." marking the cut
  void release() { dset.release(), type.release(); }
  void reset() { dset.reset(), type.reset(); }
};

Scalar string_scalar(hid_t parent, const char* name, size_t size);

// Opens a run file read-only: plainly when it was closed (one attempt per metadata read: no writer
// to wait for), in single-writer/multiple-reader mode when a run is writing it or was killed.  There
// HDF5 retries a metadata read that fails its checksum, sleeping longer each time (100 attempts by
// default: a corrupt file would hang the reader for ever); kMetadataReadAttempts bounds that.
// Throws soadyn::Error naming the path.
inline constexpr unsigned kMetadataReadAttempts = 20;
Id open_run_file(const std::string& path);

// Reading back.  `where` names the object in messages ("run.h5: /model"); each throws
// soadyn::Error "<where>: <name>: <what is wrong>" for a missing or malformed object.
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
bool exists(hid_t file, const std::string& path);  // every link of an absolute path
bool has_attribute(hid_t obj, const char* name);
// the strings of an attribute or a dataset (fixed-length, or variable-length when `variable`:
// otherwise those are refused before HDF5 follows them into the global heap; scalar or 1-D)
std::vector<std::string> strings(hid_t obj, const char* name, bool attribute, const std::string& where, bool variable);
std::string one_string(hid_t obj, const char* name, bool attribute, const std::string& where, bool variable);  // exactly one
// the numbers of an attribute or a dataset, as a row-major matrix: its first dimension the rows,
// the others the columns (a scalar or 1-D object: one column); `shape` gets its dimensions
RowMatrix numbers(hid_t obj, const char* name, bool attribute, const std::string& where,
                  std::vector<hsize_t>* shape = nullptr);
// the dimensions of a dataset (its data not read)
std::vector<hsize_t> dims(hid_t obj, const char* name, const std::string& where);
// rows [first, first + count) of a 2-D dataset of doubles, row-major into `out`
void read_rows(hid_t dset, hsize_t first, hsize_t count, hsize_t width, double* out, const std::string& where);

}  // namespace soadyn::h5
