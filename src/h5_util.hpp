// HDF5 helpers for the run file (h5log.cpp): move-only owners of HDF5 ids, every return code
// checked, the cause of a failure (the errno the file driver recorded) kept for the message, and
// the attribute and dataset writers the layout uses.  Internal to the library.
#pragma once

#include "soadyn/types.hpp"

#include <hdf5.h>

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

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

Id group(hid_t parent, const char* name);

// a fixed-length string type of `size` bytes, UTF-8 when the text is valid UTF-8
Id string_type(size_t size, bool utf8);

// Attributes, written once before SWMR writing starts.  Strings are variable-length UTF-8 (h5py
// reads them as str), ASCII-tagged if the text is not valid UTF-8.
void attribute(hid_t obj, const char* name, double value);
void attribute(hid_t obj, const char* name, long value);
void attribute(hid_t obj, const char* name, const std::string& value);
void attribute(hid_t obj, const char* name, const std::vector<std::string>& values);  // 1-D, one per entry
void attribute(hid_t obj, const char* name, const std::vector<double>& values);

// a 1-D dataset of ints, and of variable-length UTF-8 strings (h5py: .asstr()[...] gives str)
void int_dataset(hid_t parent, const char* name, const std::vector<int>& values, const std::string& units);
void string_dataset(hid_t parent, const char* name, const std::vector<std::string>& values);

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

}  // namespace soadyn::h5
