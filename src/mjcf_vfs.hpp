// The files MuJoCo reads for an MJCF model, checked and handed to it in memory.  Internal to soadyn.
//
// MuJoCo's compiler opens a model's <include>s and assets (<mesh file>, <skin file>, <hfield file>,
// <texture file fileright …>) itself, and would wait for ever on a FIFO or read /dev/zero without
// end.  Each such file is found as MuJoCo 2.2 finds it (an include: the main file's folder joined
// with the name; an asset: that folder, <compiler meshdir> or <compiler texturedir>, the name
// stripped of its folders under strippath="true", an absolute name or folder taken as it is),
// opened as every input is (input_file.hpp: a regular file, an include at most kMaxModelBytes, an
// asset at most kMaxAssetBytes, not empty), and put into MuJoCo's virtual file system, where
// MuJoCo looks before the disk.  MuJoCo 2.2's VFS tells files apart by their name without folders
// (case-blind): two different files of one such name are both checked but left out of it, and
// MuJoCo reads those two from the disk itself.
#pragma once

#include <mujoco/mujoco.h>

#include <string>

namespace soadyn {

// Fills `vfs` (empty) with `xml` under `main_name` (a name no file of the model has) and the files
// it names, resolved against `dir` (the folder MuJoCo takes from the name given to mj_loadXML:
// everything up to its last '/', or "" for the working folder).  Throws soadyn::Error naming the
// file for one that cannot be read or is not a regular file.  A model that does not parse is left
// for MuJoCo to refuse with its own message.
void load_mjcf_files(mjVFS* vfs, const std::string& main_name, const std::string& xml, const std::string& dir);

// The folder MuJoCo 2.2 resolves a model's files against: `path` up to and with its last '/' or '\'
std::string mjcf_file_dir(const std::string& path);

// The name given to mj_loadXML for a model whose files resolve against `dir`: one no user file has
inline std::string mjcf_main_name(const std::string& dir) { return dir + "soadyn-model.in-memory.xml"; }

}  // namespace soadyn
