// The files MuJoCo reads for an MJCF model, checked and pre-loaded (mjcf_vfs.hpp).  The include
// expansion and the asset names follow MuJoCo 2.2.2's mjIncludeXML (xml.cc), mjuu_makefullname
// and mjuu_strippath (user_util.cc) and its VFS's names (engine_vfs.c).
#include "mjcf_vfs.hpp"

#include "soadyn/io/input_file.hpp"
#include "soadyn/multibody/text.hpp"

#include <sys/stat.h>
#include <tinyxml2.h>

#include <cctype>
#include <cstring>
#include <functional>
#include <map>
#include <strings.h>
#include <vector>

namespace soadyn {

namespace {

namespace tx = tinyxml2;

// MuJoCo's VFS name: the file name without its folders, lower case
std::string vfs_key(const std::string& name) {
  std::string k = name.substr(name.find_last_of("/\\") == std::string::npos ? 0 : name.find_last_of("/\\") + 1);
  for (char& c : k) c = char(std::tolower(static_cast<unsigned char>(c)));
  return k;
}

bool is_absolute(const std::string& p) {
  return !p.empty() && (p[0] == '/' || p[0] == '\\' || p.find(":/") != std::string::npos || p.find(":\\") != std::string::npos);
}

// mjuu_makefullname: the file as it is when absolute, else under an absolute folder, else dir/folder/file
std::string full_name(const std::string& dir, const std::string& folder, const std::string& file) {
  if (is_absolute(file)) return file;
  if (is_absolute(folder)) return folder + file;
  return dir + folder + file;
}

std::string strip_folders(const std::string& file) {
  const size_t at = file.find_last_of("/\\");
  return at == std::string::npos ? file : file.substr(at + 1);
}

// a <compiler> folder as MuJoCo keeps it: with a trailing separator
std::string as_folder(std::string d) {
  if (!d.empty() && d.back() != '/' && d.back() != '\\') d += '/';
  return d;
}

// a file of the model, read once
struct File {
  std::string path, data;
  dev_t dev = 0;
  ino_t ino = 0;
};

// a file the model names that a run file does not hold (load_stored_mjcf_files)
struct NotStored {
  std::string name;
};

// the bytes a run stored for a resolved path (nullptr: none): the Collector reads those, never the disk
using StoredLookup = std::function<const std::string*(const std::string& path)>;

class Collector {
 public:
  explicit Collector(std::string dir, StoredLookup stored = nullptr) : dir_(std::move(dir)), stored_(std::move(stored)) {}

  // the model: its includes expanded as MuJoCo expands them, then its assets
  void model(tx::XMLDocument& doc, const std::string& main_name) {
    tx::XMLElement* root = doc.RootElement();
    if (!root || strcasecmp(root->Value(), "mujoco") != 0) return;
    included_.push_back(main_name);
    if (!expand(root)) return;  // MuJoCo stops at that <include> with its own message
    assets(root);
  }

  std::vector<File> files;

 private:
  // one file, checked as an input; nullptr: not one MuJoCo can use (it says why)
  const File& read(const std::string& path, std::string_view what, std::uint64_t limit) {
    for (const File& f : files)
      if (f.path == path) return f;
    if (stored_) {
      const std::string* data = stored_(path);
      if (!data) throw NotStored{path};
      files.push_back(File{path, *data});
      return files.back();
    }
    const InputFile in(path, what, limit);
    File f;
    f.path = path;
    f.data = in.read();
    if (f.data.empty()) throw Error(printable(path) + ": the file is empty, expected " + std::string(what));
    struct stat st {};
    if (::fstat(in.fd(), &st) == 0) f.dev = st.st_dev, f.ino = st.st_ino;
    files.push_back(std::move(f));
    return files.back();
  }

  // mjIncludeXML: an <include> replaced by the children of its file's root, which are then
  // searched in turn; false where MuJoCo's own expansion stops with an error
  bool expand(tx::XMLElement* root) {
    for (tx::XMLElement* e = root; e;) {
      if (strcasecmp(e->Value(), "include") == 0) {
        tx::XMLElement* next = include(e);
        if (!next) return false;
        e = next;  // the first element the include brought, searched next
        continue;
      }
      if (tx::XMLElement* child = e->FirstChildElement()) {
        e = child;
        continue;
      }
      // the next element in document order
      while (e && e != root && !e->NextSiblingElement()) e = e->Parent() ? e->Parent()->ToElement() : nullptr;
      e = e && e != root ? e->NextSiblingElement() : nullptr;
    }
    return true;
  }

  // the first element an <include> brought in its place, or nullptr where MuJoCo stops
  tx::XMLElement* include(tx::XMLElement* elem) {
    const char* file = elem->Attribute("file");
    if (!elem->NoChildren() || !file) return nullptr;
    const std::string name = dir_ + file;
    for (const std::string& seen : included_)
      if (strcasecmp(seen.c_str(), name.c_str()) == 0) return nullptr;  // MuJoCo: "already included"
    const File& f = read(name, "a file an MJCF <include> names", kMaxModelBytes);
    included_.push_back(name);
    tx::XMLDocument doc;
    if (doc.Parse(f.data.data(), f.data.size()) != tx::XML_SUCCESS || !doc.RootElement()) return nullptr;
    const tx::XMLElement* first = doc.RootElement()->FirstChildElement();
    tx::XMLNode* parent = elem->Parent();
    if (!first || !parent) return nullptr;
    tx::XMLNode* at = elem;
    tx::XMLElement* brought = nullptr;
    for (const tx::XMLElement* c = first; c; c = c->NextSiblingElement()) {
      at = parent->InsertAfterChild(at, c->DeepClone(parent->GetDocument()));
      if (!brought) brought = at->ToElement();
    }
    parent->DeleteChild(elem);
    return brought;
  }

  // <compiler meshdir texturedir strippath> (the last given of each), then the files of <asset>'s
  // meshes, skins, height fields (under meshdir) and textures (under texturedir)
  void assets(tx::XMLElement* root) {
    std::string meshdir, texturedir;
    bool strip = false;
    for (tx::XMLElement* c = root->FirstChildElement("compiler"); c; c = c->NextSiblingElement("compiler")) {
      if (const char* v = c->Attribute("meshdir")) meshdir = v;
      if (const char* v = c->Attribute("texturedir")) texturedir = v;
      if (const char* v = c->Attribute("strippath")) strip = std::strcmp(v, "true") == 0;
    }
    meshdir = as_folder(meshdir), texturedir = as_folder(texturedir);
    static const char* const cube[] = {"file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback"};
    for (tx::XMLElement* a = root->FirstChildElement("asset"); a; a = a->NextSiblingElement("asset"))
      for (tx::XMLElement* e = a->FirstChildElement(); e; e = e->NextSiblingElement()) {
        const std::string tag = e->Value();
        const bool texture = tag == "texture";
        if (!texture && tag != "mesh" && tag != "skin" && tag != "hfield") continue;
        for (const char* attr : cube) {
          const char* v = e->Attribute(attr);
          if (!v || !*v || (!texture && std::strcmp(attr, "file") != 0)) continue;
          const std::string file = strip ? strip_folders(v) : std::string(v);
          read(full_name(dir_, texture ? texturedir : meshdir, file), "an MJCF " + tag + " file", kMaxAssetBytes);
        }
      }
  }

  std::string dir_;
  StoredLookup stored_;
  std::vector<std::string> included_;
};

void add(mjVFS* vfs, const std::string& name, const std::string& data) {
  if (vfs->nfile >= mjMAXVFS - 1 || mj_makeEmptyFileVFS(vfs, name.c_str(), int(data.size())) != 0)
    throw Error(printable(name) + ": MJCF: more files than MuJoCo's virtual file system holds (" + std::to_string(mjMAXVFS - 1) + ")");
  std::memcpy(vfs->filedata[vfs->nfile - 1], data.data(), data.size());
}

}  // namespace

std::string mjcf_file_dir(const std::string& path) {
  const size_t at = path.find_last_of("/\\");
  return at == std::string::npos ? std::string() : path.substr(0, at + 1);
}

std::vector<ModelFile> load_mjcf_files(mjVFS* vfs, const std::string& main_name, const std::string& xml,
                                       const std::string& dir) {
  if (xml.empty()) throw Error(printable(main_name) + ": MJCF: the model text is empty");
  add(vfs, main_name, xml);
  std::vector<ModelFile> handed{{main_name, xml}};
  tx::XMLDocument doc;
  if (doc.Parse(xml.data(), xml.size()) != tx::XML_SUCCESS) return handed;  // MuJoCo says where
  Collector c(dir);
  c.model(doc, main_name);
  // into the VFS under its name without folders, unless another file (not the same one by
  // another path) has that name: MuJoCo would hand it over for both
  std::map<std::string, std::vector<const File*>> by_key;
  for (const File& f : c.files) by_key[vfs_key(f.path)].push_back(&f);
  for (const auto& [key, same] : by_key) {
    bool one = key != vfs_key(main_name);
    for (const File* f : same) one = one && f->dev == same[0]->dev && f->ino == same[0]->ino;
    if (one && !key.empty() && key.size() < mjMAXVFSNAME) {
      add(vfs, same[0]->path, same[0]->data);
      handed.push_back({same[0]->path, same[0]->data});
    }
  }
  return handed;
}

std::string load_stored_mjcf_files(mjVFS* vfs, const std::vector<ModelFile>& files, const std::string& path) {
  if (files.empty() || files[0].data.empty()) throw Error(path + ": MJCF: the run file holds no model text");
  std::map<std::string, const ModelFile*> by_key;
  for (const ModelFile& f : files) {
    const std::string key = vfs_key(f.name);
    if (key.empty() || key.size() >= mjMAXVFSNAME || !by_key.emplace(key, &f).second)
      throw Error(path + ": MJCF: " + printable(f.name) +
                  ": a stored model file's name MuJoCo's virtual file system cannot hold, or holds twice");
  }
  tx::XMLDocument doc;
  if (doc.Parse(files[0].data.data(), files[0].data.size()) == tx::XML_SUCCESS) {
    // every file MuJoCo would look for, as load_mjcf_files resolved it at run time: stored, or refused
    Collector c(mjcf_file_dir(files[0].name), [&](const std::string& p) -> const std::string* {
      const auto it = by_key.find(vfs_key(p));
      return it == by_key.end() ? nullptr : &it->second->data;
    });
    try {
      c.model(doc, files[0].name);
    } catch (const NotStored& n) {
      throw Error(path + ": MJCF: " + printable(n.name) +
                  ": not among the model's files the run file holds; soadyn view reads nothing but the run file");
    }
  }
  for (const ModelFile& f : files) add(vfs, f.name, f.data);
  return files[0].name;
}

bool mjcf_text_names_files(const std::string& xml) {
  tx::XMLDocument doc;
  if (doc.Parse(xml.data(), xml.size()) != tx::XML_SUCCESS) return false;
  Collector c("", [](const std::string&) -> const std::string* { return nullptr; });
  try {
    c.model(doc, mjcf_main_name(""));
  } catch (const NotStored&) {
    return true;
  }
  return false;
}

}  // namespace soadyn
