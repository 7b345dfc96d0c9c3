// MJCF values MuJoCo takes without a word, checked by soadyn (mjcf.cpp): MuJoCo's own messages
// caught for the length of a load, the file's numbers scanned for NaN and infinities and for
// negative joint damping, stiffness, friction loss or armature (located: file, line, attribute),
// the compiled model checked again, and the values soadyn does not model named.  Internal: built
// only with MuJoCo.
#pragma once

#include <mujoco/mujoco.h>

#include <mutex>
#include <string>
#include <vector>

namespace soadyn::mjcf_detail {

// While alive, MuJoCo's warnings are kept here (never printed, never appended to the working
// folder's MUJOCO_LOG.TXT) and a MuJoCo error throws MujocoError; the previous handlers come back
// at destruction.  One at a time in the process (the handlers are global).
class MujocoMessages {
 public:
  MujocoMessages();
  ~MujocoMessages();
  MujocoMessages(const MujocoMessages&) = delete;
  MujocoMessages& operator=(const MujocoMessages&) = delete;
  // the warnings so far, each once
  std::vector<std::string> warnings() const;

 private:
  std::unique_lock<std::mutex> lock_;
  void (*saved_error_)(const char*);
  void (*saved_warning_)(const char*);
};

// thrown by a MuJoCo error while MujocoMessages is alive
struct MujocoError {
  std::string message;
};

// Refuses (soadyn::Error "file:line: element: attribute 'a': …") a number that is NaN or infinite
// in any numeric attribute, and a negative joint damping, stiffness, frictionloss or armature
// (<joint> or a <default>'s <joint>), in `xml` and, when from_disk, in the files it <include>s.
void check_file_values(const std::string& xml, const std::string& path, bool from_disk);

// Refuses what the compiled model still holds wrong (a value from a file the scan could not read):
// a non-finite value soadyn reads, a negative damping or stiffness, naming the body or joint.
void check_compiled_values(const mjModel* m, const std::string& path);

// The values of the file soadyn does not model, for the "ignored: …" line: joint frictionloss,
// ball- and free-joint damping and stiffness, <option wind density viscosity>.
std::vector<std::string> unmodelled_values(const mjModel* m);

}  // namespace soadyn::mjcf_detail
