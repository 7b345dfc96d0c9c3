#include "cli.hpp"

#include "soadyn/algorithms.hpp"
#include "soadyn/kinematics.hpp"
#include "soadyn/scenario.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>

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

void add_inspect(CLI::App& app, InspectOptions& o) {
  CLI::App* c = app.add_subcommand(
      "inspect",
      "Print the system mass matrix M(q) (eq. 14), bias(q, qd), qdd for --tau, energy and momentum at one state.\n"
      "MODEL is a .yaml scenario or a .urdf; without --q/--qd the scenario's initial state (zeros for a URDF).");
  c->add_option("MODEL", o.model, "scenario (.yaml) or robot (.urdf)")->required();
  c->add_option("--q", o.q, "configuration, comma-separated, nq numbers (free root: x,y,z,qw,qx,qy,qz first)");
  c->add_option("--qd", o.qd, "velocities, comma-separated, nv numbers (free root: wx,wy,wz,vx,vy,vz first)");
  c->add_option("--tau", o.tau, "joint forces for qdd, comma-separated, nv numbers (default zero)");
  c->add_option("--gravity", o.gravity, "gravity gx,gy,gz in m/s^2 (default: the scenario's; 0,0,-9.81 for a URDF)");
  c->add_flag("--free-root", o.free_root, "give a URDF's root link a free joint instead of welding it to the world");
  c->add_flag("--json", o.json, "print one JSON object on stdout");
  c->add_option("--method", o.method, "forward-dynamics route for qdd: dense | sparse | on (default on)")
      ->check(CLI::IsMember({"dense", "sparse", "on"}));
}

namespace {

VecX vector_option(const std::string& option, const std::string& text, int size, const VecX& fallback) {
  if (text.empty()) return fallback;
  const auto v = parse_list(option, text);
  if (int(v.size()) != size)
    throw Error(option + ": expected " + std::to_string(size) + " numbers, got " + std::to_string(v.size()));
  return Eigen::Map<const VecX>(v.data(), size);
}

std::string num(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

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
  for (Eigen::Index k = 0; k < v.size(); ++k) std::printf("  %-24s % .10e\n", labels[k].c_str(), v(k));
}

}  // namespace

int run_inspect(const InspectOptions& o) {
  std::optional<Vec3> gravity;
  if (!o.gravity.empty()) gravity = vector_option("--gravity", o.gravity, 3, Vec3::Zero());
  const Scenario sc = load_scenario(o.model, o.free_root, gravity);
  const Model& m = sc.model;
  VecX q = vector_option("--q", o.q, m.nq, sc.q0);
  for (int i = 0; i < m.nbodies; ++i)
    if (m.joint_type[i] == JointType::Free) {
      const double norm = q.segment<4>(m.idx_q[i] + 3).norm();
      if (std::abs(norm - 1.0) > 1e-6)
        throw Error("--q: joint '" + m.joint_names[i] + "': expected a unit quaternion, got norm " + num(norm));
    }
  m.normalize(q);
  const VecX v = vector_option("--qd", o.qd, m.nv, sc.v0);
  const VecX tau = vector_option("--tau", o.tau, m.nv, VecX::Zero(m.nv));

  Data d(m);
  update_kinematics(m, d, q);
  mass_matrix(m, d);
  const MatX M = d.Mass;
  update_velocities(m, d, v);
  bias_forces(m, d);
  const VecX bias = d.bias;
  forward_dynamics(m, d, tau, parse_fd_method(o.method));
  const double T = kinetic_energy(m, d), V = potential_energy(m, d);
  const Momentum h = momentum(m, d);

  // labels of the q and v entries
  std::vector<std::string> qlab, vlab;
  for (int i = 0; i < m.nbodies; ++i) {
    const std::string& j = m.joint_names[i];
    if (m.joint_type[i] == JointType::Free) {
      for (const char* c : {"x", "y", "z", "qw", "qx", "qy", "qz"}) qlab.push_back(j + "." + c);
      for (const char* c : {"wx", "wy", "wz", "vx", "vy", "vz"}) vlab.push_back(j + "." + c);
    } else {
      qlab.push_back(j);
      vlab.push_back(j);
    }
  }

  if (o.json) {
    std::string out = "{\"joints\": [";
    for (int i = 0; i < m.nbodies; ++i) out += (i ? ", " : "") + json_string(m.joint_names[i]);
    out += "], \"nq\": " + std::to_string(m.nq) + ", \"nv\": " + std::to_string(m.nv);
    out += ", \"q\": " + json_array(q) + ", \"qd\": " + json_array(v) + ", \"gravity\": " + json_array(m.gravity);
    out += ", \"M\": [";
    for (int r = 0; r < m.nv; ++r) out += (r ? ", " : "") + json_array(VecX(M.row(r).transpose()));
    out += "], \"bias\": " + json_array(bias) + ", \"tau\": " + json_array(tau) + ", \"qdd\": " + json_array(d.qdd);
    out += ", \"kinetic_energy\": " + num(T) + ", \"potential_energy\": " + num(V);
    out += ", \"momentum\": {\"linear\": " + json_array(h.linear) + ", \"angular\": " + json_array(h.angular) + "}";
    out += ", \"method\": " + json_string(o.method) + "}";
    std::cout << out << std::endl;
    return 0;
  }

  std::printf("model      %s (%d bodies, nq = %d, nv = %d)\n", sc.path.c_str(), m.nbodies, m.nq, m.nv);
  std::printf("gravity    [% g, % g, % g] m/s^2\n", m.gravity.x(), m.gravity.y(), m.gravity.z());
  std::printf("%-4s %-20s %-20s %-10s %s\n", "#", "body", "joint", "type", "parent");
  for (int i = 0; i < m.nbodies; ++i)
    std::printf("%-4d %-20s %-20s %-10s %s\n", i, m.body_names[i].c_str(), m.joint_names[i].c_str(),
                std::string(to_string(m.joint_type[i])).c_str(),
                m.parent[i] < 0 ? "world" : m.body_names[m.parent[i]].c_str());
  print_vector("q", qlab, q);
  print_vector("qd", vlab, v);
  std::printf("mass matrix M(q) (%d x %d)\n", m.nv, m.nv);
  for (int r = 0; r < m.nv; ++r) {
    std::printf("  %-24s", vlab[r].c_str());
    for (int c = 0; c < m.nv; ++c) std::printf(" % .6e", M(r, c));
    std::printf("\n");
  }
  print_vector("bias(q, qd) (Coriolis, centrifugal, gyroscopic, gravity)", vlab, bias);
  print_vector("tau", vlab, tau);
  print_vector("qdd = M^-1 (tau - bias)  [" + o.method + "]", vlab, d.qdd);
  std::printf("energy     kinetic % .10e   potential % .10e   total % .10e J\n", T, V, T + V);
  std::printf("momentum   linear  [% .6e, % .6e, % .6e]\n", h.linear.x(), h.linear.y(), h.linear.z());
  std::printf("           angular [% .6e, % .6e, % .6e] (about the inertial origin)\n", h.angular.x(), h.angular.y(),
              h.angular.z());
  return 0;
}

}  // namespace soadyn::cli
