// Scenario files (YAML) and URDF import.
//
// A scenario states only what its scene has: bodies (or a URDF), gravity, an initial state,
// and, when the scene needs them, simulation settings and inputs.  Everything else has a
// documented default (README, "Scenario files").  Every mistake is reported as
// `file:line:column: field: message` through soadyn::Error.
#pragma once

#include "soadyn/model.hpp"

#include <optional>
#include <string>
#include <vector>

namespace soadyn {

// Joint inputs a scene may need, and no more.  Each acts on one 1-DOF joint (index into v).
struct TorqueInput {
  std::string joint;
  int dof = -1;
  double constant = 0.0;   // N·m or N
  double amplitude = 0.0;  // + amplitude · sin(2π frequency t + phase)
  double frequency = 0.0;  // Hz
  double phase = 0.0;      // rad
};
struct SpringInput {
  std::string joint;
  int dof = -1;
  int coord = -1;          // index into q
  double stiffness = 0.0;  // τ = −k (q − rest)
  double rest = 0.0;
};
struct DamperInput {
  std::string joint;
  int dof = -1;
  double damping = 0.0;    // τ = −c q̇
};

struct Inputs {
  std::vector<TorqueInput> torques;
  std::vector<SpringInput> springs;
  std::vector<DamperInput> dampers;
  bool empty() const { return torques.empty() && springs.empty() && dampers.empty(); }
  // τ(t, q, v): the generalized force the inputs apply
  void evaluate(double t, const VecX& q, const VecX& v, Eigen::Ref<VecX> tau) const;
  // the inputs' potential energy (springs), so E = T + V_gravity + V_springs is conserved
  double spring_energy(const VecX& q) const;
};

struct SimulationSettings {
  double t_end = 10.0;                 // s
  double output_dt = 0.01;             // s between logged samples
  std::string method = "cvode-adams";  // cvode-adams | cvode-bdf | rk4 | euler | symplectic-euler | implicit-midpoint
  double rtol = 1e-8;                  // CVODE relative tolerance
  double atol = 1e-10;                 // CVODE absolute tolerance
  double dt = 1e-3;                    // fixed-step methods' step, s
  double max_step = 0.0;               // CVODE maximum step, s (0: none)
  long max_steps = 100000000;          // CVODE steps allowed in the whole run
  std::string dynamics = "on";         // forward-dynamics route: dense | sparse | on
};

struct Scenario {
  std::string path;   // file it came from
  std::string text;   // its full text, stored with every run
  std::string name;
  std::string description;
  Model model;
  VecX q0, v0;        // initial state (neutral and zero where the file is silent)
  SimulationSettings simulation;
  Inputs inputs;
};

// Loads a .yaml scenario or a .urdf (then: zero initial state, default settings, no inputs).
// `gravity` overrides the file's gravity; for a URDF the default is (0, 0, −9.81).
Scenario load_scenario(const std::string& path, bool free_root = false,
                       const std::optional<Vec3>& gravity = std::nullopt);

// Parses scenario text; `path` names it in messages and anchors a relative `urdf:`.
Scenario parse_scenario(const std::string& text, const std::string& path, bool free_root = false);

// URDF import.  Fixed joints are merged; the root link is welded to the world unless the URDF
// has a floating joint or free_root is set.
Model load_urdf(const std::string& path, bool free_root, const Vec3& gravity);
Model parse_urdf(const std::string& xml, const std::string& path, bool free_root, const Vec3& gravity);

std::string read_text_file(const std::string& path);  // throws soadyn::Error naming the file

}  // namespace soadyn
