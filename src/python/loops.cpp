// Closed loops from Python (loops.hpp): a scene's loops' row names and units, and forward and
// inverse dynamics of the tree closed by them.  The loops are the scene's (its `loops:`), the
// model its model; each call makes its own Data (a few allocations: these are not the calls made
// in tight loops).
#include "common.hpp"

#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/algorithm/loops.hpp"
#include "soadyn/multibody/text.hpp"
#include "soadyn/sim/scenario.hpp"

#include <algorithm>

namespace soadyn::python {

namespace {

// the scene's loops, refused when it has none
const std::vector<LoopConstraint>& loops_of(const Scenario& sc, const char* where) {
  if (sc.inputs.loops.empty())
    throw Error(std::string(where) + ": scene '" + sc.name + "' has no closed loops (a scenario's loops:)");
  return sc.inputs.loops;
}

// the DOFs `actuated` names: joint names (each of the joint's DOFs) or DOF indices
std::vector<int> actuated_dofs(const Model& m, const py::iterable& actuated) {
  std::vector<int> out;
  for (const py::handle h : actuated) {
    if (py::isinstance<py::str>(h)) {
      const std::string name = h.cast<std::string>();
      const int i = m.joint_index(name);
      if (i < 0) throw py::key_error("no joint named '" + printable(name) + "'" + did_you_mean(name, m.joint_names));
      for (int k = m.idx_v[i]; k < m.idx_v[i] + m.nv_i[i]; ++k) out.push_back(k);
    } else if (py::isinstance<py::int_>(h) && !py::isinstance<py::bool_>(h)) {
      const long k = h.cast<long>();
      if (k < 0 || k >= m.nv)
        throw Error("loop_inverse_dynamics: actuated: expected DOF indices 0.." + std::to_string(m.nv - 1) + ", got " +
                    std::to_string(k));
      out.push_back(int(k));
    } else {
      throw py::type_error("loop_inverse_dynamics: actuated: expected joint names or DOF indices, got " +
                           std::string(py::str(py::type::handle_of(h).attr("__name__"))));
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// what both bindings begin with: the scene's loops (refused without any), then (q, v) checked and
// the kinematics and velocities there, and the loops' workspace
struct LoopCall {
  const Model& model;
  const std::vector<LoopConstraint>& loops;
  Data d;
  VecX q, v;
  LoopData ld;
  LoopCall(const Scenario& sc, const char* where, const ArrayIn& q_in, const ArrayIn& v_in)
      : model(sc.model), loops(loops_of(sc, where)), d(model), ld(model, loops) {
    q = read_vector(where, "q", q_in, model.nq);
    model.check_unit_quaternions(q, where);
    v = read_vector(where, "v", v_in, model.nv);
    update_kinematics(model, d, q);
    update_velocities(model, d, v);
  }
};

}  // namespace

void bind_loops(py::module_& m) {
  auto scenario = py::reinterpret_borrow<py::class_<Scenario>>(m.attr("Scenario"));
  scenario.def_property_readonly("loop_rows", [](const Scenario& s) { return loop_row_names(s.inputs.loops); },
                                 "the names of the loops' constraint rows, '<loop>.<part>' (λ's entries; [] without loops)");
  scenario.def_property_readonly("loop_units", [](const Scenario& s) { return loop_row_units(s.inputs.loops); },
                                 "the unit of each row's force λ: 'N' or 'N m'");

  m.def("loop_forward_dynamics", [](const Scenario& sc, const ArrayIn& q_in, const ArrayIn& v_in, const std::optional<ArrayIn>& tau_in) {
        const char* where = "loop_forward_dynamics";
        LoopCall c(sc, where, q_in, v_in);
        const VecX tau = tau_in ? read_vector(where, "tau", *tau_in, c.model.nv) : VecX::Zero(c.model.nv);
        loop_forward_dynamics(c.model, c.d, c.loops, c.v, tau, c.ld);
        return py::make_tuple(owned(VecX(c.d.qdd)), owned(VecX(c.ld.lambda)));
      }, "scene"_a, "q"_a, "v"_a, "tau"_a = py::none(),
      R"(q̈ of the scene's tree closed by its loops under τ (default 0), and the loops' forces λ.

Solves 𝓜 q̈ + Kᵀ λ = τ − bias with K q̈ = −K̇ v (the loops' velocity rows K): 𝓜⁻¹ Kᵀ by the
articulated-body factor, λ of minimum norm where rows depend on each other.  Returns (qdd (nv,),
lam (m,)), lam's entries named by scene.loop_rows (N or N m: scene.loop_units).)");

  m.def("loop_inverse_dynamics", [](const Scenario& sc, const ArrayIn& q_in, const ArrayIn& v_in, const ArrayIn& qdd_in,
                                    const py::iterable& actuated) {
        const char* where = "loop_inverse_dynamics";
        LoopCall c(sc, where, q_in, v_in);
        VecX qdd = read_vector(where, "qdd", qdd_in, c.model.nv);
        const std::vector<int> dofs = actuated_dofs(c.model, actuated);
        if (dofs.empty()) throw Error("loop_inverse_dynamics: actuated: expected at least one joint or DOF");
        const VecX tau = loop_inverse_dynamics(c.model, c.d, c.loops, dofs, qdd, c.ld);
        return py::make_tuple(owned(VecX(tau)), owned(VecX(c.ld.lambda)), owned(std::move(qdd)));
      }, "scene"_a, "q"_a, "v"_a, "qdd"_a, "actuated"_a,
      R"(The actuators' torques that make a motion of the scene's closed mechanism (constrained inverse dynamics).

actuated: the joints (names) or DOFs (indices) that carry actuators; qdd (nv,): their q̈ (the other
entries are ignored).  The passive DOFs' q̈ follow from the loops (K q̈ = −K̇ v; (q, v) must lie on
them), λ from the passive joints' equations of motion (no torque there), τ from the actuated ones'.
Returns (tau (nv,): zero on the passive DOFs, lam (m,): the loops' forces, qdd (nv,): every DOF's).
Raises soadyn.Error when the actuated DOFs do not determine the passive ones (too few, or a dead
point) or cannot make the motion.)");
}

}  // namespace soadyn::python
