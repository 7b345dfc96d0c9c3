#include "cli.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/frames.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/sim/scenario.hpp"
#include "soadyn/multibody/text.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <tuple>

namespace soadyn::cli {

void add_inspect(CLI::App& app, InspectOptions& o) {
  CLI::App* c = app.add_subcommand(
      "inspect",
      "Print the system mass matrix M(q) (eq. 14), bias(q, qd), qdd for --tau, energy and momentum at one state.\n"
      "MODEL is a .yaml scenario or a .urdf; without --q/--qd the scenario's initial state (zeros for a URDF).");
  c->add_option("MODEL", o.model, "scenario (.yaml) or robot (.urdf)")->required();
  add_state_options(c, o.state, "the state");
  c->add_option("--tau", o.tau, "joint forces for qdd, comma-separated, nv numbers (default zero)");
  c->add_flag("--json", o.json, "print one JSON object on stdout");
  std::vector<std::string> routes = fd_method_names();
  routes.emplace_back(kFdMethodAliasOn);  // the O(N) route's old word, still taken
  c->add_option("--method", o.method, "forward-dynamics route for qdd: " + join(fd_method_names(), " | ") + " (default aba)")
      ->transform(one_of(routes));
  c->add_option("--frame", o.frames,
                "a named frame (a body, a link merged by a fixed joint, a scenario's frames: entry) whose pose and "
                "Jacobian J (6 x nv, [w; v] of the frame's origin, inertial axes) are printed; may be repeated");
}


namespace {

std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\', o += c;
    else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      o += buf;
    } else o += c;
  }
  return o + "\"";
}

template <class V>
std::string json_array(const V& v) {
  std::string o = "[";
  for (Eigen::Index k = 0; k < v.size(); ++k) o += (k ? ", " : "") + exact_number(v(k));
  return o + "]";
}

void print_vector(const std::string& title, const std::vector<std::string>& labels, const VecX& v) {
  std::printf("%s\n", title.c_str());
  for (Eigen::Index k = 0; k < v.size(); ++k) std::printf("  %-24s % .17g\n", labels[k].c_str(), v(k));
}


// Everything inspect reports, computed once and printed as JSON or as tables.
struct Inspection {
  VecX q, v, tau, bias, qdd;
  MatX M;
  double T = 0.0, V = 0.0;
  Momentum h;
  Mat3X position, com;                            // η_i and r_i, inertial
  Eigen::Matrix<double, 4, Eigen::Dynamic> orientation;  // [w x y z], body → inertial, w ≥ 0
  struct Frame {
    int index;
    Placement X;   // frame → inertial
    MatX J;        // local_world_aligned, 6×nv
  };
  std::vector<Frame> frames;                      // --frame
};

// q (unit quaternions checked, then normalized), v and τ from the options, then 𝓜, bias and q̈.
Inspection inspect(const Scenario& sc, const InspectOptions& o) {
  const Model& m = sc.model;
  Inspection r;
  r.q = sc.q0;
  r.v = sc.v0;
  state_from_options(m, o.state, r.q, r.v);
  r.tau = vector_option("--tau", o.tau, m.nv, VecX::Zero(m.nv));
  for (const std::string& name : o.frames) {
    const int f = m.frame_index(name);
    if (f < 0) throw Error("--frame: no frame named '" + printable(name) + "'" + did_you_mean(name, m.frame_names));
    r.frames.push_back({f, {}, {}});
  }

  Data d(m);
  update_kinematics(m, d, r.q);
  mass_matrix(m, d);
  r.M = d.M;
  update_velocities(m, d, r.v);
  bias_forces(m, d);
  r.bias = d.bias;
  forward_dynamics(m, d, r.tau, parse_fd_method(o.method));
  r.qdd = d.qdd;
  r.T = kinetic_energy(m, d);
  r.V = potential_energy(m, d);
  r.h = momentum(m, d);
  // body poses as soadyn run logs them
  r.position = d.eta;
  r.com = d.r;
  r.orientation.resize(4, m.nbodies);
  for (int i = 0; i < m.nbodies; ++i) {
    r.orientation.col(i) = attitude_quaternion(d.R[i]);
  }
  update_kinematics(m, d, r.q);  // the frames' placements and Jacobians, from [kin]
  for (Inspection::Frame& f : r.frames) {
    f.X = frame_placement(m, d, f.index);
    frame_jacobian(m, d, f.index, Reference::LocalWorldAligned, f.J);
  }
  return r;
}

void print_json(const Model& m, const Inspection& r, const std::string& method) {
  std::string out = "{\"joints\": [";
  for (int i = 0; i < m.nbodies; ++i) out += (i ? ", " : "") + json_string(m.joint_names[i]);
  out += "], \"nq\": " + std::to_string(m.nq) + ", \"nv\": " + std::to_string(m.nv);
  out += ", \"q\": " + json_array(r.q) + ", \"qd\": " + json_array(r.v) + ", \"gravity\": " + json_array(m.gravity);
  out += ", \"M\": [";
  for (int k = 0; k < m.nv; ++k) out += (k ? ", " : "") + json_array(VecX(r.M.row(k).transpose()));
  out += "], \"bias\": " + json_array(r.bias) + ", \"tau\": " + json_array(r.tau) + ", \"qdd\": " + json_array(r.qdd);
  out += ", \"kinetic_energy\": " + exact_number(r.T) + ", \"potential_energy\": " + exact_number(r.V);
  out += ", \"momentum\": {\"linear\": " + json_array(r.h.linear) + ", \"angular\": " + json_array(r.h.angular) + "}";
  out += ", \"bodies\": [";
  for (int i = 0; i < m.nbodies; ++i)
    out += std::string(i ? ", " : "") + "{\"name\": " + json_string(m.body_names[i]) +
           ", \"position\": " + json_array(r.position.col(i)) + ", \"orientation\": " + json_array(r.orientation.col(i)) +
           ", \"com\": " + json_array(r.com.col(i)) + "}";
  out += "]";
  if (!r.frames.empty()) {
    out += ", \"frames\": [";
    for (size_t n = 0; n < r.frames.size(); ++n) {
      const Inspection::Frame& f = r.frames[n];
      const int b = m.frame_body[size_t(f.index)];
      out += std::string(n ? ", " : "") + "{\"name\": " + json_string(m.frame_names[size_t(f.index)]) +
             ", \"body\": " + json_string(b < 0 ? "world" : m.body_names[size_t(b)]) + ", \"position\": " + json_array(f.X.p) +
             ", \"orientation\": " + json_array(attitude_quaternion(f.X.R)) + ", \"jacobian\": [";
      for (int k = 0; k < 6; ++k) out += (k ? ", " : "") + json_array(VecX(f.J.row(k).transpose()));
      out += "]}";
    }
    out += "]";
  }
  out += ", \"method\": " + json_string(method) + "}";
  std::cout << out << std::endl;
}

void print_tables(const Scenario& sc, const Inspection& r, const std::string& method) {
  const Model& m = sc.model;
  const std::vector<std::string> qlab = m.q_names(), vlab = m.v_names();
  std::printf("model      %s (%d bodies, nq = %d, nv = %d)\n", sc.path.c_str(), m.nbodies, m.nq, m.nv);
  std::printf("gravity    [% g, % g, % g] m/s^2\n", m.gravity.x(), m.gravity.y(), m.gravity.z());
  std::printf("%-4s %-20s %-20s %-10s %s\n", "#", "body", "joint", "type", "parent");
  for (int i = 0; i < m.nbodies; ++i)
    std::printf("%-4d %-20s %-20s %-10s %s\n", i, m.body_names[i].c_str(), m.joint_names[i].c_str(),
                std::string(to_string(m.joint_type[i])).c_str(),
                m.parent[i] < 0 ? "world" : m.body_names[m.parent[i]].c_str());
  print_vector("q", qlab, r.q);
  print_vector("qd", vlab, r.v);
  std::printf("mass matrix M(q) (%d x %d)\n", m.nv, m.nv);
  for (int k = 0; k < m.nv; ++k) {
    std::printf("  %-24s", vlab[k].c_str());
    for (int c = 0; c < m.nv; ++c) std::printf(" % 14.9g", r.M(k, c));
    std::printf("\n");
  }
  print_vector("bias(q, qd) (Coriolis, centrifugal, gyroscopic, gravity)", vlab, r.bias);
  print_vector("tau", vlab, r.tau);
  print_vector("qdd = M^-1 (tau - bias)  [" + method + "]", vlab, r.qdd);
  std::printf("energy     kinetic % .17g   potential % .17g   total % .17g J\n", r.T, r.V, r.T + r.V);
  std::printf("bodies     frame origin (m), attitude [w x y z] body -> inertial, centre of mass (m); inertial\n");
  for (int i = 0; i < m.nbodies; ++i) {
    const Vec3 p = r.position.col(i), c = r.com.col(i);
    const Eigen::Vector4d u = r.orientation.col(i);
    std::printf("  %-20s [% .12g, % .12g, % .12g]  [% .12g, % .12g, % .12g, % .12g]  [% .12g, % .12g, % .12g]\n",
                m.body_names[i].c_str(), p(0), p(1), p(2), u(0), u(1), u(2), u(3), c(0), c(1), c(2));
  }
  for (const Inspection::Frame& f : r.frames) {
    const int b = m.frame_body[size_t(f.index)];
    const Eigen::Vector4d u = attitude_quaternion(f.X.R);
    std::printf("frame      %s on %s: origin [% .12g, % .12g, % .12g] m, attitude [% .12g, % .12g, % .12g, % .12g] "
                "frame -> inertial\n",
                m.frame_names[size_t(f.index)].c_str(), b < 0 ? "the world" : m.body_names[size_t(b)].c_str(), f.X.p(0),
                f.X.p(1), f.X.p(2), u(0), u(1), u(2), u(3));
    std::printf("  Jacobian (6 x %d): [w; v] of the frame's origin = J qd, inertial axes\n", m.nv);
    const char* rows[] = {"wx", "wy", "wz", "vx", "vy", "vz"};
    for (int k = 0; k < 6; ++k) {
      std::printf("  %-24s", rows[k]);
      for (int c = 0; c < m.nv; ++c) std::printf(" % 14.9g", f.J(k, c));
      std::printf("\n");
    }
  }
  std::printf("momentum   linear  [% .10g, % .10g, % .10g]\n", r.h.linear.x(), r.h.linear.y(), r.h.linear.z());
  std::printf("           angular [% .10g, % .10g, % .10g] (about the inertial origin)\n", r.h.angular.x(),
              r.h.angular.y(), r.h.angular.z());
}

}  // namespace

int run_inspect(const InspectOptions& o) {
  const Scenario sc = load_with_options(o.model, o.state);
  const Inspection r = inspect(sc, o);
  const std::string method(to_string(parse_fd_method(o.method)));  // "on" printed as "aba"
  if (o.json) print_json(sc.model, r, method);
  else print_tables(sc, r, method);
  return 0;
}

}  // namespace soadyn::cli
