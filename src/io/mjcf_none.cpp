// MJCF import in a build without MuJoCo: every MJCF file is refused with what to install.
#include "soadyn/io/mjcf.hpp"

namespace soadyn {

bool mjcf_available() { return false; }

MjcfModel parse_mjcf(const std::string&, const std::string& path, bool, const MjcfOptions&) {
  throw Error(path + ": an MJCF (MuJoCo) model: this soadyn was built without MuJoCo; install Debian's "
                     "libmujoco-dev and rebuild (tools/setup.sh does both)");
}

MjcfModel parse_mjcf_files(const std::vector<ModelFile>& files, const std::string& path, const MjcfOptions& o) {
  return parse_mjcf(files.empty() ? std::string() : files[0].data, path, false, o);
}

bool mjcf_names_files(const std::string&) { return false; }

}  // namespace soadyn
