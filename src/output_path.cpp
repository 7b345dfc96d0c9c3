// The output path's checks and its lock (h5log.hpp).
#include "soadyn/h5log.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace soadyn {

namespace fs = std::filesystem;

void check_output_path(const std::string& path, const std::vector<std::string>& inputs) {
  std::error_code ec;
  const fs::path p(path);
  if (path.empty()) throw Error("the output path is empty");
  if (fs::is_directory(p, ec)) throw Error(path + ": is a directory, expected an output file");
  if (!fs::exists(p, ec)) return;
  for (const auto& in : inputs)
    if (!in.empty() && fs::equivalent(p, fs::path(in), ec))
      throw Error(path + ": the output is the input file " + in + "; choose another -o");
  // an existing file is replaced only if it is an HDF5 file (its signature at 0, 512, 1024, …)
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path + ": exists and cannot be read, so it cannot be checked before it is replaced");
  static const char sig[8] = {'\x89', 'H', 'D', 'F', '\r', '\n', '\x1a', '\n'};
  const auto size = fs::file_size(p, ec);
  if (!ec && size == 0) return;
  for (std::uint64_t off = 0; !ec && off + 8 <= size; off = off ? 2 * off : 512) {
    char b[8];
    f.seekg(std::streamoff(off));
    if (f.read(b, 8) && std::memcmp(b, sig, 8) == 0) return;
    if (off >= (std::uint64_t(1) << 40)) break;
  }
  throw Error(path + ": exists and is not an HDF5 file; refusing to replace it (remove it or choose another -o)");
}

OutputLock::OutputLock(const std::string& path) : lock_path_(path + ".lock") {
  const fs::path p(path);
  std::error_code ec;
  if (p.has_parent_path()) fs::create_directories(p.parent_path(), ec);
  for (int attempt = 0; attempt < 100; ++attempt) {
    fd_ = ::open(lock_path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0)
      throw Error(path + ": cannot create the lock file " + lock_path_ + " (" + std::strerror(errno) +
                  "; is the directory writable?)");
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      char buf[32] = {};
      const ssize_t n = ::pread(fd_, buf, sizeof buf - 1, 0);
      const long pid = n > 0 ? std::atol(buf) : 0;
      ::close(fd_);
      fd_ = -1;
      throw Error(path + ": in use by another soadyn run" + (pid > 0 ? " (pid " + std::to_string(pid) + ")" : std::string()) +
                  "; wait for it to end or choose another -o");
    }
    // the owner before us may have removed the file after we opened it: lock the file on the path
    struct stat held {}, named {};
    if (::fstat(fd_, &held) == 0 && ::stat(lock_path_.c_str(), &named) == 0 && held.st_ino == named.st_ino &&
        held.st_dev == named.st_dev) {
      const std::string pid = std::to_string(getpid()) + "\n";
      if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, pid.data(), pid.size(), 0) != ssize_t(pid.size())) {
      }  // the pid is only for messages
      // "<path>.<pid>.tmp" files are runs' files under construction; with the lock held, any left
      // are from runs that were killed before their first flush
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

}  // namespace soadyn
