// soadyn view: the mesh files of a model's visuals, found, read and checked when the page is
// written, each embedded in the page once however many visuals use it.  A URDF's meshes are read
// from the disk (a run file does not hold them): package://, file://, absolute or relative to the
// URDF, STL (binary or ASCII), OBJ and Collada, as the input files are (input_file.hpp: regular
// files only, never a FIFO or a device), at most kMaxMeshBytes each and kMaxMeshBytesTotal in all.
// An MJCF model's meshes come as MuJoCo compiled them from the files the run stored.  A mesh that
// cannot be drawn keeps the reason, for the page's note; its bodies keep their default shape.
#include "view.hpp"

#include "soadyn/io/input_file.hpp"
#include "soadyn/multibody/text.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <system_error>

namespace soadyn::cli::view {

namespace fs = std::filesystem;

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// "%20" and the like decoded, as a URL's path is (an invalid escape is kept as written)
std::string percent_decoded(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(static_cast<unsigned char>(s[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(s[i + 2]))) {
      out += char(std::stoi(s.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += s[i];
    }
  }
  return out;
}

// the folders of a search path variable (ROS_PACKAGE_PATH, AMENT_PREFIX_PATH), in order
std::vector<fs::path> env_folders(const char* name) {
  std::vector<fs::path> out;
  const char* v = std::getenv(name);
  if (!v) return out;
  std::string s = v;
  for (size_t at = 0; at <= s.size();) {
    const size_t colon = std::min(s.find(':', at), s.size());
    if (colon > at) out.emplace_back(s.substr(at, colon - at));
    at = colon + 1;
  }
  return out;
}

bool is_there(const fs::path& p) {
  std::error_code ec;
  return fs::exists(p, ec);
}

// the file package://pkg/rel names, looked for as ROS users expect: the folder called pkg among
// the URDF's folder and its parents, or a folder pkg in one of them; then in ROS_PACKAGE_PATH
// (ROS 1) and AMENT_PREFIX_PATH's share/ (ROS 2).  Throws with where it looked.
fs::path find_package_file(const std::string& url, const fs::path& urdf_dir) {
  const std::string rest = url.substr(std::strlen("package://"));
  const size_t slash = rest.find('/');
  if (slash == std::string::npos || slash == 0 || slash + 1 == rest.size())
    throw Error("a package:// URL without a package and a path in it");
  const std::string pkg = rest.substr(0, slash);
  const fs::path rel = fs::path(percent_decoded(rest.substr(slash + 1))).relative_path();
  for (fs::path d = urdf_dir;; d = d.parent_path()) {
    if (d.filename() == pkg && is_there(d / rel)) return (d / rel).lexically_normal();
    if (is_there(d / pkg / rel)) return (d / pkg / rel).lexically_normal();
    if (d == d.parent_path() || d.empty()) break;
  }
  for (const fs::path& e : env_folders("ROS_PACKAGE_PATH")) {
    if (e.filename() == pkg && is_there(e / rel)) return e / rel;
    if (is_there(e / pkg / rel)) return e / pkg / rel;
  }
  for (const fs::path& e : env_folders("AMENT_PREFIX_PATH"))
    if (is_there(e / "share" / pkg / rel)) return e / "share" / pkg / rel;
  throw Error("not found: no package folder '" + printable(pkg) + "' holding " + printable(rel.string()) +
              " at or in the URDF's folder " + printable(urdf_dir.string()) +
              " or its parents, nor in ROS_PACKAGE_PATH or AMENT_PREFIX_PATH");
}

// the path a URDF <mesh filename> names: package://, file://, absolute, or relative to the URDF
fs::path mesh_path(const std::string& filename, const fs::path& urdf_dir) {
  if (filename.rfind("package://", 0) == 0) return find_package_file(filename, urdf_dir);
  fs::path p;
  if (filename.rfind("file://", 0) == 0) {
    p = percent_decoded(filename.substr(std::strlen("file://")));
  } else if (filename.find("://") != std::string::npos) {
    throw Error("a URL the viewer does not read (package:// and file:// it does)");
  } else {
    p = filename;
  }
  return (p.is_absolute() ? p : urdf_dir / p).lexically_normal();
}

std::uint32_t le32(const char* p) {
  std::uint32_t v = 0;
  std::memcpy(&v, p, 4);  // the machines soadyn builds on are little-endian, as STL is
  return v;
}

// why `bytes` is not a mesh of `format` the page's loaders can read ("" if it looks like one):
// a binary STL is 84 + 50 bytes per triangle with finite numbers; an ASCII STL, an OBJ and a
// Collada file are text with their keywords.  (The loaders in the page check the rest.)
std::string format_problem(const std::string& format, const std::string& bytes) {
  const bool text = bytes.find('\0') == std::string::npos;
  if (format == "stl") {
    if (bytes.size() >= 84 && 84 + 50 * std::uint64_t(le32(bytes.data() + 80)) == bytes.size()) {
      const std::uint32_t n = le32(bytes.data() + 80);
      if (n == 0) return "a binary STL file with no triangles";
      for (std::uint32_t t = 0; t < n; ++t)
        for (int k = 0; k < 12; ++k) {
          float x;
          std::memcpy(&x, bytes.data() + 84 + 50 * size_t(t) + 4 * size_t(k), 4);
          if (!std::isfinite(x)) return "triangle " + std::to_string(t) + " of the binary STL file has a non-finite number";
        }
      return "";
    }
    const size_t start = bytes.find_first_not_of(" \t\r\n");
    if (text && start != std::string::npos && bytes.compare(start, 5, "solid") == 0 &&
        bytes.find("facet") != std::string::npos && bytes.find("vertex") != std::string::npos)
      return "";
    return "not an STL file (neither binary, 84 + 50 bytes per triangle, nor ASCII: solid, facet, vertex)";
  }
  if (format == "obj") {
    auto has_line = [&](const char* key) {
      for (size_t at = bytes.find(key); at != std::string::npos; at = bytes.find(key, at + 1))
        if (at == 0 || bytes[at - 1] == '\n') return true;
      return false;
    };
    if (text && has_line("v ") && has_line("f ")) return "";
    return "not an OBJ file (no 'v' and 'f' lines of text)";
  }
  if (text && bytes.find("<COLLADA") != std::string::npos) return "";
  return "not a Collada file (no <COLLADA> element in a text file)";
}

}  // namespace

UrdfMeshes::UrdfMeshes(const std::string& urdf_path, std::vector<MeshFile>& files) : files_(files) {
  std::error_code ec;
  const fs::path dir = fs::path(urdf_path).parent_path();
  dir_ = fs::absolute(dir.empty() ? fs::path(".") : dir, ec).lexically_normal();
  if (ec) dir_ = dir;
  if (dir_.filename().empty() && dir_ != dir_.root_path()) dir_ = dir_.parent_path();  // "/a/b/" as "/a/b"
}

int UrdfMeshes::add(const std::string& filename) {
  MeshFile f;
  f.name = filename;
  std::string key = "urdf:" + filename;
  try {
    // one file (links resolved) read as one format (the name's extension) is one entry
    const fs::path path = mesh_path(filename, dir_);
    const std::string ext = lower(path.extension().string());
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(path, ec);
    key = (ec ? path : canonical).string() + " as " + ext;
    for (size_t k = 0; k < files_.size(); ++k)
      if (files_[k].key == key) return int(k);
    f.key = key;
    if (ext == ".stl" || ext == ".obj" || ext == ".dae") {
      f.format = ext.substr(1);
    } else {
      throw Error(printable(path.string()) + ": " +
                  (ext.empty() ? std::string("a file without an extension") : "a " + printable(ext) + " file") +
                  "; the viewer draws STL, OBJ and Collada (.dae) meshes");
    }
    const InputFile in(path.string(), "a mesh file (STL, OBJ or Collada)", kMaxMeshBytes);
    if (total_ + in.size() > kMaxMeshBytesTotal)
      throw Error(printable(path.string()) + ": " + std::to_string(in.size()) + " bytes, past the " +
                  std::to_string(kMaxMeshBytesTotal >> 20) + " MiB of mesh files one page may hold");
    f.bytes = in.read();
    if (const std::string why = format_problem(f.format, f.bytes); !why.empty()) {
      f.bytes.clear();
      throw Error(printable(path.string()) + ": " + why);
    }
    total_ += f.bytes.size();
  } catch (const Error& e) {
    for (size_t k = 0; k < files_.size(); ++k)
      if (files_[k].key == key) return int(k);
    f.key = key;
    f.bytes.clear();
    f.error = e.what();
  }
  files_.push_back(std::move(f));
  return int(files_.size()) - 1;
}

MeshFile compiled_mesh(const MjcfMesh& mesh) {
  MeshFile f;
  f.name = mesh.name;
  f.key = "mjcf:" + mesh.name;
  f.format = "arrays";
  f.vertices = mesh.vertices.size() / 3;
  f.triangles = mesh.faces.size() / 3;
  if (f.vertices == 0 || f.triangles == 0) {
    f.error = "MuJoCo compiled the mesh to no triangles";
    return f;
  }
  for (const int v : mesh.faces)
    if (v < 0 || size_t(v) >= f.vertices) {
      f.error = "a triangle of the compiled mesh names a vertex it does not have";
      return f;
    }
  f.bytes.resize(mesh.vertices.size() * sizeof(float) + mesh.faces.size() * sizeof(std::uint32_t));
  std::memcpy(f.bytes.data(), mesh.vertices.data(), mesh.vertices.size() * sizeof(float));
  std::memcpy(f.bytes.data() + mesh.vertices.size() * sizeof(float), mesh.faces.data(), mesh.faces.size() * sizeof(std::uint32_t));
  return f;
}

}  // namespace soadyn::cli::view
