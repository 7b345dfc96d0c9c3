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

#include "soadyn/multibody/types.hpp"

#include <string>
#include <vector>

namespace soadyn {

// Fills `vfs` (empty) with `xml` under `main_name` (a name no file of the model has) and the files
// it names, resolved against `dir` (the folder MuJoCo takes from the name given to mj_loadXML:
// everything up to its last '/', or "" for the working folder).  Throws soadyn::Error naming the
// file for one that cannot be read or is not a regular file.  A model that does not parse is left
// for MuJoCo to refuse with its own message.
// Returns every file put into `vfs`, as put there (the name given, the bytes; `xml` first): what a run
// stores (h5log.hpp /model_files).
std::vector<ModelFile> load_mjcf_files(mjVFS* vfs, const std::string& main_name, const std::string& xml,
                                       const std::string& dir);

// Fills `vfs` (empty) with files a run stored (load_mjcf_files' list: the main text first, under its
// name) and nothing else; returns the main file's name for mj_loadXML.  Every file the main text
// names (its <include>s followed, its assets, resolved as load_mjcf_files resolves them against the
// main name's folder) must be among them, found by MuJoCo's VFS name, so that MuJoCo never opens a
// file on disk: one that is not throws soadyn::Error "`path`: MJCF: NAME: not among the model's
// files the run file holds; soadyn view reads nothing but the run file".
std::string load_stored_mjcf_files(mjVFS* vfs, const std::vector<ModelFile>& files, const std::string& path);

// Whether `xml` names files of its own MuJoCo reads (<include>s, mesh, skin, height-field or
// texture files), none of them read.
bool mjcf_text_names_files(const std::string& xml);

// The folder MuJoCo 2.2 resolves a model's files against: `path` up to and with its last '/' or '\'
std::string mjcf_file_dir(const std::string& path);

// The name given to mj_loadXML for a model whose files resolve against `dir`: one no user file has
inline std::string mjcf_main_name(const std::string& dir) { return dir + "soadyn-model.in-memory.xml"; }

}  // namespace soadyn
