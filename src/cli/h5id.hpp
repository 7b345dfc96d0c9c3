// A move-only owner of one HDF5 id, for the command line's readers of run files (view, export).
#pragma once

#include <hdf5.h>

namespace soadyn::cli::h5 {

// Closed with the function for its kind (H5Fclose, H5Dclose, …) when it goes out of scope; an id
// below zero (a failed call) is held but never closed: test it with ok().
class Id {
 public:
  Id(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Id(Id&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
  Id& operator=(Id&& o) noexcept {
    if (this != &o) {
      if (id_ >= 0) close_(id_);
      id_ = o.id_, close_ = o.close_;
      o.id_ = -1;
    }
    return *this;
  }
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  ~Id() {
    if (id_ >= 0) close_(id_);
  }
  operator hid_t() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

}  // namespace soadyn::cli::h5
