// Frames and task space (frames.hpp) as Python functions f(model, data, q, …, frame, …): frame
// by name or index, reference by name; each first updates the kinematics at q (and velocities
// at v) and returns new arrays.
#include "common.hpp"

#include "soadyn/algorithm/frames.hpp"
#include "soadyn/multibody/text.hpp"

namespace soadyn::python {

namespace {

int frame_arg(const Model& m, const py::object& f, const char* where) {
  if (py::isinstance<py::str>(f)) {
    const std::string name = f.cast<std::string>();
    const int i = m.frame_index(name);
    if (i < 0) throw py::key_error("no frame named '" + printable(name) + "'" + did_you_mean(name, m.frame_names));
    return i;
  }
  if (py::isinstance<py::int_>(f) && !py::isinstance<py::bool_>(f)) {
    const long i = f.cast<long>();
    if (i < 0 || i >= long(m.frame_names.size()))
      throw Error(std::string(where) + ": frame: expected an index 0.." + std::to_string(m.frame_names.size() - 1) +
                  ", got " + std::to_string(i));
    return int(i);
  }
  throw py::type_error(std::string(where) + ": frame: expected a frame name or index, got " +
                       std::string(py::str(py::type::handle_of(f).attr("__name__"))));
}

Reference reference_arg(const std::string& r) { return parse_reference(r); }

void kin(const Model& m, PyData& d, const char* where, const py::object& q) {
  read_vector(m, *d.data, where, "q", q, m.nq, d.q);
  update_kinematics(m, *d.data, d.q);
}

void kin_vel(const Model& m, PyData& d, const char* where, const py::object& q, const py::object& v) {
  read_vector(m, *d.data, where, "v", v, m.nv, d.v);
  kin(m, d, where, q);
  update_velocities(m, *d.data, d.v);
}

py::array vec(const Eigen::Ref<const VecX>& x) { return owned(VecX(x)); }

py::array mat3(const Mat3& R) {
  std::vector<double> out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out.push_back(R(r, c));
  return owned(std::move(out), {3, 3});
}

Mat3 rpy(const Vec3& a) {
  return (Eigen::AngleAxisd(a.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(a.y(), Vec3::UnitY()) *
          Eigen::AngleAxisd(a.x(), Vec3::UnitX()))
      .toRotationMatrix();
}

#define SOADYN_REFERENCES \
    "reference: 'world' ([ω; v_O], the body's point at the inertial origin, inertial axes), 'local'\n" \
    "(the frame's axes, about its origin) or 'local_world_aligned' ([ω; ṗ], inertial axes, about the\n" \
    "frame's origin; the default).\n" \
    "Rows are [angular; linear], [ω; v] as in the note: rows 0-2 angular, 3-5 linear (Pinocchio puts\n" \
    "linear first, so its habit J[:3] takes the angular rows here).  part: 'all' (the default, 6 rows),\n" \
    "'linear' (rows 3-5) or 'angular' (rows 0-2)."

// part="all" | "angular" | "linear" → (first row, rows) of a spatial quantity [ω; v]
std::pair<int, int> part_rows(const std::string& part, const char* where) {
  if (part == "all") return {0, 6};
  if (part == "angular") return {0, 3};
  if (part == "linear") return {3, 3};
  throw py::value_error(std::string(where) + ": part: expected 'all', 'angular' or 'linear', got '" + printable(part) + "'" +
                        did_you_mean(part, {"all", "angular", "linear"}));
}

py::array rows(const Vec6& x, const std::string& part, const char* where) {
  const auto [first, n] = part_rows(part, where);
  return vec(x.segment(first, n));
}

}  // namespace

namespace {

// the Model's named frames: frame_names, frame_bodies, frame_index, add_frame
void bind_model_frames(py::module_& m) {
  auto model = py::reinterpret_borrow<py::class_<Model>>(m.attr("Model"));
  model
      .def_readonly("frame_names", &Model::frame_names,
                    "named frames: every body's own, every link merged by a fixed joint, then those a scenario's\n"
                    "'frames:' or add_frame added")
      .def_readonly("frame_bodies", &Model::frame_body, "the body each frame moves with, -1 for the world")
      .def("frame_index", [](const Model& self, const std::string& name) {
            const int i = self.frame_index(name);
            if (i < 0) throw py::key_error("no frame named '" + printable(name) + "'" + did_you_mean(name, self.frame_names));
            return i;
          }, "name"_a, "index of the named frame; KeyError (with the nearest name) when absent")
      .def("add_frame", [](Model& self, const std::string& name, const std::string& on, const ArrayIn& position,
                           const ArrayIn& rpy_angles) {
            Placement X;
            int body = -1;
            if (on != "world") {
              const int at = self.frame_index(on);
              if (at < 0) {
                std::vector<std::string> names = self.frame_names;
                names.push_back("world");
                throw py::key_error("no body or frame named '" + printable(on) + "'" + did_you_mean(on, names));
              }
              body = self.frame_body[at], X = self.frame_placement[at];
            }
            const Placement local{rpy(read_vector("Model.add_frame", "rpy", rpy_angles, 3)),
                                  read_vector("Model.add_frame", "position", position, 3)};
            return self.add_frame(name, body, compose(X, local));
          }, "name"_a, "body"_a, "position"_a = std::vector<double>{0, 0, 0}, "rpy"_a = std::vector<double>{0, 0, 0},
          "Add a frame on `body` (a body's or any frame's name, or 'world'), at position and rpy (R = Rz Ry Rx)\n"
          "in that frame, as a scenario's frames: {name: {body, position, rpy}}; returns its index.");
}

// a frame's placement, velocity, acceleration, Jacobian and J̇v; a point's Jacobian
void bind_frame_functions(py::module_& m) {
  m.def("frame_placement", [](const Model& mo, PyData& d, const py::object& q, const py::object& frame) {
        const int f = frame_arg(mo, frame, "frame_placement");
        kin(mo, d, "frame_placement", q);
        const Placement X = frame_placement(mo, *d.data, f);
        return py::make_tuple(mat3(X.R), vec(X.p));
      }, "model"_a, "data"_a, "q"_a, "frame"_a,
      "(R, p) of the frame at q: R (3, 3) frame → inertial, p (3,) its origin.  frame: name or index.");
  m.def("frame_velocity", [](const Model& mo, PyData& d, const py::object& q, const py::object& v, const py::object& frame,
                             const std::string& reference, const std::string& part) {
        const int f = frame_arg(mo, frame, "frame_velocity");
        const Reference r = reference_arg(reference);
        part_rows(part, "frame_velocity");
        kin_vel(mo, d, "frame_velocity", q, v);
        return rows(frame_velocity(mo, *d.data, f, r), part, "frame_velocity");
      }, "model"_a, "data"_a, "q"_a, "v"_a, "frame"_a, "reference"_a = "local_world_aligned", "part"_a = "all",
      "The frame's velocity (6,) = frame_jacobian(…) @ v ((3,) with part).\n" SOADYN_REFERENCES);
  m.def("frame_acceleration", [](const Model& mo, PyData& d, const py::object& q, const py::object& v, const py::object& qdd,
                                 const py::object& frame, const std::string& reference, bool classical, const std::string& part) {
        const int f = frame_arg(mo, frame, "frame_acceleration");
        const Reference r = reference_arg(reference);
        part_rows(part, "frame_acceleration");
        read_vector(mo, *d.data, "frame_acceleration", "qdd", qdd, mo.nv, d.x);
        kin_vel(mo, d, "frame_acceleration", q, v);
        return rows(frame_acceleration(mo, *d.data, f, d.x, r, classical), part, "frame_acceleration");
      }, "model"_a, "data"_a, "q"_a, "v"_a, "qdd"_a, "frame"_a, "reference"_a = "local_world_aligned", "classical"_a = false,
      "part"_a = "all",
      "The frame's acceleration (6,) for joint accelerations qdd: spatial (the time derivative of the\n"
                   "world or local velocity; local_world_aligned: local's in inertial axes, [α; p̈ − ω × ṗ]) or, with\n"
                   "classical=True, [α; the acceleration of the body's point at the reference point].\n" SOADYN_REFERENCES);
  m.def("frame_jacobian", [](const Model& mo, PyData& d, const py::object& q, const py::object& frame,
                             const std::string& reference, const std::string& part) {
        const int f = frame_arg(mo, frame, "frame_jacobian");
        const Reference r = reference_arg(reference);
        const auto [first, n] = part_rows(part, "frame_jacobian");
        kin(mo, d, "frame_jacobian", q);
        MatX J;
        frame_jacobian(mo, *d.data, f, r, J);
        if (n == 6) return owned(std::move(J));
        return owned(MatX(J.middleRows(first, n)));
      }, "model"_a, "data"_a, "q"_a, "frame"_a, "reference"_a = "local_world_aligned", "part"_a = "all",
      "J (6, nv) ((3, nv) with part): the frame's velocity is J @ v; body b's rows of Ψ_D G (eq. 7) moved to\n"
      "the frame.\n" SOADYN_REFERENCES);
  m.def("frame_jacobian_dot_times_v", [](const Model& mo, PyData& d, const py::object& q, const py::object& v,
                                         const py::object& frame, const std::string& reference, const std::string& part) {
        const int f = frame_arg(mo, frame, "frame_jacobian_dot_times_v");
        const Reference r = reference_arg(reference);
        part_rows(part, "frame_jacobian_dot_times_v");
        kin_vel(mo, d, "frame_jacobian_dot_times_v", q, v);
        Vec6 out;
        frame_jacobian_dot_times_v(mo, *d.data, f, r, out);
        return rows(out, part, "frame_jacobian_dot_times_v");
      }, "model"_a, "data"_a, "q"_a, "v"_a, "frame"_a, "reference"_a = "local_world_aligned", "part"_a = "all",
      "J̇ v (6,) ((3,) with part) = d/dt (J(q) v) at fixed v: the task acceleration is J q̈ + J̇ v.\n" SOADYN_REFERENCES);
  m.def("point_jacobian", [](const Model& mo, PyData& d, const py::object& q, const py::object& body, const ArrayIn& point) {
        int b;
        if (py::isinstance<py::str>(body)) {
          const std::string name = body.cast<std::string>();
          b = mo.body_index(name);
          if (b < 0) throw py::key_error("no body named '" + printable(name) + "'" + did_you_mean(name, mo.body_names));
        } else {
          b = body.cast<int>();
        }
        const Vec3 p = read_vector("point_jacobian", "point", point, 3);
        kin(mo, d, "point_jacobian", q);
        MatX J;
        point_jacobian(mo, *d.data, b, p, J);
        return owned(std::move(J));
      }, "model"_a, "data"_a, "q"_a, "body"_a, "point"_a,
      "J (3, nv) with ṗ = J @ v for the point at `point` (3,) of `body` (name or index), body frame coordinates.");
}

// the centre of mass and the centroidal momentum
void bind_centroidal(py::module_& m) {
  m.def("com", [](const Model& mo, PyData& d, const py::object& q) {
        kin(mo, d, "com", q);
        return vec(com(mo, *d.data));
      }, "model"_a, "data"_a, "q"_a, "c = Σ m_i r_i / m (3,), the centre of mass of the moving bodies.");
  m.def("com_velocity", [](const Model& mo, PyData& d, const py::object& q, const py::object& v) {
        kin_vel(mo, d, "com_velocity", q, v);
        return vec(com_velocity(mo, *d.data));
      }, "model"_a, "data"_a, "q"_a, "v"_a, "ċ = Σ m_i ṙ_i / m (3,).");
  m.def("com_jacobian", [](const Model& mo, PyData& d, const py::object& q) {
        read_vector(mo, *d.data, "com_jacobian", "q", q, mo.nq, d.q);
        MatX J;
        com_jacobian(mo, *d.data, d.q, J);  // from q alone: frames, subtree masses and first moments
        return owned(std::move(J));
      }, "model"_a, "data"_a, "q"_a, "J_c (3, nv) with ċ = J_c @ v.");
  m.def("centroidal_momentum_matrix", [](const Model& mo, PyData& d, const py::object& q) {
        kin(mo, d, "centroidal_momentum_matrix", q);
        MatX A;
        centroidal_momentum_matrix(mo, *d.data, A);
        return owned(std::move(A));
      }, "model"_a, "data"_a, "q"_a,
      "A_G (6, nv): h_G = A_G @ v = [k_G; l], the angular momentum about the centre of mass, then the linear.");
  m.def("centroidal_momentum", [](const Model& mo, PyData& d, const py::object& q, const py::object& v) {
        kin_vel(mo, d, "centroidal_momentum", q, v);
        return vec(centroidal_momentum(mo, *d.data));
      }, "model"_a, "data"_a, "q"_a, "v"_a, "h_G = [k_G; l] (6,) from the bodies' velocities.");
  m.def("centroidal_momentum_matrix_dot_times_v", [](const Model& mo, PyData& d, const py::object& q, const py::object& v) {
        kin_vel(mo, d, "centroidal_momentum_matrix_dot_times_v", q, v);
        return vec(centroidal_momentum_matrix_dot_times_v(mo, *d.data));
      }, "model"_a, "data"_a, "q"_a, "v"_a, "Ȧ_G v (6,): ḣ_G = A_G q̈ + Ȧ_G v.");
  m.def("centroidal_inertia", [](const Model& mo, PyData& d, const py::object& q) {
        kin(mo, d, "centroidal_inertia", q);
        const SpatialInertia K = centroidal_inertia(mo, *d.data);
        return py::make_tuple(K.m, mat3(K.I));
      }, "model"_a, "data"_a, "q"_a,
      "(m, I_G): the moving bodies' total mass and composite inertia (3, 3) about the centre of mass, inertial axes.");
}

// the operational-space inertia and the Coriolis matrix
void bind_task_space(py::module_& m) {
  m.def("operational_space_inertia", [](const Model& mo, PyData& d, const py::object& q, const ArrayIn& J) {
        if (J.ndim() != 2) throw Error("operational_space_inertia: J: expected a 2-D array (k, nv)");
        MatX Jm(J.shape(0), J.shape(1));
        const auto u = J.unchecked<2>();
        for (py::ssize_t r = 0; r < J.shape(0); ++r)
          for (py::ssize_t c = 0; c < J.shape(1); ++c) Jm(r, c) = u(r, c);
        if (!Jm.allFinite()) throw Error("operational_space_inertia: J: expected finite numbers");
        kin(mo, d, "operational_space_inertia", q);
        MatX L;
        operational_space_inertia(mo, *d.data, Jm, L);
        return owned(std::move(L));
      }, "model"_a, "data"_a, "q"_a, "J"_a,
      "Λ = (J 𝓜⁻¹ Jᵀ)⁻¹ (k, k) for a task Jacobian J (k, nv), through 𝓜's Cholesky factor (𝓜⁻¹ never formed).\n"
      "soadyn.Error when J 𝓜⁻¹ Jᵀ is singular (more rows than the joints move independently there).");
  m.def("coriolis_matrix", [](const Model& mo, PyData& d, const py::object& q, const py::object& v) {
        kin_vel(mo, d, "coriolis_matrix", q, v);
        MatX C;
        coriolis_matrix(mo, *d.data, C);
        return owned(std::move(C));
      }, "model"_a, "data"_a, "q"_a, "v"_a,
      "C(q, v) (nv, nv): C @ v = bias − gravity's part, 𝓜̇ − 2C skew-symmetric.");
}

}  // namespace

void bind_frames(py::module_& m) {
  bind_model_frames(m);
  bind_frame_functions(m);
  bind_centroidal(m);
  bind_task_space(m);
}

}  // namespace soadyn::python
