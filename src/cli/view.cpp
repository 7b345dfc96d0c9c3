// soadyn view RUN.h5: one self-contained web page that plays a run in 3D.
//
// The model is rebuilt from the scenario stored in the run, body poses are recomputed from the
// logged q by the library's kinematics, and the page gets them, decimated to the display rate, as
// base64 float32 arrays inside a JSON block.  The page's HTML, CSS and script (tools/view/) and
// three.js (Debian libjs-three) are compiled into the executable and inlined in every page, so
// the page fetches nothing when it is opened (its Content-Security-Policy forbids it).
#include "cli.hpp"
#include "view.hpp"

#include "soadyn/algorithm/frames.hpp"
#include "soadyn/io/h5log.hpp"
#include "soadyn/sim/limits.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/multibody/text.hpp"
#include "soadyn/multibody/configuration.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string_view>

namespace soadyn::cli {

namespace assets {
extern const std::string_view page_html, page_css, page_js, plot_js, frames_js, bodies_js, meshes_js, three_js, orbit_js,
    stl_js, obj_js, collada_js;
}

namespace {

using view::Shape;

// --- a small JSON writer ----------------------------------------------------------------------

std::string quote(std::string_view s) {
  std::string out = "\"";
  for (const unsigned char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      case '<': out += "\\u003c"; break;  // never "</script>" inside the page's JSON block
      case '>': out += "\\u003e"; break;
      case '&': out += "\\u0026"; break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += char(c);
        }
    }
  }
  return out + "\"";
}

std::string num(double x) {
  if (!std::isfinite(x)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

std::string vec(const Vec3& v) { return "[" + num(v.x()) + "," + num(v.y()) + "," + num(v.z()) + "]"; }

std::string quat(const Eigen::Quaterniond& q) {  // three.js order: x, y, z, w
  return "[" + num(q.x()) + "," + num(q.y()) + "," + num(q.z()) + "," + num(q.w()) + "]";
}

std::string shape(const Shape& s) {
  return "{\"kind\":" + quote(s.kind) + ",\"size\":" + vec(s.size) + ",\"p\":" + vec(s.p) + ",\"q\":" + quat(s.R) +
         ",\"color\":" + (s.color.empty() ? std::string("null") : quote(s.color)) +
         (s.mesh >= 0 ? ",\"mesh\":" + std::to_string(s.mesh) : std::string()) + "}";
}

std::string shapes(const std::vector<Shape>& v) {
  std::string out = "[";
  for (size_t k = 0; k < v.size(); ++k) out += (k ? "," : "") + shape(v[k]);
  return out + "]";
}

std::string base64(const void* data, size_t bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* p = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve((bytes + 2) / 3 * 4);
  for (size_t i = 0; i < bytes; i += 3) {
    const unsigned n = unsigned(p[i]) << 16 | (i + 1 < bytes ? unsigned(p[i + 1]) << 8 : 0u) | (i + 2 < bytes ? p[i + 2] : 0u);
    out += table[n >> 18 & 63];
    out += table[n >> 12 & 63];
    out += i + 1 < bytes ? table[n >> 6 & 63] : '=';
    out += i + 2 < bytes ? table[n & 63] : '=';
  }
  return out;
}

template <class T>
std::string base64(const std::vector<T>& v) {
  return quote(base64(v.data(), v.size() * sizeof(T)));
}

std::string html_escape(std::string_view s) {
  std::string out;
  for (const char c : s) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

// --- frames -------------------------------------------------------------------------------------

// The samples shown: the first, then each one at least h after the last kept, and the last, with
// h = max(1/fps, duration/max_frames): ≤ fps frames per simulated second (real time at ×1), and a
// bounded page however long the run.
std::vector<Eigen::Index> decimate(const VecX& t, double fps, long max_frames, double& h) {
  const Eigen::Index n = t.size();
  h = std::max(1.0 / fps, (t(n - 1) - t(0)) / double(std::max(1L, max_frames - 1)));
  std::vector<Eigen::Index> keep{0};
  for (Eigen::Index k = 1; k < n; ++k)
    if (t(k) - t(keep.back()) >= h * (1 - 1e-6) || k == n - 1) keep.push_back(k);
  return keep;
}

// names of the q coordinates, for the joint plot: the joint's name, and the joint type's label of
// each coordinate when it has several (pivot.qw, bus.x, ...); a joint whose motion the run
// prescribed is marked so
std::vector<std::string> coordinate_names(const Model& m, const std::vector<std::string>& prescribed) {
  std::vector<std::string> names;
  for (int i = 0; i < m.nbodies; ++i) {
    const JointTraits& tr = joint_traits(m.joint_type[i]);
    const bool given = std::find(prescribed.begin(), prescribed.end(), m.joint_names[i]) != prescribed.end();
    for (int k = 0; k < m.nq_i[i]; ++k)
      names.push_back(m.joint_names[i] + (m.nq_i[i] > 1 ? "." + std::string(tr.q_labels.at(k)) : std::string()) +
                      (given ? " [prescribed]" : ""));
  }
  return names;
}

// the SI unit of each q coordinate, for the joint plot's axis: m, rad, or 1 (a quaternion's parts)
std::vector<std::string> coordinate_units(const Model& m) {
  std::vector<std::string> units;
  for (int i = 0; i < m.nbodies; ++i) {
    const JointTraits& tr = joint_traits(m.joint_type[i]);
    for (int k = 0; k < m.nq_i[i]; ++k) units.emplace_back(tr.q_units.at(k));
  }
  return units;
}

// the mesh files, for the page: a list in its JSON block (name, format, sizes, why one is not
// drawn) and each file's bytes, base64, in a block of its own (read only by the script that
// draws it); `formats` gets the formats drawn (their loaders go into the page)
std::string mesh_list(const std::vector<view::MeshFile>& meshes, std::string& blocks, std::string& formats) {
  std::string list = "[";
  for (size_t k = 0; k < meshes.size(); ++k) {
    const view::MeshFile& f = meshes[k];
    list += std::string(k ? "," : "") + "{\"name\":" + quote(printable(f.name)) + ",\"format\":" + quote(f.format) +
            ",\"bytes\":" + std::to_string(f.bytes.size()) + ",\"vertices\":" + std::to_string(f.vertices) +
            ",\"triangles\":" + std::to_string(f.triangles) + ",\"error\":" + (f.error.empty() ? "null" : quote(f.error)) + "}";
    if (!f.error.empty()) continue;
    blocks += "<script type=\"text/plain\" id=\"soadyn-mesh-" + std::to_string(k) + "\">" + base64(f.bytes.data(), f.bytes.size()) +
              "</script>\n";
    if (formats.find(f.format) == std::string::npos) formats += f.format + " ";
  }
  return list + "]";
}

std::string fill_template(std::string_view tpl, const std::vector<std::pair<std::string, std::string_view>>& values) {
  std::string out;
  out.reserve(tpl.size() + [&] {
    size_t n = 0;
    for (const auto& v : values) n += v.second.size();
    return n;
  }());
  size_t at = 0;
  while (true) {
    const size_t open = tpl.find('@', at);
    if (open == std::string_view::npos) break;
    bool matched = false;
    for (const auto& [key, value] : values)
      if (tpl.compare(open, key.size() + 2, "@" + key + "@") == 0) {
        out.append(tpl.substr(at, open - at));
        out.append(value);
        at = open + key.size() + 2;
        matched = true;
        break;
      }
    if (!matched) {
      out.append(tpl.substr(at, open + 1 - at));
      at = open + 1;
    }
  }
  out.append(tpl.substr(at));
  return out;
}

}  // namespace

void add_view(CLI::App& app, ViewOptions& o) {
  CLI::App* c = app.add_subcommand(
      "view",
      "Write one self-contained web page (three.js inlined, nothing fetched) that plays a run in 3D,\n"
      "with linked plots of the energy error and a joint, the model drawn in its visuals (a URDF's mesh files\n"
      "are read now and inlined).  Open RUN.html#t=1.5 to start paused at t = 1.5 s.\n"
      "Exit status: 0 written, 2 bad input or output refused (an input, in use, not a soadyn page), 4 writing failed.");
  c->add_option("RUN", o.run, "HDF5 run file from soadyn run")->required();
  c->add_option("-o,--output", o.output, "HTML file to write (default: RUN with the extension .html)");
  c->add_option("--fps", o.fps, "at most this many frames per simulated second (default 60)")
      ->check(CLI::Range(1.0, 1000.0));
  c->add_option("--max-frames", o.max_frames, "and at most this many frames in all (default 20000)")
      ->check(CLI::Range(2L, 1000000L));
  c->add_flag("--force", o.force,
              "replace the output even when it is not a soadyn page (never an input or a file in use)");
  c->add_flag("-q,--quiet", o.quiet, "no summary on stdout");
}

namespace {

// Every shown sample's poses from q by the library's kinematics: R_i, η_i of every body (the note's
// [kin] stage), and of the frames the run logged (frames.hpp's placement: R = C_b X.R, p = η_b +
// C_b X.p), with the box that holds them all
struct Poses {
  std::vector<double> times;
  std::vector<float> body, frame, q;  // K × N × 7, K × F × 7 ([p; x y z w]), K × nq
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  void extend(const Vec3& x) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
};

void put_pose(float* out, const Vec3& p, const Mat3& R) {
  const Eigen::Quaterniond r(R);
  for (int c = 0; c < 3; ++c) out[c] = float(p(c));
  out[3] = float(r.x()), out[4] = float(r.y()), out[5] = float(r.z()), out[6] = float(r.w());
}

Poses poses(const Model& m, const view::RunFile& run, const view::Look& look, const std::vector<int>& logged,
            const std::vector<Eigen::Index>& keep) {
  const size_t K = keep.size(), N = size_t(m.nbodies), F = logged.size();
  Poses P;
  P.times.resize(K), P.body.resize(K * N * 7), P.frame.resize(K * F * 7), P.q.resize(K * size_t(m.nq));
  Data d(m);
  for (size_t f = 0; f < K; ++f) {
    const Eigen::Index k = keep[f];
    VecX q = run.q.row(k).transpose();
    m.normalize(q);
    update_kinematics(m, d, q);
    P.times[f] = run.time(k);
    for (size_t i = 0; i < N; ++i) {
      const Vec3 p = d.eta.col(i);
      put_pose(&P.body[(f * N + i) * 7], p, d.R[i]);
      P.extend(p);
      P.extend(d.r.col(i));
      for (const Vec3& s : look.bodies[i].segments) P.extend(p + d.R[i] * s);
      const Shape& box = look.bodies[i].inertia_box;  // its corners
      for (int c = 0; c < 8; ++c) {
        const Vec3 corner(c & 1 ? 0.5 : -0.5, c & 2 ? 0.5 : -0.5, c & 4 ? 0.5 : -0.5);
        P.extend(p + d.R[i] * (box.p + box.R * corner.cwiseProduct(box.size)));
      }
    }
    for (size_t j = 0; j < F; ++j) {
      const Placement X = frame_placement(m, d, logged[j]);
      put_pose(&P.frame[(f * F + j) * 7], X.p, X.R);
      P.extend(X.p);
    }
    for (int c = 0; c < m.nq; ++c) P.q[f * size_t(m.nq) + c] = float(run.q(k, c));
  }
  return P;
}

// the energy-balance error (E − E0 − W + L) / max(|E0|, peak T), as soadyn run reports it, L the
// energy the limits' impacts took (files before layout 3 hold no W: the energy error); "null"
// without energies
std::string energy_json(const view::RunFile& run, const view::RunModel& rm, const std::vector<Eigen::Index>& keep) {
  if (!run.total.size()) return "null";
  const bool balance = run.work.size() > 0, impacts = run.impact_loss.size() > 0;
  const bool held = run.work_prescribed.size() > 0;  // W_p, the prescribed joints' torques' work
  const auto L = [&](Eigen::Index k) { return impacts ? run.impact_loss(k) : 0.0; };
  const auto Wp = [&](Eigen::Index k) { return held ? run.work_prescribed(k) : 0.0; };
  const double E0 = run.total(0) + L(0);
  const double scale = std::max({std::abs(E0), run.kinetic.size() ? run.kinetic.maxCoeff() : 0.0, 1e-300});
  std::vector<float> err(keep.size());
  for (size_t f = 0; f < keep.size(); ++f)
    err[f] = float((run.total(keep[f]) - E0 - (balance ? run.work(keep[f]) : 0.0) - Wp(keep[f]) + L(keep[f])) / scale);
  return "{\"error\":" + base64(err) + ",\"E0\":" + num(E0) + ",\"scale\":" + num(scale) +
         ",\"work_inputs\":" + (rm.has_work_inputs ? "true" : "false") + ",\"balance\":" + (balance ? "true" : "false") +
         ",\"impacts\":" + (impacts ? "true" : "false") + ",\"prescribed\":" + (held ? "true" : "false") + "}";
}

// the joint limits' events, for the timeline: time, joint, side, kind and velocities
std::string events_json(const view::RunFile& run, const Model& m) {
  std::string events = "[";
  const std::vector<std::string> vn = run.v_names.empty() ? m.v_names() : run.v_names;
  for (size_t k = 0; k < run.events.size(); ++k) {
    const RunEvent& e = run.events[k];
    const char* kind = e.kind >= 0 && e.kind < int(std::size(kLimitEventKinds)) ? kLimitEventKinds[e.kind] : "event";
    events += std::string(k ? "," : "") + "{\"t\":" + num(e.t) + ",\"joint\":" + quote(size_t(e.dof) < vn.size() ? vn[size_t(e.dof)] : "dof " + std::to_string(e.dof)) +
              ",\"side\":" + quote(e.side < 0 ? "lower" : "upper") + ",\"kind\":" + quote(kind) + ",\"v_before\":" + num(e.v_before) +
              ",\"v_after\":" + num(e.v_after) + ",\"energy_lost\":" + num(e.energy_lost) + "}";
  }
  return events + "]";
}

// the scene: bodies as the model knows them, and the coordinates' names and units
std::string bodies_json(const Model& m, const view::Look& look) {
  std::string bodies = "[";
  for (size_t i = 0; i < size_t(m.nbodies); ++i) {
    const view::BodyLook& b = look.bodies[i];
    std::string segs = "[";
    for (size_t s = 0; s < b.segments.size(); ++s) segs += (s ? "," : "") + vec(b.segments[s]);
    segs += "]";
    bodies += std::string(i ? "," : "") + "{\"name\":" + quote(m.body_names[i]) + ",\"joint\":" + quote(m.joint_names[i]) +
              ",\"type\":" + quote(std::string(to_string(m.joint_type[i]))) + ",\"parent\":" + std::to_string(m.parent[i]) + ",\"iq\":" + std::to_string(m.idx_q[i]) +
              ",\"quaternion\":" + std::to_string(joint_quaternion(m, i)) +
              ",\"mass\":" + num(m.mass[i]) + ",\"com\":" + vec(m.com[i]) + ",\"axis\":" + vec(m.axis[i]) +
              ",\"segments\":" + segs + ",\"box\":" + shape(b.inertia_box) + ",\"visuals\":" + shapes(b.visuals) +
              ",\"meshes\":" + std::to_string(b.meshes) + "}";
  }
  return bodies + "]";
}

std::string string_list(const std::vector<std::string>& v) {
  std::string out = "[";
  for (size_t c = 0; c < v.size(); ++c) out += (c ? "," : "") + quote(v[c]);
  return out + "]";
}

// the logged frames: names, the body each moves with, and per shown sample their poses
std::string named_frames_json(const Model& m, const view::RunFile& run, const std::vector<int>& logged, const Poses& P) {
  std::vector<std::string> bodies;
  for (int f : logged) {
    const int b = m.frame_body[size_t(f)];
    bodies.push_back(b < 0 ? std::string("world") : m.body_names[size_t(b)]);
  }
  return "{\"names\":" + string_list(run.frame_names) + ",\"bodies\":" + string_list(bodies) + ",\"pose\":" + base64(P.frame) + "}";
}

// The mesh files: what the page draws, their bytes, how many cannot be drawn; those are said on
// stderr too (the page's note names all)
struct Meshes {
  std::string list, blocks, formats;
  size_t failed = 0, bytes = 0;
};

Meshes meshes(const view::Look& look, const std::string& run_path) {
  Meshes M;
  M.list = mesh_list(look.meshes, M.blocks, M.formats);
  for (const view::MeshFile& f : look.meshes) {
    M.bytes += f.bytes.size();
    if (f.error.empty()) continue;
    if (++M.failed <= 5)
      std::fprintf(stderr, "soadyn: note: %s: mesh %s drawn as its body's default shape: %s\n", run_path.c_str(),
                   printable(f.name).c_str(), f.error.c_str());
  }
  if (M.failed > 5) std::fprintf(stderr, "soadyn: note: %s: and %zu more meshes (the page names them all)\n", run_path.c_str(), M.failed - 5);
  return M;
}

// the page: the template with the run's data, the styles and scripts inlined, and a mesh format's
// loader only in a page that has one
std::string page_html(const std::string& name, const std::string& data, const Meshes& M) {
  const auto loader = [&](const char* ext, std::string_view js) {
    return M.formats.find(ext) != std::string::npos ? js : std::string_view();
  };
  return fill_template(assets::page_html, {{"TITLE", html_escape(name)},
                                           {"CSS", assets::page_css},
                                           {"DATA", data},
                                           {"THREE", assets::three_js},
                                           {"ORBIT", assets::orbit_js},
                                           {"PLOT", assets::plot_js},
                                           {"FRAMES", assets::frames_js},
                                           {"BODIES", assets::bodies_js},
                                           {"MESHES", assets::meshes_js},
                                           {"MESH_DATA", M.blocks},
                                           {"STL", loader("stl", assets::stl_js)},
                                           {"OBJ", loader("obj", assets::obj_js)},
                                           {"COLLADA", loader("dae", assets::collada_js)},
                                           {"VIEWER", assets::page_js}});
}

// a run that went unstable may end in non-finite rows: shown up to the last finite one
void keep_finite(view::RunFile& run, const std::string& path) {
  Eigen::Index finite = 0;
  while (finite < run.q.rows() && run.q.row(finite).allFinite()) ++finite;
  if (finite == 0) throw Error(path + ": /q is not finite from its first row on: nothing to show");
  if (finite < run.q.rows()) {
    std::fprintf(stderr, "soadyn: note: %s: /q is not finite from t = %g s on; the page ends at t = %g s\n", path.c_str(),
                 run.time(finite), run.time(finite - 1));
    view::keep_rows(run, finite);
  }
}

}  // namespace

int run_view(const ViewOptions& o) {
  // the output is checked before anything is read, and nothing is touched if it is refused
  const std::string out = o.output.empty() ? std::filesystem::path(o.run).replace_extension(".html").string() : o.output;
  const OutputTarget target = check_outputs({{out, OutputKind::Page}}, {o.run}, o.force).at(0);
  view::RunFile run = view::read_run(o.run);
  keep_finite(run, o.run);
  const view::RunModel rm = view::rebuild_model(run);
  const Model& m = rm.model;
  const view::Look look = view::make_look(m, rm.urdf_text, rm.urdf_path, rm.mjcf_files);

  double h = 0.0;
  const std::vector<Eigen::Index> keep = decimate(run.time, o.fps, o.max_frames, h);
  const size_t K = keep.size(), N = size_t(m.nbodies);
  std::vector<int> logged;
  for (const std::string& name : run.frame_names) logged.push_back(m.frame_index(name));
  const Poses P = poses(m, run, look, logged, keep);
  const Meshes M = meshes(look, o.run);

  char rule[160];
  std::snprintf(rule, sizeof rule, "%zu of %ld logged samples, at least %.4g s apart (at most %.4g per simulated second)", K,
                long(run.time.size()), h, 1.0 / h);
  const std::string data =
      "{\"name\":" + quote(rm.name) + ",\"description\":" + quote(rm.description) + ",\"run\":" +
      quote(std::filesystem::path(o.run).filename().string()) + ",\"scenario_path\":" + quote(run.scenario_path) +
      ",\"version\":" + quote(run.version) + ",\"method\":" + quote(run.method) + ",\"status\":" + quote(run.status) +
      ",\"gravity\":" + vec(m.gravity) + ",\"bodies\":" + bodies_json(m, look) + ",\"world_visuals\":" + shapes(look.world_visuals) +
      ",\"world_meshes\":" + std::to_string(look.world_meshes) + ",\"bounds\":{\"min\":" + vec(P.lo) + ",\"max\":" + vec(P.hi) +
      "},\"frames\":{\"n\":" + std::to_string(K) + ",\"nb\":" + std::to_string(N) + ",\"t\":" + base64(P.times) +
      ",\"pose\":" + base64(P.body) + ",\"rule\":" + quote(rule) + "},\"coords\":" + string_list(coordinate_names(m, run.prescribed)) +
      ",\"coord_units\":" + string_list(coordinate_units(m)) + ",\"meshes\":" + M.list + ",\"nq\":" + std::to_string(m.nq) +
      ",\"q\":" + base64(P.q) + ",\"energy\":" + energy_json(run, rm, keep) + ",\"events\":" + events_json(run, m) +
      ",\"named_frames\":" + named_frames_json(m, run, logged, P) + "}";
  const std::string page = page_html(rm.name, data, M);

  try {
    TextWriter w(out, target);
    w.write(page);
    w.commit();
  } catch (const IoError& e) {
    std::fprintf(stderr, "soadyn: error: %s\n", e.what());
    return 4;
  }
  if (!o.quiet) {
    std::printf("run                    %s (%s)\n", printable(o.run).c_str(),
                run.status.empty() ? "status unknown" : printable(run.status).c_str());
    std::printf("bodies                 %zu\n", N);
    std::printf("frames                 %s\n", rule);
    if (!look.meshes.empty())
      std::printf("meshes                 %zu file(s), %.3g MB in the page; %zu not drawn (said on stderr and in the page)\n",
                  look.meshes.size(), double(M.bytes) / 1e6, M.failed);
    std::printf("page                   %s (%.3g MB)\n", out.c_str(), double(page.size()) / 1e6);
  }
  return 0;
}

}  // namespace soadyn::cli
