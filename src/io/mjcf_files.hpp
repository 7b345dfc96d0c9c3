// The files an MJCF model names: its <include>s (followed into the included files) and the files
// of its assets (<mesh file>, <texture file>, <hfield file>, <skin file>, <model file>, …), so that
// no command writes its output onto a file the model was read from.  Internal to soadyn.
#pragma once

#include <string>
#include <vector>

namespace soadyn {

// The paths `xml` (the MJCF file at `path`) names, resolved as MuJoCo resolves them: an <include>
// against the main file's folder, an asset against that folder joined with <compiler meshdir,
// texturedir, assetdir>, with and without the name's own folders (strippath) — each candidate
// listed: more names protected, never fewer.  Included files are read (regular files only, as
// read_text_file reads them) and searched in turn; a file that cannot be read or parsed is listed
// and not searched (MuJoCo's compiler says why it failed).
std::vector<std::string> mjcf_files(const std::string& xml, const std::string& path);

}  // namespace soadyn
