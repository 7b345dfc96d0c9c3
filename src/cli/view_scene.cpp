// soadyn view: what each body looks like.  From the model: a skeleton (capsules from the joint to
// the children's joints), the centre of mass, and the uniform box with the body's mass and
// principal moments.  From a URDF: its <visual> boxes, cylinders, spheres and meshes, moved into
// the frame of the body they were welded into; from an MJCF file, its geoms where MuJoCo's
// compiler put them.  Mesh files are found and read by view_meshes.cpp.
#include "view.hpp"

#include "soadyn/io/mjcf.hpp"
#include "soadyn/sim/scenario.hpp"

#include <Eigen/Eigenvalues>
#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace soadyn::cli::view {

namespace {

// the uniform box of mass m with the principal moments of I: I_x = m (b² + c²)/12 etc., so
// a² = 6 (I_y + I_z − I_x)/m, and likewise (clamped at zero against round-off)
Shape inertia_box(double mass, const Vec3& com, const Mat3& I) {
  Shape s;
  s.kind = "box";
  s.p = com;
  if (!(mass > 0)) return s;
  Eigen::SelfAdjointEigenSolver<Mat3> eig(0.5 * (I + I.transpose()));
  const Vec3 l = eig.eigenvalues();
  Mat3 V = eig.eigenvectors();
  if (V.determinant() < 0) V.col(2) = -V.col(2);
  for (int k = 0; k < 3; ++k) {
    const double sq = 6.0 * (l.sum() - 2.0 * l(k)) / mass;
    s.size(k) = std::sqrt(std::max(0.0, sq));
  }
  s.R = Eigen::Quaterniond(V).normalized();
  return s;
}

// urdfdom's console messages are dropped: the model was already read from this URDF
class QuietConsole : public console_bridge::OutputHandler {
 public:
  QuietConsole() { console_bridge::useOutputHandler(this); }
  ~QuietConsole() override { console_bridge::restorePreviousOutputHandler(); }
  QuietConsole(const QuietConsole&) = delete;
  QuietConsole& operator=(const QuietConsole&) = delete;
  void log(const std::string&, console_bridge::LogLevel, const char*, int) override {}
};

std::string hex_color(const urdf::Color& c) {
  char buf[8];
  auto byte = [](float x) { return int(std::lround(std::clamp(double(x), 0.0, 1.0) * 255)); };
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", byte(c.r), byte(c.g), byte(c.b));
  return buf;
}

// the URDF's visuals, each in the frame of the model body its link was welded into (-1: world)
void add_urdf_visuals(const Model& model, const std::string& urdf_text, const std::string& urdf_path, Look& look) {
  urdf::ModelInterfaceSharedPtr robot;
  {
    QuietConsole quiet;
    robot = urdf::parseURDF(urdf_text);
  }
  if (!robot) throw Error(urdf_path + ": URDF: cannot be read for its visuals");
  UrdfMeshes meshes(urdf_path, look.meshes);
  for (const auto& [name, link] : robot->links_) {
    if (link->visual_array.empty()) continue;
    // climb fixed joints up to the moving body the link belongs to: X = frame of link in that body
    Placement X;
    int body = model.body_index(name);
    for (urdf::LinkConstSharedPtr at = link; body < 0;) {
      const urdf::JointConstSharedPtr j = at->parent_joint;
      if (!j) break;  // the root, welded to the world
      if (j->type != urdf::Joint::FIXED) {
        X = Placement{};  // a moving link missing from the model: not drawn
        body = -2;
        break;
      }
      X = compose(placement_of_pose(j->parent_to_joint_origin_transform), X);
      at = robot->getLink(j->parent_link_name);
      if (!at) break;
      body = model.body_index(at->name);
    }
    if (body == -2) continue;
    for (const auto& v : link->visual_array) {
      if (!v || !v->geometry) continue;
      const Placement Xv = compose(X, placement_of_pose(v->origin));
      Shape s;
      s.p = Xv.p;
      s.R = Eigen::Quaterniond(Xv.R).normalized();
      // a material's colour (a texture alone leaves urdfdom's black: the body's colour then)
      if (v->material && (v->material->texture_filename.empty() || v->material->color.r > 0 || v->material->color.g > 0 ||
                          v->material->color.b > 0))
        s.color = hex_color(v->material->color);
      switch (v->geometry->type) {
        case urdf::Geometry::BOX: {
          const auto& b = static_cast<const urdf::Box&>(*v->geometry);
          s.kind = "box";
          s.size = Vec3(b.dim.x, b.dim.y, b.dim.z);
          break;
        }
        case urdf::Geometry::CYLINDER: {
          const auto& c = static_cast<const urdf::Cylinder&>(*v->geometry);
          s.kind = "cylinder";
          s.size = Vec3(c.radius, c.length, 0);
          break;
        }
        case urdf::Geometry::SPHERE: {
          s.kind = "sphere";
          s.size = Vec3(static_cast<const urdf::Sphere&>(*v->geometry).radius, 0, 0);
          break;
        }
        case urdf::Geometry::MESH: {
          const auto& mesh = static_cast<const urdf::Mesh&>(*v->geometry);
          s.kind = "mesh";
          s.size = Vec3(mesh.scale.x, mesh.scale.y, mesh.scale.z);
          s.mesh = meshes.add(mesh.filename);
          (body >= 0 ? look.bodies[body].meshes : look.world_meshes) += 1;
          break;
        }
        default:
          continue;
      }
      (body >= 0 ? look.bodies[body].visuals : look.world_visuals).push_back(s);
    }
  }
}

// an MJCF file's geoms (MuJoCo's compiler placed them): boxes, spheres, cylinders, meshes (as
// compiled: MuJoCo 2.2 moves a mesh to its centre of mass and principal axes and keeps no record
// of the move, only the geoms placed to match); a capsule as its cylinder, an ellipsoid as its
// box; planes and height fields (the floor) are not drawn (compiled from the run's stored files
// alone, never from the disk)
void add_mjcf_visuals(const std::vector<ModelFile>& files, const std::string& path, Look& look) {
  MjcfOptions o;
  o.inertia_check = InertiaCheck::Balance;
  const MjcfModel compiled = parse_mjcf_files(files, path, o);
  std::vector<int> page_mesh(compiled.meshes.size(), -1);  // each MJCF mesh's index in look.meshes
  for (const MjcfGeom& g : compiled.geoms) {
    Shape s;
    s.p = g.X.p;
    s.R = Eigen::Quaterniond(g.X.R).normalized();
    char color[8];
    auto byte = [](double x) { return int(std::lround(std::clamp(x, 0.0, 1.0) * 255)); };
    std::snprintf(color, sizeof color, "#%02x%02x%02x", byte(g.rgb.x()), byte(g.rgb.y()), byte(g.rgb.z()));
    s.color = color;
    if (g.kind == "box" || g.kind == "ellipsoid") {
      s.kind = "box";
      s.size = 2.0 * g.size;
    } else if (g.kind == "sphere") {
      s.kind = "sphere";
      s.size = Vec3(g.size.x(), 0, 0);
    } else if (g.kind == "cylinder" || g.kind == "capsule") {
      s.kind = "cylinder";
      s.size = Vec3(g.size.x(), 2.0 * g.size.y() + (g.kind == "capsule" ? 2.0 * g.size.x() : 0.0), 0);
    } else if (g.kind == "mesh" && g.mesh >= 0 && size_t(g.mesh) < compiled.meshes.size()) {
      // the mesh as compiled, in the geom's frame; each embedded once
      s.kind = "mesh";
      s.size = Vec3::Ones();
      if (page_mesh[size_t(g.mesh)] < 0) {
        page_mesh[size_t(g.mesh)] = int(look.meshes.size());
        look.meshes.push_back(compiled_mesh(compiled.meshes[size_t(g.mesh)]));
      }
      s.mesh = page_mesh[size_t(g.mesh)];
      (g.body >= 0 ? look.bodies[size_t(g.body)].meshes : look.world_meshes) += 1;
    } else {
      continue;
    }
    (g.body >= 0 ? look.bodies[size_t(g.body)].visuals : look.world_visuals).push_back(s);
  }
}

}  // namespace

Look make_look(const Model& model, const std::string& urdf_text, const std::string& urdf_path,
               const std::vector<ModelFile>& mjcf_files) {
  Look look;
  look.bodies.resize(model.nbodies);
  for (int i = 0; i < model.nbodies; ++i) {
    BodyLook& b = look.bodies[i];
    b.inertia_box = inertia_box(model.mass[i], model.com[i], model.inertia[i]);
    // a capsule from the joint to each child's joint; a leaf's runs through its centre of mass to
    // the far face of its inertia box (a uniform rod: its far end; a bob on a light rod: the bob)
    for (int c = i + 1; c < model.nbodies; ++c)
      if (model.parent[c] == i && model.placement[c].p.norm() > 1e-9) b.segments.push_back(model.placement[c].p);
    bool has_child = false;
    for (int c = i + 1; c < model.nbodies; ++c) has_child = has_child || model.parent[c] == i;
    const Vec3& s = model.com[i];
    if (!has_child && s.norm() > 1e-9) {
      const Mat3 V = b.inertia_box.R.toRotationMatrix();
      const Vec3 u = s.normalized();
      const double reach = 0.5 * (V.transpose() * u).cwiseAbs().dot(b.inertia_box.size);  // support of the box along u
      b.segments.push_back(s + reach * u);
    }
  }
  if (!urdf_text.empty() && is_mjcf_text(urdf_text)) add_mjcf_visuals(mjcf_files, urdf_path, look);
  else if (!urdf_text.empty()) add_urdf_visuals(model, urdf_text, urdf_path, look);
  return look;
}

}  // namespace soadyn::cli::view
