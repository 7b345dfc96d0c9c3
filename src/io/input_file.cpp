// Opening a user's input file (input_file.hpp): stat, open without blocking, fstat, size limit.
#include "soadyn/io/input_file.hpp"

#include "soadyn/multibody/text.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>

namespace soadyn {

std::string file_kind(unsigned mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISLNK(mode)) return "a symbolic link";
  return "not a regular file";
}

namespace {

// strerror's text as a message part: "no such file or directory"
std::string reason(int err) {
  std::string r = std::strerror(err);
  if (!r.empty()) r[0] = char(std::tolower(static_cast<unsigned char>(r[0])));
  return r;
}

std::string limit_text(std::uint64_t bytes) {
  return bytes % (std::uint64_t(1) << 20) == 0 ? std::to_string(bytes >> 20) + " MiB" : std::to_string(bytes) + " bytes";
}

// one line for a stat mode that is not a regular file
[[noreturn]] void refuse_kind(const std::string& shown, unsigned mode, std::string_view what) {
  if (S_ISDIR(mode)) throw Error(shown + ": is a directory, expected " + std::string(what));
  throw Error(shown + ": not a regular file (" + file_kind(mode) + "), expected " + std::string(what));
}

}  // namespace

InputFile::InputFile(const std::string& path, std::string_view what, std::uint64_t max_bytes) : path_(path) {
  const std::string shown = printable(path);
  if (path.empty()) throw Error("an empty file name, expected " + std::string(what));
  if (path.find('\0') != std::string::npos) throw Error(shown + ": the name holds a NUL character");
  // what the name points to (links followed) before anything is opened: a device is never opened
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int err = errno;
    throw Error(shown + ": cannot open the file (" + reason(err) + ")");
  }
  if (!S_ISREG(st.st_mode)) refuse_kind(shown, st.st_mode, what);
  // opened without blocking (a FIFO swapped in since would not block), and checked on the descriptor
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd_ < 0) {
    const int err = errno;
    throw Error(shown + ": cannot open the file (" + reason(err) + ")");
  }
  try {
    if (::fstat(fd_, &st) != 0) {
      const int err = errno;
      throw Error(shown + ": cannot be read (" + reason(err) + ")");
    }
    if (!S_ISREG(st.st_mode)) refuse_kind(shown, st.st_mode, what);
    // back to blocking reads: a regular file never blocks, and the flag must not reach a library
    const int flags = ::fcntl(fd_, F_GETFL);
    if (flags >= 0) ::fcntl(fd_, F_SETFL, flags & ~O_NONBLOCK);
    size_ = std::uint64_t(st.st_size);
    check_size(max_bytes, what);
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

InputFile::~InputFile() {
  if (fd_ >= 0) ::close(fd_);
}

void InputFile::check_size(std::uint64_t max_bytes, std::string_view what) const {
  if (max_bytes != kNoSizeLimit && size_ > max_bytes)
    throw Error(printable(path_) + ": " + limit_text(size_) + ", more than the " + limit_text(max_bytes) + " allowed for " +
                std::string(what));
}

std::string InputFile::read() const {
  std::string text(size_t(size_), '\0');
  size_t got = 0;
  while (got < text.size()) {
    const ssize_t n = ::pread(fd_, text.data() + got, text.size() - got, off_t(got));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      throw Error(printable(path_) + ": read error (" + reason(err) + ")");
    }
    if (n == 0) break;
    got += size_t(n);
  }
  text.resize(got);
  return text;
}

std::string InputFile::name_for_library() const {
  const std::string self = "/proc/self/fd/" + std::to_string(fd_);
  struct stat a {}, b {};
  // the same file through /proc (a missing /proc, or a sandbox that hides it: the path)
  if (::stat(self.c_str(), &a) == 0 && ::fstat(fd_, &b) == 0 && a.st_dev == b.st_dev && a.st_ino == b.st_ino) return self;
  return path_;
}

}  // namespace soadyn
