// MJCF import in a build without MuJoCo: every MJCF file is refused with what to install.
#include "soadyn/mjcf.hpp"

namespace soadyn {

bool mjcf_available() { return false; }

MjcfModel parse_mjcf(const std::string&, const std::string& path, bool, const MjcfOptions&) {
  throw Error(path + ": an MJCF (MuJoCo) model: this soadyn was built without MuJoCo; install Debian's "
                     "libmujoco-dev and rebuild (tools/setup.sh does both)");
}

}  // namespace soadyn
