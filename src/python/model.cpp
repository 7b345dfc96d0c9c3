// Model, Data, Scenario and their settings and inputs, as Python classes.
#include "common.hpp"

#include "soadyn/sim/integrators.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/multibody/text.hpp"

#include <deque>
#include <optional>

namespace soadyn::python {

// a Word setting's enum as its word (a str), the others as they are
py::object setting_value(const SimulationSettings& s, const SettingInfo& info) {
  return std::visit(
      [&](auto field) -> py::object {
        if constexpr (std::is_same_v<decltype(field), WordField>) return py::str(std::string(field.get(s)));
        else return py::cast(s.*field);
      },
      info.field);
}

// a Word setting from its word (refused, as a scenario refuses it, when it names none of its values)
void set_setting_value(SimulationSettings& s, const SettingInfo& info, const py::handle& value) {
  std::visit(
      [&](auto field) {
        if constexpr (std::is_same_v<decltype(field), WordField>) {
          set_setting(s, info, value.cast<std::string>());
        } else {
          using T = std::decay_t<decltype(s.*field)>;
          s.*field = value.cast<T>();
        }
      },
      info.field);
}


namespace {

template <class V>
py::array rows3(const std::vector<V>& vs) {  // N 3-vectors as an N×3 array
  std::vector<double> out;
  for (const auto& v : vs) out.insert(out.end(), v.data(), v.data() + 3);
  return owned(std::move(out), {py::ssize_t(vs.size()), 3});
}

py::array mats3(const std::vector<Mat3>& ms) {  // N 3×3 matrices as an N×3×3 array (row-major)
  std::vector<double> out;
  for (const auto& a : ms)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) out.push_back(a(r, c));
  return owned(std::move(out), {py::ssize_t(ms.size()), 3, 3});
}

std::optional<Vec3> gravity_arg(const std::optional<ArrayIn>& g) {
  if (!g) return std::nullopt;
  return Vec3(read_vector("load", "gravity", *g, 3));
}

// 'warn' | 'balance' | 'strict' → InertiaCheck (None: the file's); ValueError otherwise
std::optional<InertiaCheck> inertia_check_arg(const std::optional<std::string>& s) {
  if (!s) return std::nullopt;
  if (const auto c = parse_inertia_check(*s)) return c;
  throw py::value_error("inertia_check: expected 'warn', 'balance' or 'strict', got '" + *s + "'" +
                        did_you_mean(*s, {"warn", "balance", "strict"}));
}

// the model's build warnings as Python UserWarnings (an error when warnings are errors)
const Model& warned(const Model& model) {
  for (const std::string& w : model.warnings)
    if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 2) < 0) throw py::error_already_set();
  return model;
}

// a derivative view of a Data (its derivative arrays made on first use, zero until filled)
py::array derivative_view(PyData& self, py::array PyData::*view) {
  self.derivative_data(self.model.cast<const Model&>());
  return self.*view;
}

}  // namespace

namespace {

// the library's registries, as tuples of the names users write
void bind_registries(py::module_& m) {
  py::list joints, methods, routes;
  for (const auto& t : joint_traits_table()) joints.append(std::string(t.name));
  for (const auto& n : integrator_names()) methods.append(n);
  for (const auto& n : fd_method_names()) routes.append(n);
  m.attr("JOINT_TYPES") = py::tuple(joints);
  m.attr("METHODS") = py::tuple(methods);
  m.attr("DYNAMICS") = py::tuple(routes);
}

// Model: its sizes, names and mass properties
void bind_model_class(py::module_& m) {
  py::class_<Model> model(m, "Model", R"(The constant tree: parents in parent-first order, joints, placements and mass properties.

Built once (soadyn.load, soadyn.load_scenario, Model.build) and never changed by an algorithm;
every per-state array lives in a Data (model.create_data()).  One Model may serve any number of
Data, e.g. one per thread.

Coordinates: q has nq entries, v (the note's q̇: rates, with ω instead of the quaternion's rate
for a free joint) has nv.  Free joint: q = [x, y, z, qw, qx, qy, qz] (body frame position, unit
quaternion body → inertial), v = [ωx, ωy, ωz, vx, vy, vz] in inertial coordinates.)");
  model
      .def_readonly("nq", &Model::nq, "configuration size")
      .def_readonly("nv", &Model::nv, "velocity size (degrees of freedom)")
      .def_readonly("nbodies", &Model::nbodies, "N, the moving bodies (fixed joints merged)")
      .def_readonly("lower", &Model::lower, "each DOF's lower limit, rad or m (-inf: none)")
      .def_readonly("upper", &Model::upper, "each DOF's upper limit, rad or m (inf: none)")
      .def_readonly("body_names", &Model::body_names, "name of each body, parent-first order (N)")
      .def_readonly("warnings", &Model::warnings,
                    "what building the model accepted but a user should hear (one line each; also issued as UserWarning by load)")
      .def_readonly("joint_names", &Model::joint_names, "name of the joint moving each body (N)")
      .def_readonly("parents", &Model::parent, "parent(i) < i of each body, -1 for the ground (N)")
      .def_readonly("idx_q", &Model::idx_q, "first q index of each body's joint (N)")
      .def_readonly("idx_v", &Model::idx_v, "first v index of each body's joint (N)")
      .def_readonly("depth", &Model::depth, "longest chain from the ground (nilpotency of Φ_D)")
      .def_property_readonly("joint_types", [](const Model& self) {
            std::vector<std::string> out;
            for (auto t : self.joint_type) out.emplace_back(to_string(t));
            return out;
          }, "type of each body's joint, one of soadyn.JOINT_TYPES (N)")
      .def_property_readonly("q_names", &Model::q_names,
                             "label of each q entry: the joint's name, 'root.qw' etc. for multi-coordinate joints (nq)")
      .def_property_readonly("v_names", &Model::v_names, "label of each v entry (nv)")
      .def_property_readonly("gravity", [](const Model& self) { return owned(VecX(self.gravity)); },
                             "uniform gravity, m/s², shape (3,)")
      .def_property_readonly("masses", [](const Model& self) { return owned(VecX(Eigen::Map<const VecX>(self.mass.data(), self.nbodies))); },
                             "mass of each body, kg, shape (N,) (welded bodies merged in)")
      .def_property_readonly("coms", [](const Model& self) { return rows3(self.com); },
                             "centre of mass of each body in its body frame, shape (N, 3)")
      .def_property_readonly("inertias", [](const Model& self) { return mats3(self.inertia); },
                             "inertia about each body's centre of mass, body frame, shape (N, 3, 3)")
      .def_property_readonly("axes", [](const Model& self) { return rows3(self.axis); },
                             "unit joint axis of each body in its joint frame, shape (N, 3)")
      .def_property_readonly("pitches", [](const Model& self) { return owned(VecX(Eigen::Map<const VecX>(self.pitch.data(), self.nbodies))); },
                             "each body's helical-joint pitch, m/rad (0 for the other joint types), shape (N,)");
}

// Model: Data, configurations and names to indices
void bind_model_methods(py::module_& m) {
  auto model = py::reinterpret_borrow<py::class_<Model>>(m.attr("Model"));
  model
      .def("create_data", [](const py::object& self) {
            PyData d(self.cast<const Model&>());
            d.model = self;
            return d;
          },
           "A Data sized for this model: the per-state arrays every algorithm fills (allocated once).")
      .def("neutral", [](const Model& self) { return owned(self.neutral_configuration()); },
           "The neutral configuration: zero angles and displacements, identity quaternions; shape (nq,).")
      .def("normalize", [](const Model& self, const ArrayIn& q) {
            VecX out = read_vector("Model.normalize", "q", q, self.nq);
            self.normalize(out);
            return owned(std::move(out));
          }, "q"_a, "q with each free joint's quaternion scaled to unit norm (a new array, shape (nq,)).")
      .def("integrate", [](const Model& self, const ArrayIn& q, const ArrayIn& v, double h) {
            return owned(self.integrate(read_vector("Model.integrate", "q", q, self.nq),
                                        read_vector("Model.integrate", "v", v, self.nv), h));
          }, "q"_a, "v"_a, "h"_a,
          "q ⊕ h v: exact for revolute and prismatic joints; a free joint moves its position by h η̇ and\n"
          "turns its attitude by exp(h ω) about inertial axes.  Returns a new array, shape (nq,).")
      .def("qdot", [](const Model& self, const ArrayIn& q, const ArrayIn& v) {
            VecX qd(self.nq);
            self.qdot(read_vector("Model.qdot", "q", q, self.nq), read_vector("Model.qdot", "v", v, self.nv), qd);
            return owned(std::move(qd));
          }, "q"_a, "v"_a, "q̇ from (q, v): differs from v only for a free joint's quaternion rate; shape (nq,).")
      .def("velocity", [](const Model& self, const ArrayIn& q, const ArrayIn& qd) {
            return owned(self.velocity(read_vector("Model.velocity", "q", q, self.nq),
                                       read_vector("Model.velocity", "qd", qd, self.nq)));
          }, "q"_a, "qd"_a, "The reverse map: v from q̇ (ω = 2 quaṫ ⊗ quat* for a free joint); shape (nv,).")
      .def("body_index", [](const Model& self, const std::string& name) {
            const int i = self.body_index(name);
            if (i < 0) throw py::key_error("no body named '" + printable(name) + "'" + did_you_mean(name, self.body_names));
            return i;
          }, "name"_a, "index of the named body; KeyError (with the nearest name) when absent")
      .def("joint_index", [](const Model& self, const std::string& name) {
            const int i = self.joint_index(name);
            if (i < 0) throw py::key_error("no joint named '" + printable(name) + "'" + did_you_mean(name, self.joint_names));
            return i;
          }, "name"_a, "index of the body the named joint moves; KeyError (with the nearest name) when absent")
      .def("__repr__", [](const Model& self) {
        return "<soadyn.Model: " + std::to_string(self.nbodies) + " bodies, nq = " + std::to_string(self.nq) +
               ", nv = " + std::to_string(self.nv) + ">";
      });
}

// Data, with its results as NumPy views
void bind_data(py::module_& m) {
  py::class_<PyData>(m, "Data", R"(The per-state arrays of one Model, allocated once (model.create_data()).

The algorithms fill it and return read-only views of it (no copy), each array one function's
own: mass_matrix → data.M, bias_forces → data.bias, inverse_dynamics → data.tau, forward_dynamics →
data.qdd, inverse_dynamics_derivatives → (data.dtau_dq, data.dtau_dv), forward_dynamics_derivatives
→ (data.dqdd_dq, data.dqdd_dv, data.dqdd_dtau), minverse → data.Minv (the derivative arrays, nv×nv
each, made by the first call that needs them).  A returned view changes only when its own function
is called again on the same Data (copy it to keep it); it keeps the memory alive after the Data
object is gone.  Kinematics (filled by every algorithm that takes q), one row per
body, inertial coordinates: R (N, 3, 3) body → inertial, eta (N, 3) joint points η_i,
d (N, 3) d_i = η_i − η_parent(i), s (N, 3) s_i = r_i − η_i, r (N, 3) centres of mass,
G (6, nv) the columns of the joint maps G_i; V (N, 6) v_i = [ω_i; η̇_i] and Vbar (N, 6)
v̄_i = [ω_i; ṙ_i] (filled by the algorithms that take v).  Not shared between threads.)")
      .def(py::init([](const py::object& model) {
             PyData d(model.cast<const Model&>());
             d.model = model;
             return d;
           }), "model"_a)
      .def_readonly("M", &PyData::M, "𝓜(q), shape (nv, nv): filled by mass_matrix")
      .def_readonly("bias", &PyData::bias, "bias(q, q̇), shape (nv,): filled by bias_forces")
      .def_readonly("tau", &PyData::tau, "inverse-dynamics result τ, shape (nv,)")
      .def_readonly("qdd", &PyData::qdd, "forward-dynamics result q̈, shape (nv,)")
      .def_readonly("R", &PyData::R, "C_i^in, body i frame → inertial, shape (N, 3, 3)")
      .def_readonly("eta", &PyData::eta, "η_i, joint point (body frame origin), shape (N, 3)")
      .def_readonly("d", &PyData::d, "d_i = η_i − η_parent(i) (η_i at a root), shape (N, 3)")
      .def_readonly("s", &PyData::s, "s_i = r_i − η_i, joint point to centre of mass, shape (N, 3)")
      .def_readonly("r", &PyData::r, "r_i, centre of mass, shape (N, 3)")
      .def_readonly("G", &PyData::G, "column k: the motion vector of DOF k, [g; 0] or [0; g], shape (6, nv)")
      .def_readonly("V", &PyData::V, "v_i = [ω_i; η̇_i] (eq. 4), shape (N, 6)")
      .def_property_readonly("dtau_dq", [](PyData& self) { return derivative_view(self, &PyData::dtau_dq); },
                             "∂τ/∂q (tangent) of inverse dynamics, shape (nv, nv): filled by inverse_dynamics_derivatives")
      .def_property_readonly("dtau_dv", [](PyData& self) { return derivative_view(self, &PyData::dtau_dv); },
                             "∂τ/∂v of inverse dynamics, shape (nv, nv): filled by inverse_dynamics_derivatives")
      .def_property_readonly("dqdd_dq", [](PyData& self) { return derivative_view(self, &PyData::dqdd_dq); },
                             "∂q̈/∂q (tangent) of forward dynamics, shape (nv, nv): filled by forward_dynamics_derivatives")
      .def_property_readonly("dqdd_dv", [](PyData& self) { return derivative_view(self, &PyData::dqdd_dv); },
                             "∂q̈/∂v of forward dynamics, shape (nv, nv): filled by forward_dynamics_derivatives")
      .def_property_readonly("dqdd_dtau", [](PyData& self) { return derivative_view(self, &PyData::dqdd_dtau); },
                             "∂q̈/∂τ = 𝓜⁻¹, shape (nv, nv): filled by forward_dynamics_derivatives")
      .def_property_readonly("Minv", [](PyData& self) { return derivative_view(self, &PyData::Minv); },
                             "𝓜⁻¹, shape (nv, nv): filled by minverse")
      .def_readonly("Vbar", &PyData::Vbar, "v̄_i = [ω_i; ṙ_i] (eq. 5), shape (N, 6)")
      .def("__repr__", [](const PyData& self) {
        return "<soadyn.Data: " + std::to_string(self.nbodies) + " bodies, nq = " + std::to_string(self.nq) +
               ", nv = " + std::to_string(self.nv) + ">";
      });
}

// SimulationSettings: one attribute per setting of the table
void bind_settings(py::module_& m) {
  py::class_<SimulationSettings> settings(m, "SimulationSettings", "A scenario's 'simulation' section (scenarios/README.md).");
  settings.def(py::init<>());
  // one attribute per setting of the table (settings.hpp): its name, its help and unit
  static std::deque<std::string> docs;  // the texts the properties point to, for the module's life
  for (const SettingInfo& info : setting_table()) {
    std::string& doc = docs.emplace_back(info.help);
    if (info.kind == SettingKind::Word) {
      const std::vector<std::string> words = info.words();
      for (size_t k = 0; k < words.size(); ++k) doc += (k == 0 ? ": " : " | ") + words[k];
    } else if (!info.unit.empty() && info.unit != "1") {
      doc += ", " + std::string(info.unit);
    }
    settings.def_property(
        info.name.data(), [&info](const SimulationSettings& s) { return setting_value(s, info); },
        [&info](SimulationSettings& s, const py::object& value) { set_setting_value(s, info, value); }, doc.c_str());
  }
  settings.def_property_readonly_static(
      "names",
      [](const py::object&) {
        py::list out;
        for (const SettingInfo& info : setting_table()) out.append(std::string(info.name));
        return py::tuple(out);
      },
      "the settings' names, in the table's order (sensitivities apart)");
  settings.def_property_readonly_static(
      "integration_names",
      [](const py::object&) {
        py::list out;
        for (const SettingInfo& info : setting_table())
          if (info.integration) out.append(std::string(info.name));
        return py::tuple(out);
      },
      "the names of the settings that say how the equations are integrated (method, tolerances, steps, "
      "routes): what a sweep's reference run may set");
  settings.def_property_readonly_static(
      "words",
      [](const py::object&) {
        py::dict out;
        for (const SettingInfo& info : setting_table())
          if (info.kind == SettingKind::Word) out[py::str(std::string(info.name))] = py::tuple(py::cast(info.words()));
        return out;
      },
      "each word-valued setting's words, {name: (word, ...)} (an older word, dynamics' on, is taken too)");
  settings
      .def_property(
          "sensitivities",
          [](const SimulationSettings& s) {
            return py::dict("initial_state"_a = s.sensitivities.initial_state, "parameters"_a = s.sensitivities.parameters);
          },
          [](SimulationSettings& s, const py::object& value) {
            SensitivitySettings out;
            if (!value.is_none()) {
              const py::dict d = value.cast<py::dict>();
              for (const auto& [k, v] : d) {
                const std::string key = py::str(k);
                if (key == "initial_state") out.initial_state = v.cast<bool>();
                else if (key == "parameters" && py::isinstance<py::str>(v)) {
                  if (v.cast<std::string>() != "all")
                    throw Error("sensitivities: parameters: expected a list of body names or 'all', got '" + v.cast<std::string>() + "'");
                  out.parameters = {"all"};
                } else if (key == "parameters")
                  out.parameters = v.cast<std::vector<std::string>>();
                else
                  throw Error("sensitivities: unknown key '" + key + "'" + did_you_mean(key, {"initial_state", "parameters"}));
              }
            }
            s.sensitivities = out;
          },
          "forward sensitivities (CVODES): {'initial_state': bool, 'parameters': [body, ...] or 'all'}")
      .def("__repr__", [](const SimulationSettings& s) {
        return "SimulationSettings(method='" + std::string(to_string(s.method)) + "', t_end=" + py::repr(py::float_(s.t_end)).cast<std::string>() +
               ", output_dt=" + py::repr(py::float_(s.output_dt)).cast<std::string>() +
               ", rtol=" + py::repr(py::float_(s.rtol)).cast<std::string>() + ", atol=" +
               py::repr(py::float_(s.atol)).cast<std::string>() + ", dt=" + py::repr(py::float_(s.dt)).cast<std::string>() +
               ", dynamics='" + std::string(to_string(s.dynamics)) + "')";
      });
}

// Inputs and Scenario
void bind_scenario(py::module_& m) {
  py::class_<Inputs>(m, "Inputs", "A scenario's joint inputs: torques, springs and dampers.")
      .def_property_readonly("torques", [](const Inputs& in) {
            py::list out;
            for (const auto& t : in.torques)
              out.append(py::dict("joint"_a = t.joint, "dof"_a = t.dof, "constant"_a = t.constant,
                                  "amplitude"_a = t.amplitude, "frequency"_a = t.frequency, "phase"_a = t.phase));
            return out;
          }, "τ = constant + amplitude·sin(2π frequency t + phase) on one DOF, as dicts")
      .def_property_readonly("springs", [](const Inputs& in) {
            py::list out;
            for (const auto& s : in.springs)
              out.append(py::dict("joint"_a = s.joint, "dof"_a = s.dof, "coord"_a = s.coord, "stiffness"_a = s.stiffness,
                                  "rest"_a = s.rest));
            return out;
          }, "τ = −stiffness (q − rest) on one DOF, as dicts")
      .def_property_readonly("dampers", [](const Inputs& in) {
            py::list out;
            for (const auto& d : in.dampers) out.append(py::dict("joint"_a = d.joint, "dof"_a = d.dof, "damping"_a = d.damping));
            return out;
          }, "τ = −damping q̇ on one DOF, as dicts")
      .def("evaluate", [](const Inputs& in, double t, const ArrayIn& q, const ArrayIn& v) {
            const VecX qv = read_vector("Inputs.evaluate", "q", q, int(q.size())), vv = read_vector("Inputs.evaluate", "v", v, int(v.size()));
            for (const auto& s : in.springs)
              if (s.coord >= qv.size()) throw Error("Inputs.evaluate: q: too short for the spring on '" + s.joint + "'");
            for (const auto& t : in.torques)
              if (t.dof >= vv.size()) throw Error("Inputs.evaluate: v: too short for the torque on '" + t.joint + "'");
            for (const auto& d : in.dampers)
              if (d.dof >= vv.size()) throw Error("Inputs.evaluate: v: too short for the damper on '" + d.joint + "'");
            VecX tau = VecX::Zero(vv.size());
            in.evaluate(t, qv, vv, tau);
            return owned(std::move(tau));
          }, "t"_a, "q"_a, "v"_a, "τ(t, q, v), the generalized force the inputs apply, shape (nv,)")
      .def("spring_energy", [](const Inputs& in, const ArrayIn& q) {
            const VecX qv = read_vector("Inputs.spring_energy", "q", q, int(q.size()));
            for (const auto& s : in.springs)
              if (s.coord >= qv.size()) throw Error("Inputs.spring_energy: q: too short for the spring on '" + s.joint + "'");
            return in.spring_energy(qv);
          }, "q"_a, "the springs' potential energy ½ k (q − rest)², J")
      .def("__len__", [](const Inputs& in) { return in.torques.size() + in.springs.size() + in.dampers.size(); });

  py::class_<Scenario>(m, "Scenario", R"(A scenario file: the model, the initial state, the inputs and the simulation settings.

Fields: model, q0 (nq,), v0 (nv,), inputs, settings, name, description, path, text (the file's
full text).  q0 and v0 may be assigned (size-checked); settings is changed in place.)")
      .def_property_readonly("model", [](const Scenario& s) -> const Model& { return s.model; },
                             py::return_value_policy::reference_internal, "the scene's Model")
      .def_property("q0", [](const Scenario& s) { return owned(VecX(s.q0)); },
                    [](Scenario& s, const ArrayIn& q) {
                      VecX v = read_vector("Scenario.q0", "q0", q, s.model.nq);
                      s.model.check_unit_quaternions(v, "Scenario.q0");
                      s.model.normalize(v);
                      s.q0 = v;
                    }, "initial configuration, shape (nq,) (quaternions within 1e-6 of unit norm, then normalized; others "
                       "refused)")
      .def_property("v0", [](const Scenario& s) { return owned(VecX(s.v0)); },
                    [](Scenario& s, const ArrayIn& v) { s.v0 = read_vector("Scenario.v0", "v0", v, s.model.nv); },
                    "initial velocity, shape (nv,)")
      .def_property_readonly("inputs", [](const Scenario& s) -> const Inputs& { return s.inputs; },
                             py::return_value_policy::reference_internal, "the joint inputs")
      .def_property("settings", [](Scenario& s) -> SimulationSettings& { return s.simulation; },
                    [](Scenario& s, const SimulationSettings& v) { s.simulation = v; },
                    py::return_value_policy::reference_internal, "the simulation settings (a live reference)")
      .def_readonly("name", &Scenario::name)
      .def_readonly("description", &Scenario::description)
      .def_readonly("path", &Scenario::path)
      .def_readonly("text", &Scenario::text)
      .def("__repr__", [](const Scenario& s) {
        return "<soadyn.Scenario '" + s.name + "' from " + s.path + ": " + std::to_string(s.model.nbodies) +
               " bodies, nq = " + std::to_string(s.model.nq) + ", nv = " + std::to_string(s.model.nv) + ">";
      });
}

// load, load_scenario, parse_scenario
void bind_loaders(py::module_& m) {
  m.def("load", [](const std::string& path, bool free_root, const std::optional<ArrayIn>& gravity,
                   const std::optional<std::string>& inertia_check) {
        return warned(load_scenario(path, free_root, gravity_arg(gravity), inertia_check_arg(inertia_check)).model);
      }, "path"_a, "free_root"_a = false, "gravity"_a = py::none(), "inertia_check"_a = py::none(),
      R"(Load a Model from a URDF (.urdf) or a scenario (.yaml).

free_root: give a URDF's root link a free joint instead of welding it to the world.
gravity: (3,) m/s², overrides the file's (a URDF's default is (0, 0, −9.81)).
inertia_check: 'warn' (default: inertias breaking the triangle inequality by at most 5 % load
  with a UserWarning, the rest are refused), 'balance' (made physical) or 'strict' (refused);
  overrides a scenario's inertia_check.
Raises soadyn.Error naming the file, line and field of any mistake.)");
  m.def("load_scenario", [](const std::string& path, bool free_root, const std::optional<ArrayIn>& gravity,
                            const std::optional<std::string>& inertia_check) {
        Scenario sc = load_scenario(path, free_root, gravity_arg(gravity), inertia_check_arg(inertia_check));
        warned(sc.model);
        return sc;
      }, "path"_a, "free_root"_a = false, "gravity"_a = py::none(), "inertia_check"_a = py::none(),
      "Load a Scenario (.yaml; a .urdf gives zero initial state, default settings and no inputs).\n"
      "free_root, gravity and inertia_check as for load().");
  m.def("parse_scenario", [](const std::string& text, const std::string& path, const std::optional<std::string>& inertia_check) {
        Scenario sc = parse_scenario(text, path, false, inertia_check_arg(inertia_check));
        warned(sc.model);
        return sc;
      },
        "text"_a, "path"_a = "<string>", "inertia_check"_a = py::none(),
        "A Scenario from YAML text; path names it in messages and anchors a relative 'urdf:'.");
}

}  // namespace

void bind_model(py::module_& m) {
  bind_registries(m);
  bind_model_class(m);
  bind_model_methods(m);
  bind_data(m);
  bind_settings(m);
  bind_scenario(m);
  bind_loaders(m);
}

}  // namespace soadyn::python
