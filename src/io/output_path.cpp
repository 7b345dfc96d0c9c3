// Output paths: the checks before a file is replaced, the writer's lock, and text written whole
// (output_file.hpp).
#include "soadyn/io/output_file.hpp"

#include "soadyn/io/h5log.hpp"

#include "h5_util.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

namespace soadyn {

namespace fs = std::filesystem;

const char* to_string(OutputKind kind) {
  switch (kind) {
    case OutputKind::Run: return "run file";
    case OutputKind::Page: return "page";
    case OutputKind::Csv: return "CSV export";
    case OutputKind::Json: return "JSON export";
    case OutputKind::Scenario: return "fitted scenario";
  }
  return "output";
}

std::string temporary_path(const std::string& path) { return path + "." + std::to_string(getpid()) + ".tmp"; }

namespace {

// A read-only descriptor, closed on scope exit.
struct Fd {
  int fd;
  explicit Fd(int f) : fd(f) {}
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
};

// the first `n` bytes of an open file
std::string head(int fd, size_t n) {
  std::string s(n, '\0');
  const ssize_t got = ::pread(fd, s.data(), n, 0);
  s.resize(got > 0 ? size_t(got) : 0);
  return s;
}

// Why "<path>.lock" (described by `st`, from lstat or fstat) cannot be soadyn's lock file, or "":
// soadyn writes its pid there and truncates it, so only a regular file of ours, with one name,
// holding at most a pid, is taken; never a symlink's target, a FIFO, a device, a directory, a hard
// link to another file, or another user's file.
std::string lock_file_problem(const std::string& lock_path, const struct stat& st, int fd) {
  const std::string remove = ": remove it (soadyn keeps its lock there as a file of its own)";
  if (S_ISLNK(st.st_mode)) return lock_path + ": a symbolic link where soadyn keeps its lock, not followed" + remove;
  if (S_ISDIR(st.st_mode)) return lock_path + ": a directory where soadyn keeps its lock" + remove;
  if (!S_ISREG(st.st_mode)) return lock_path + ": not a regular file (a FIFO, device or socket) where soadyn keeps its lock" + remove;
  if (st.st_nlink != 1)
    return lock_path + ": has " + std::to_string(st.st_nlink) + " names (a hard link to another file), so it is not soadyn's lock" + remove;
  if (st.st_uid != ::geteuid()) return lock_path + ": belongs to another user, so it is not this user's soadyn lock" + remove;
  if (fd >= 0) {  // a lock file holds a pid and a newline, or nothing yet
    char buf[40] = {};
    const ssize_t n = st.st_size > 32 ? -1 : ::pread(fd, buf, sizeof buf - 1, 0);
    const std::string text = n >= 0 ? std::string(buf, size_t(n)) : std::string("x");
    if (text.find_first_not_of("0123456789\n") != std::string::npos)
      return lock_path + ": holds something other than a soadyn writer's pid, so it is not soadyn's lock" + remove;
  }
  return "";
}

// the pid in "<path>.lock", or 0
long lock_owner(const std::string& lock_path) {
  Fd f(::open(lock_path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOFOLLOW));
  if (f.fd < 0) return 0;
  const std::string s = head(f.fd, 31);
  return std::atol(s.c_str());
}

// A soadyn writer holds "<path>.lock"?  (Its flock; the file alone may be a killed run's leftover.)
bool held_by_soadyn(const std::string& path, long& pid) {
  const std::string lock = path + ".lock";
  Fd f(::open(lock.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOFOLLOW));
  if (f.fd < 0) return false;
  if (::flock(f.fd, LOCK_SH | LOCK_NB) == 0 || errno != EWOULDBLOCK) return false;
  pid = lock_owner(lock);
  return true;
}

// HDF5's signature at 0, 512, 1024, … (a user block may precede it)
bool is_hdf5(int fd, std::uint64_t size) {
  static const char sig[8] = {'\x89', 'H', 'D', 'F', '\r', '\n', '\x1a', '\n'};
  for (std::uint64_t off = 0; off + 8 <= size; off = off ? 2 * off : 512) {
    char b[8];
    if (::pread(fd, b, 8, off_t(off)) == 8 && std::memcmp(b, sig, 8) == 0) return true;
    if (off >= (std::uint64_t(1) << 40)) break;
  }
  return false;
}

// A soadyn run file: the root attributes every soadyn log has.  Opened read-only with one metadata
// read attempt, so a corrupt file answers at once.
bool is_soadyn_run(const std::string& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t p = H5Pcreate(H5P_FILE_ACCESS);
  if (p < 0) return false;
  const h5::Id fapl(p, H5Pclose, "H5Pcreate");
  H5Pset_metadata_read_attempts(fapl, 1);
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl);
  if (f < 0) f = H5Fopen(path.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, fapl);  // a killed run's file
  if (f < 0) return false;
  const h5::Id file(f, H5Fclose, path);
  return h5::has_attribute(file, "soadyn_version") && h5::has_attribute(file, "layout_version");
}

// Is the file's content what this writer makes?
bool made_by_this_writer(const std::string& path, int fd, std::uint64_t size, OutputKind kind) {
  switch (kind) {
    case OutputKind::Run: return is_hdf5(fd, size) && is_soadyn_run(path);
    case OutputKind::Page: {
      const std::string h = head(fd, 4096);
      return h.rfind("<!DOCTYPE html>", 0) == 0 && h.find("<meta name=\"generator\" content=\"soadyn view") != std::string::npos;
    }
    case OutputKind::Csv: {
      const std::string h = head(fd, 4096);
      return h.rfind("time [s]", 0) == 0 && h.find('\0') == std::string::npos;
    }
    case OutputKind::Json: return head(fd, 9) == "{\"file\": ";
    case OutputKind::Scenario: return head(fd, 4096).rfind(kFittedScenarioHeader, 0) == 0;
  }
  return false;
}

}  // namespace

OutputTarget check_output_path(const std::string& path, OutputKind kind, const std::vector<std::string>& inputs,
                               bool force) {
  const bool text = kind != OutputKind::Run;
  if (path.empty()) throw Error("the output path is empty");
  if (path == "-") {
    if (!text) throw Error("-: a run file cannot go to stdout (HDF5 needs a file); give a file name");
    return OutputTarget::Stdout;
  }
  // the lock file a writer would take: refused now, before anything is touched, if it is not one
  const std::string lock_path = path + ".lock";
  struct stat lst {};
  if (::lstat(lock_path.c_str(), &lst) == 0) {
    Fd lf(S_ISREG(lst.st_mode) ? ::open(lock_path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOFOLLOW) : -1);
    if (const std::string why = lock_file_problem(lock_path, lst, lf.fd); !why.empty()) throw Error(why);
  }
  long pid = 0;
  if (held_by_soadyn(path, pid))
    throw Error(path + ": in use by another soadyn run" + (pid > 0 ? " (pid " + std::to_string(pid) + ")" : std::string()) +
                "; wait for it to end or choose another output");
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return OutputTarget::New;  // nothing there (or a dangling link: replaced by the file)
    throw Error(path + ": cannot be checked (" + std::strerror(errno) + ")");
  }
  std::error_code ec;
  for (const auto& in : inputs)
    if (!in.empty() && fs::equivalent(fs::path(path), fs::path(in), ec))
      throw Error(path + ": the output is the input file " + in + " (the same file, under any name); choose another output");
  if (S_ISDIR(st.st_mode)) throw Error(path + ": is a directory, expected an output file");
  if (!S_ISREG(st.st_mode)) {
    if (!text) throw Error(path + ": not a regular file (a device or FIFO); a run file must be a regular file");
    if (S_ISFIFO(st.st_mode) || S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) return OutputTarget::InPlace;
    throw Error(path + ": not a regular file, a device or a FIFO; choose another output");
  }
  // another program writing it (HDF5 and most writers take an exclusive flock)
  Fd f(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK));
  if (f.fd < 0)
    throw Error(path + ": exists and cannot be read (" + std::strerror(errno) + "), so it cannot be checked before it is replaced");
  if (::flock(f.fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK)
    throw Error(path + ": open for writing by another program; close it there or choose another output");
  if (st.st_size == 0 || force) return OutputTarget::Replace;
  if (made_by_this_writer(path, f.fd, std::uint64_t(st.st_size), kind)) return OutputTarget::Replace;
  const bool hdf5 = is_hdf5(f.fd, std::uint64_t(st.st_size));
  throw Error(path + ": exists and is " + (hdf5 && text ? "an HDF5 file (a run?), " : hdf5 ? "an HDF5 file but " : "") +
              "not a soadyn " + to_string(kind) +
              "; refusing to replace it (remove it, choose another output, or give --force)");
}

OutputLock::OutputLock(const std::string& path) : lock_path_(path + ".lock") {
  const fs::path p(path);
  std::error_code ec;
  if (p.has_parent_path()) fs::create_directories(p.parent_path(), ec);
  for (int attempt = 0; attempt < 100; ++attempt) {
    // O_NOFOLLOW: never a symlink's target; O_NONBLOCK: never waiting on a FIFO; then only a
    // regular file of ours with one name (lock_file_problem) is written
    fd_ = ::open(lock_path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NONBLOCK | O_NOFOLLOW, 0644);
    if (fd_ < 0) {
      const int err = errno;
      struct stat lst {};
      if (::lstat(lock_path_.c_str(), &lst) == 0)
        if (const std::string why = lock_file_problem(lock_path_, lst, -1); !why.empty()) throw Error(why);
      throw Error(path + ": cannot create the lock file " + lock_path_ + " (" + std::strerror(err) +
                  "; is the directory writable?)");
    }
    if (struct stat st {}; ::fstat(fd_, &st) != 0 || !lock_file_problem(lock_path_, st, fd_).empty()) {
      const std::string why = lock_file_problem(lock_path_, st, fd_);
      ::close(fd_);
      fd_ = -1;
      throw Error(why.empty() ? lock_path_ + ": cannot be checked (" + std::strerror(errno) + ")" : why);
    }
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      char buf[32] = {};
      const ssize_t n = ::pread(fd_, buf, sizeof buf - 1, 0);
      const long pid = n > 0 ? std::atol(buf) : 0;
      ::close(fd_);
      fd_ = -1;
      throw Error(path + ": in use by another soadyn run" + (pid > 0 ? " (pid " + std::to_string(pid) + ")" : std::string()) +
                  "; wait for it to end or choose another output");
    }
    // the owner before us may have removed the file after we opened it: lock the file on the path
    struct stat held {}, named {};
    if (::fstat(fd_, &held) == 0 && ::stat(lock_path_.c_str(), &named) == 0 && held.st_ino == named.st_ino &&
        held.st_dev == named.st_dev) {
      const std::string pid = std::to_string(getpid()) + "\n";
      if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, pid.data(), pid.size(), 0) != ssize_t(pid.size())) {
      }  // the pid is only for messages
      // "<path>.<pid>.tmp" files are outputs under construction; with the lock held, any left are
      // from writers that were killed before they renamed theirs
      const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
      const std::string prefix = p.filename().string() + ".";
      for (const auto& e : fs::directory_iterator(dir, ec)) {
        const std::string n = e.path().filename().string();
        if (n.size() > prefix.size() + 4 && n.rfind(prefix, 0) == 0 && n.ends_with(".tmp") &&
            n.find_first_not_of("0123456789", prefix.size()) == n.size() - 4)
          fs::remove(e.path(), ec);
      }
      return;
    }
    ::close(fd_);
    fd_ = -1;
  }
  throw Error(path + ": could not lock " + lock_path_);
}

OutputLock::~OutputLock() {
  if (fd_ < 0) return;
  ::unlink(lock_path_.c_str());  // while still holding the lock, see the constructor
  ::close(fd_);
}

TextOutput::TextOutput(std::string path, OutputTarget target) : path_(std::move(path)) {
  switch (target) {
    case OutputTarget::Stdout:
      stdout_ = true;
      fd_ = 1;
      return;
    case OutputTarget::InPlace:
      // a FIFO without a reader fails at once (ENXIO) instead of blocking
      fd_ = ::open(path_.c_str(), O_WRONLY | O_CLOEXEC | O_NONBLOCK);
      if (fd_ < 0)
        throw Error(path_ + ": cannot open it for writing (" +
                    std::string(errno == ENXIO ? "a FIFO with no reader" : std::strerror(errno)) + ")");
      ::fcntl(fd_, F_SETFL, ::fcntl(fd_, F_GETFL) & ~O_NONBLOCK);
      return;
    case OutputTarget::New:
    case OutputTarget::Replace:
      tmp_ = temporary_path(path_);
      fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
      if (fd_ < 0)
        throw Error(path_ + ": cannot create " + tmp_ + " (" + std::strerror(errno) + "; is the directory writable?)");
      return;
  }
}

TextOutput::~TextOutput() {
  if (!tmp_.empty()) {
    if (fd_ >= 0) ::close(fd_);
    ::unlink(tmp_.c_str());
  } else if (fd_ > 2) {
    ::close(fd_);
  }
}

void TextOutput::fail(int err, const char* doing) {
  const std::string where = stdout_ ? std::string("stdout") : path_;
  std::string kept;
  if (!tmp_.empty()) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    ::unlink(tmp_.c_str());
    tmp_.clear();
    kept = " (nothing written; an existing file there is unchanged)";
  }
  throw IoError(std::string(std::strerror(err)) + " while " + doing + " " + where + kept);
}

void TextOutput::write(const std::string& text) {
  const char* p = text.data();
  size_t left = text.size();
  while (left > 0) {
    const ssize_t n = ::write(fd_, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(n < 0 ? errno : EIO, "writing");
    p += n, left -= size_t(n);
  }
}

void TextOutput::commit() {
  if (tmp_.empty()) return;  // stdout, a device or a FIFO: written as it went
  if (::fsync(fd_) != 0) fail(errno, "writing");
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail(errno, "writing");
  if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp_.c_str());
    tmp_.clear();
    throw IoError(std::string(std::strerror(err)) + " while renaming the new file onto " + path_ +
                  " (an existing file there is unchanged)");
  }
  tmp_.clear();
}

}  // namespace soadyn
