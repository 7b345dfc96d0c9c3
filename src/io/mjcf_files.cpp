// The files an MJCF model names (mjcf_files.hpp): a tinyxml2 walk over the model and its includes.
#include "mjcf_files.hpp"

#include "soadyn/io/scenario_file.hpp"

#include <tinyxml2.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <set>

namespace soadyn {

namespace {

namespace fs = std::filesystem;

struct Walk {
  fs::path base;                               // the main file's folder: includes and asset dirs are under it
  std::vector<std::string> dirs{""};           // <compiler meshdir texturedir assetdir>, and the folder itself
  std::vector<std::pair<std::string, std::string>> assets;  // (element, file) seen anywhere
  std::vector<std::string> files;
  std::set<std::string> searched;

  void add(const std::string& p) {
    if (std::find(files.begin(), files.end(), p) == files.end()) files.push_back(p);
  }

  void element(const tinyxml2::XMLElement* e, int depth) {
    for (; e; e = e->NextSiblingElement()) {
      const std::string tag = e->Name() ? e->Name() : "";
      if (tag == "compiler")
        for (const char* d : {"meshdir", "texturedir", "assetdir"})
          if (const char* v = e->Attribute(d)) dirs.emplace_back(v);
      for (const tinyxml2::XMLAttribute* a = e->FirstAttribute(); a; a = a->Next()) {
        // file=, and a cube texture's fileright=, fileleft=, …
        if (std::strncmp(a->Name(), "file", 4) != 0 || !*a->Value()) continue;
        if (tag == "include") include(a->Value(), depth);
        else assets.emplace_back(tag, a->Value());
      }
      element(e->FirstChildElement(), depth);
    }
  }

  void include(const std::string& file, int depth) {
    const fs::path p = fs::path(file).is_absolute() ? fs::path(file) : base / file;
    add(p.string());
    if (depth > 32 || !searched.insert(p.lexically_normal().string()).second) return;  // a loop: MuJoCo refuses it
    std::string text;
    try {
      text = read_text_file(p.string());
    } catch (const Error&) {
      return;
    }
    document(text, depth + 1);
  }

  void document(const std::string& text, int depth) {
    tinyxml2::XMLDocument doc;
    if (doc.Parse(text.data(), text.size()) != tinyxml2::XML_SUCCESS) return;
    element(doc.FirstChildElement(), depth);
  }
};

}  // namespace

std::vector<std::string> mjcf_files(const std::string& xml, const std::string& path) {
  Walk w;
  w.base = fs::path(path).parent_path();
  w.searched.insert(fs::path(path).lexically_normal().string());
  w.document(xml, 0);
  for (const auto& [tag, file] : w.assets) {
    if (fs::path(file).is_absolute()) {
      w.add(file);
      continue;
    }
    // and the name without its folders, as <compiler strippath="true"> has MuJoCo read it
    for (const std::string& d : w.dirs)
      for (const fs::path& f : {fs::path(file), fs::path(file).filename()}) w.add((w.base / d / f).lexically_normal().string());
  }
  return w.files;
}

}  // namespace soadyn
