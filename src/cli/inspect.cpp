#include "cli.hpp"

#include "soadyn/algorithms.hpp"
#include "soadyn/kinematics.hpp"
#include "soadyn/scenario.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <tuple>

namespace soadyn::cli {

std::vector<std::string> join_negative_values(int argc, char** argv) {
  static const std::vector<std::string> list_options = {"--q", "--qd", "--tau", "--gravity"};
  std::vector<std::string> out;
  for (int k = 0; k < argc; ++k) {
    const std::string a = argv[k];
    const bool takes_list = std::find(list_options.begin(), list_options.end(), a) != list_options.end();
    if (takes_list && k + 1 < argc && argv[k + 1][0] == '-') {
      out.push_back(a + "=" + argv[k + 1]);
      ++k;
    } else {
      out.push_back(a);
    }
  }
  return out;
}

std::vector<double> parse_list(const std::string& option, const std::string& text) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  int k = 0;
  while (std::getline(ss, item, ',')) {
    const size_t b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
    const std::string t = b == std::string::npos ? "" : item.substr(b, e - b + 1);
    char* end = nullptr;
    const double x = t.empty() ? 0.0 : std::strtod(t.c_str(), &end);
    if (t.empty() || *end != '\0' || !std::isfinite(x))
      throw Error(option + ": item " + std::to_string(k + 1) + ": expected a finite number, got '" + t + "'");
    out.push_back(x);
    ++k;
  }
  if (!text.empty() && text.back() == ',') throw Error(option + ": trailing comma in '" + text + "'");
  return out;
}

std::string join(const std::vector<std::string>& items, const std::string& separator) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : separator) + s;
  return out;
}

void add_inspect(CLI::App& app, InspectOptions& o) {
  CLI::App* c = app.add_subcommand(
      "inspect",
      "Print the system mass matrix M(q) (eq. 14), bias(q, qd), qdd for --tau, energy and momentum at one state.\n"
      "MODEL is a .yaml scenario or a .urdf; without --q/--qd the scenario's initial state (zeros for a URDF).");
  c->add_option("MODEL", o.model, "scenario (.yaml) or robot (.urdf)")->required();
  add_state_options(c, o.state, "the state");
  c->add_option("--tau", o.tau, "joint forces for qdd, comma-separated, nv numbers (default zero)");
  c->add_flag("--json", o.json, "print one JSON object on stdout");
  c->add_option("--method", o.method, "forward-dynamics route for qdd: " + join(fd_method_names(), " | ") + " (default on)")
      ->transform(CLI::IsMember(fd_method_names(), CLI::ignore_case));
}

namespace {

VecX vector_option(const std::string& option, const std::string& text, int size, const VecX& fallback) {
  if (text.empty()) return fallback;
  const auto v = parse_list(option, text);
  if (int(v.size()) != size)
    throw Error(option + ": expected " + std::to_string(size) + " numbers, got " + std::to_string(v.size()));
  return Eigen::Map<const VecX>(v.data(), size);
}

std::string short_num(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

std::string num(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

}  // namespace

void add_state_options(CLI::App* c, StateOptions& o, const std::string& what) {
  c->add_option("--q", o.q, "configuration of " + what + ", comma-separated, nq numbers (free root: x,y,z,qw,qx,qy,qz first)");
  c->add_option("--qd", o.qd, "velocities of " + what + ", comma-separated, nv numbers (free root: wx,wy,wz,vx,vy,vz first)");
  c->add_option("--gravity", o.gravity, "gravity gx,gy,gz in m/s^2 (default: the scenario's; 0,0,-9.81 for a URDF)");
  c->add_flag("--free-root", o.free_root, "give a URDF's root link a free joint instead of welding it to the world");
}

std::optional<Vec3> gravity_option(const StateOptions& o) {
  if (o.gravity.empty()) return std::nullopt;
  return Vec3(vector_option("--gravity", o.gravity, 3, Vec3::Zero()));
}

void state_from_options(const Model& m, const StateOptions& o, VecX& q, VecX& v) {
  q = vector_option("--q", o.q, m.nq, q);
  for (int i = 0; i < m.nbodies; ++i)
    if (const int k = joint_traits(m.joint_type[i]).quaternion; k >= 0) {
      const double norm = q.segment<4>(m.idx_q[i] + k).norm();
      if (std::abs(norm - 1.0) > 1e-6)
        throw Error("--q: joint '" + m.joint_names[i] + "': expected a unit quaternion, got norm " + num(norm));
    }
  m.normalize(q);
  v = vector_option("--qd", o.qd, m.nv, v);
  for (const auto& [option, x, names] : {std::tuple{"--q", &q, m.q_names()}, std::tuple{"--qd", &v, m.v_names()}})
    for (Eigen::Index k = 0; k < x->size(); ++k)
      if (std::abs((*x)(k)) > kMaxStateMagnitude)
        throw Error(std::string(option) + ": " + names[size_t(k)] + " = " +
                    short_num((*x)(k)) + ": expected |value| <= " + short_num(kMaxStateMagnitude) + " (m, rad, m/s or rad/s)");
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
  for (Eigen::Index k = 0; k < v.size(); ++k) o += (k ? ", " : "") + num(v(k));
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
};

// q (unit quaternions checked, then normalized), v and τ from the options, then 𝓜, bias and q̈.
Inspection inspect(const Scenario& sc, const InspectOptions& o) {
  const Model& m = sc.model;
  Inspection r;
  r.q = sc.q0;
  r.v = sc.v0;
  state_from_options(m, o.state, r.q, r.v);
  r.tau = vector_option("--tau", o.tau, m.nv, VecX::Zero(m.nv));

  Data d(m);
  update_kinematics(m, d, r.q);
  mass_matrix(m, d);
  r.M = d.Mass;
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
  out += ", \"kinetic_energy\": " + num(r.T) + ", \"potential_energy\": " + num(r.V);
  out += ", \"momentum\": {\"linear\": " + json_array(r.h.linear) + ", \"angular\": " + json_array(r.h.angular) + "}";
  out += ", \"bodies\": [";
  for (int i = 0; i < m.nbodies; ++i)
    out += std::string(i ? ", " : "") + "{\"name\": " + json_string(m.body_names[i]) +
           ", \"position\": " + json_array(r.position.col(i)) + ", \"orientation\": " + json_array(r.orientation.col(i)) +
           ", \"com\": " + json_array(r.com.col(i)) + "}";
  out += "], \"method\": " + json_string(method) + "}";
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
  std::printf("momentum   linear  [% .10g, % .10g, % .10g]\n", r.h.linear.x(), r.h.linear.y(), r.h.linear.z());
  std::printf("           angular [% .10g, % .10g, % .10g] (about the inertial origin)\n", r.h.angular.x(),
              r.h.angular.y(), r.h.angular.z());
}

}  // namespace

int run_inspect(const InspectOptions& o) {
  const Scenario sc = load_scenario(o.model, o.state.free_root, gravity_option(o.state));
  const Inspection r = inspect(sc, o);
  if (o.json) print_json(sc.model, r, o.method);
  else print_tables(sc, r, o.method);
  return 0;
}

}  // namespace soadyn::cli
