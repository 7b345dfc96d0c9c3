#include "log_layout.hpp"

#include "soadyn/algorithm/frames.hpp"
#include "soadyn/algorithm/kinematics.hpp"

#include <algorithm>
#include <cassert>

namespace soadyn::log {

namespace {

std::vector<std::string> units_of(const Model& m, bool of_q) {
  std::vector<std::string> out;
  for (int i = 0; i < m.nbodies; ++i) {
    const JointTraits& tr = joint_traits(m.joint_type[i]);
    for (const auto& u : of_q ? tr.q_units : tr.v_units) out.emplace_back(u);
  }
  return out;
}

// "rad/s" → "rad/s^2"
std::string per_second(const std::string& rate) { return rate + "^2"; }

// a view of the next `cols` (× bodies) columns, named prefix + name [+ "." + suffix]
struct Builder {
  Layout out;
  void view(const std::string& path, const std::vector<Column>& cols, int view_cols, int bodies = 0) {
    // the reader finds views and their columns by kViewPaths and column_stem
    assert(std::any_of(std::begin(kViewPaths), std::end(kViewPaths), [&](const char* p) { return path == p; }));
    assert(std::all_of(cols.begin(), cols.end(), [&](const Column& c) { return column_of(c.name, column_stem(path)); }));
    View v;
    v.path = path;
    v.first = int(out.columns.size());
    v.cols = view_cols;
    v.bodies = bodies;
    const int last = std::max(1, view_cols);
    for (int c = 0; c < last; ++c) v.units.push_back(cols[size_t(c)].unit);
    out.columns.insert(out.columns.end(), cols.begin(), cols.end());
    out.views.push_back(std::move(v));
  }
};

// /q, /qd, /qdd: a column per coordinate of q and of v, q̈ in v's units per second
void state_views(Builder& b, const Model& m) {
  const std::vector<std::string> qn = m.q_names(), vn = m.v_names(), qu = q_units(m), vu = v_units(m);
  std::vector<Column> q, qd, qdd;
  for (int k = 0; k < m.nq; ++k) q.push_back({"q." + qn[size_t(k)], qu[size_t(k)]});
  for (int k = 0; k < m.nv; ++k) qd.push_back({"qd." + vn[size_t(k)], vu[size_t(k)]});
  for (int k = 0; k < m.nv; ++k) qdd.push_back({"qdd." + vn[size_t(k)], per_second(vu[size_t(k)])});
  b.view("/q", q, m.nq);
  b.view("/qd", qd, m.nv);
  b.view("/qdd", qdd, m.nv);
}

// /momentum/linear and /momentum/angular: 3 columns each, x y z
void momentum_views(Builder& b) {
  b.out.groups.push_back("/momentum");
  for (const auto& [kind, unit] : {std::pair{"linear", "kg m/s"}, std::pair{"angular", "kg m^2/s"}}) {
    std::vector<Column> c;
    for (const char* x : {"x", "y", "z"}) c.push_back({std::string("momentum.") + kind + "." + x, unit});
    b.view(std::string("/momentum/") + kind, c, 3);
  }
}

// /bodies/position, orientation and com: T × N × (3 | 4), body by body
void body_views(Builder& b, const Model& m) {
  b.out.groups.push_back("/bodies");
  const std::pair<const char*, std::vector<const char*>> series[] = {
      {"position", {"x", "y", "z"}}, {"orientation", {"w", "x", "y", "z"}}, {"com", {"x", "y", "z"}}};
  for (const auto& [kind, parts] : series) {
    const std::string unit = std::string(kind) == "orientation" ? "1" : "m";
    std::vector<Column> c;
    for (int i = 0; i < m.nbodies; ++i)
      for (const char* x : parts) c.push_back({std::string("bodies.") + kind + "." + m.body_names[size_t(i)] + "." + x, unit});
    b.view(std::string("/bodies/") + kind, c, int(parts.size()), m.nbodies);
  }
}

// /control: a generalized force per DOF: N m on a turning one, N on a sliding one
void control_view(Builder& b, const Model& m) {
  const std::vector<std::string> vn = m.v_names(), vu = v_units(m);
  std::vector<Column> c;
  for (int k = 0; k < m.nv; ++k) c.push_back({"control." + vn[size_t(k)], vu[size_t(k)] == "rad/s" ? "N m" : "N"});
  b.view("/control", c, m.nv);
}

// /prescribed: the torque holding each prescribed joint's motion (its DOF's v name), N m or N
void prescribed_view(Builder& b, const Model& m, const std::vector<int>& dofs) {
  const std::vector<std::string> vn = m.v_names(), vu = v_units(m);
  std::vector<Column> c;
  for (const int k : dofs) c.push_back({"prescribed." + vn[size_t(k)], vu[size_t(k)] == "rad/s" ? "N m" : "N"});
  b.view("/prescribed", c, int(dofs.size()));
}

// /sensitivities: ∂x_i/∂p_j, row-major (i, j): a T × nx × (nx | np) view; its units x_i's over p_j's
void sensitivity_views(Builder& b, const SensitivityPlan& p) {
  b.out.groups.push_back("/sensitivities");
  auto ratio = [](const std::string& a, const std::string& c) {
    if (a == c) return std::string("1");
    if (c == "1") return a;
    return a + "/" + (c.find_first_of(" /") != std::string::npos ? "(" + c + ")" : c);
  };
  const std::pair<const char*, std::pair<const std::vector<std::string>*, const std::vector<std::string>*>> parts[] = {
      {"initial_state", {&p.state_names, &p.state_units}}, {"parameters", {&p.parameter_names, &p.parameter_units}}};
  for (const auto& [kind, by] : parts) {
    const auto& [names, units] = by;
    if (std::string(kind) == "initial_state" ? !p.initial_state : p.np() == 0) continue;
    std::vector<Column> c;
    std::vector<std::string> all_units;
    for (int i = 0; i < p.nx; ++i)
      for (size_t j = 0; j < names->size(); ++j) {
        c.push_back({std::string("sensitivities.") + kind + "." + p.state_names[size_t(i)] + "." + (*names)[j],
                     ratio(p.state_units[size_t(i)], (*units)[j])});
        all_units.push_back(c.back().unit);
      }
    b.view(std::string("/sensitivities/") + kind, c, int(names->size()), p.nx);
    b.out.views.back().units = std::move(all_units);
  }
}

// /frames/position and orientation: T × F × (3 | 4), frame by frame
void frame_views(Builder& b, const Model& m, const std::vector<int>& frames) {
  b.out.groups.push_back("/frames");
  const std::pair<const char*, std::vector<const char*>> series[] = {{"position", {"x", "y", "z"}},
                                                                      {"orientation", {"w", "x", "y", "z"}}};
  for (const auto& [kind, parts] : series) {
    const std::string unit = std::string(kind) == "orientation" ? "1" : "m";
    std::vector<Column> c;
    for (const int f : frames)
      for (const char* x : parts) c.push_back({std::string("frames.") + kind + "." + m.frame_names[size_t(f)] + "." + x, unit});
    b.view(std::string("/frames/") + kind, c, int(parts.size()), int(frames.size()));
  }
}

}  // namespace

std::vector<std::string> q_units(const Model& model) { return units_of(model, true); }
std::vector<std::string> v_units(const Model& model) { return units_of(model, false); }

Layout layout(const Model& m, const LogGroups& g) {
  Builder b;
  b.view("/time", {{"time", "s"}}, 0);
  if (g.state) state_views(b, m);
  if (g.energy) {
    b.out.groups.push_back("/energy");
    for (const char* e : {"kinetic", "potential", "total", "work_inputs", "dissipated"})
      b.view(std::string("/energy/") + e, {{std::string("energy.") + e, "J"}}, 0);
  }
  if (g.energy && g.impacts) b.view("/energy/impact_loss", {{"energy.impact_loss", "J"}}, 0);
  if (g.energy && !g.prescribed.empty()) b.view("/energy/work_prescribed", {{"energy.work_prescribed", "J"}}, 0);
  if (g.momentum) momentum_views(b);
  if (g.bodies) body_views(b, m);
  if (g.control) control_view(b, m);
  if (!g.prescribed.empty()) prescribed_view(b, m, g.prescribed);
  if (!g.loop_rows.empty()) {
    // /loops/force: λ row by row; /loops/closure: the largest |φ|
    b.out.groups.push_back("/loops");
    std::vector<Column> c;
    for (size_t r = 0; r < g.loop_rows.size(); ++r) c.push_back({"loops.force." + g.loop_rows[r], g.loop_units[r]});
    b.view("/loops/force", c, int(c.size()));
    b.view("/loops/closure", {{"loops.closure", "m"}}, 0);
  }
  if (g.sensitivities) sensitivity_views(b, *g.sensitivities);
  if (!g.frames.empty()) frame_views(b, m, g.frames);  // last, as append_row writes them
  return std::move(b.out);
}

void append_row(const Model& m, Data& data, const LogGroups& g, const Sample& s, std::vector<double>& b) {
  auto put = [&b](const auto& x) { b.insert(b.end(), x.data(), x.data() + x.size()); };
  b.push_back(s.t);
  if (g.state) put(s.q), put(s.qd), put(s.qdd);
  if (g.energy) b.insert(b.end(), {s.kinetic, s.potential, s.total, s.work_inputs, s.dissipated});
  if (g.energy && g.impacts) b.push_back(s.impact_loss);
  if (g.energy && !g.prescribed.empty()) b.push_back(s.work_prescribed);
  if (g.momentum) put(s.linear), put(s.angular);
  if (g.bodies) put(s.body_position), put(s.body_orientation), put(s.body_com);  // column-major: body by body
  if (g.control) put(s.control);
  if (!g.prescribed.empty()) put(s.prescribed_torque);
  if (!g.loop_rows.empty()) put(s.loop_force), b.push_back(s.loop_closure);
  if (g.sensitivities) {
    // row-major (∂x_i/∂p_j at i·cols + j): the transpose's column-major storage
    if (g.sensitivities->initial_state) put(MatX(s.sensitivity_initial_state.transpose()));
    if (g.sensitivities->np() > 0) put(MatX(s.sensitivity_parameters.transpose()));
  }
  if (g.frames.empty()) return;
  // the frames' placements at q: every position, then every orientation (w ≥ 0)
  update_frames(m, data, s.q);
  for (const int f : g.frames) put(frame_placement(m, data, f).p);
  for (const int f : g.frames) put(attitude_quaternion(frame_placement(m, data, f).R));
}

}  // namespace soadyn::log
