// Inertial parameters (regressor.hpp) as Python functions: parameters, with_parameters, regressor,
// forward_dynamics_parameter_derivative.  Each taking a state first updates the kinematics (and
// velocities) at it; results are new arrays.
#include "common.hpp"

#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/algorithm/regressor.hpp"

namespace soadyn::python {

namespace {

void at_state(const Model& m, PyData& d, const char* where, const py::object& q, const py::object& v) {
  d.check(m, where);
  read_vector(m, *d.data, where, "q", q, m.nq, d.q);
  read_vector(m, *d.data, where, "v", v, m.nv, d.v);
  update_kinematics(m, *d.data, d.q);
  update_velocities(m, *d.data, d.v);
}

}  // namespace

void bind_regressor(py::module_& m) {
  m.def("parameters", [](const Model& model) { return owned(parameters(model)); }, "model"_a,
        R"(The model's inertial parameters π, shape (10 N,): per body, in the model's order,
m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz with c the centre of mass and I the
inertia about the body frame's origin (its joint point), in the body's axes (Pinocchio's order).)");
  m.def("with_parameters", [](const Model& model, const ArrayIn& pi) {
        return with_parameters(model, read_vector("with_parameters", "pi", pi, 10 * model.nbodies));
      }, "model"_a, "pi"_a,
      "A copy of the model with inertial parameters pi (10 N,), ordered as parameters() gives them.\n"
      "Raises soadyn.Error naming the body for a mass <= 0 or an inertia about the centre of mass that\n"
      "is not positive semidefinite or breaks the triangle inequality.");
  m.def("regressor", [](const Model& model, PyData& d, const py::object& q, const py::object& v, const py::object& qdd) {
        at_state(model, d, "regressor", q, v);
        read_vector(model, *d.data, "regressor", "qdd", qdd, model.nv, d.x);
        MatX Y;
        d.kept_tau = d.data->tau;  // its inverse dynamics passes through data.tau: inverse_dynamics' result stays
        regressor(model, *d.data, d.x, Y);
        d.data->tau = d.kept_tau;
        return owned(std::move(Y));
      }, "model"_a, "data"_a, "q"_a, "v"_a, "qdd"_a,
      "The joint-torque regressor Y, shape (nv, 10 N): inverse dynamics tau = Y @ parameters(model),\n"
      "gravity included, at (q, v, qdd).");
  m.def("forward_dynamics_parameter_derivative",
        [](const Model& model, PyData& d, const py::object& q, const py::object& v, const py::object& tau) {
          at_state(model, d, "forward_dynamics_parameter_derivative", q, v);
          read_vector(model, *d.data, "forward_dynamics_parameter_derivative", "tau", tau, model.nv, d.x);
          MatX out;
          // it forms 𝓜, bias, q̈ and τ in data.M, data.bias, data.qdd and data.tau on its way: the
          // results mass_matrix, bias_forces, forward_dynamics and inverse_dynamics returned stay
          d.kept_M = d.data->M;
          d.kept_bias = d.data->bias;
          d.kept_qdd = d.data->qdd;
          d.kept_tau = d.data->tau;
          forward_dynamics_parameter_derivative(model, *d.data, d.x, out);
          d.data->M = d.kept_M;
          d.data->bias = d.kept_bias;
          d.data->qdd = d.kept_qdd;
          d.data->tau = d.kept_tau;
          return owned(std::move(out));
        }, "model"_a, "data"_a, "q"_a, "v"_a, "tau"_a,
        "dqdd/dpi, shape (nv, 10 N): -M^-1 Y(q, v, qdd) at the forward-dynamics qdd for tau, M^-1\n"
        "applied by the tree's factorization, never formed.");
}

}  // namespace soadyn::python
