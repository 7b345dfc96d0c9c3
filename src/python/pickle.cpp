// pickle and copy.deepcopy of Model and Data: a fitted model shipped to a worker process without a
// file.
//
// A Model's state is ("soadyn.Model", version, fields): its bodies as BodySpec fields (name, joint,
// parent, axis, pitch, placement, mass, centre of mass, inertia, travel, effort), rebuilt by Model::build,
// so everything derived (DOF tree, depth-first order, unit axes) comes from the library's own code
// and every check it makes refuses a corrupted state; then the fields build derives by arithmetic
// that could round differently are set to the stored bits (axes, a merged body's inertia, inertias
// about the origin, which with_parameters sets directly; each checked against the rebuilt one), and
// the fields no BodySpec carries are restored: the frames (the
// welded bodies' and add_frame's), merged names, the world's mass and first moment, the warnings.
// A Data's state is its Model and its result arrays.  A Scenario's: its Model, initial state,
// settings, torques, springs and dampers, log frames, name, path and text; its controllers (which
// may hold tables read from files) are parsed again from its text, so a scene with controllers
// unpickles only where its files are (its loops likewise; an MJCF model's, from the files it
// handed MuJoCo, which the state holds).  An unknown tag or version, a missing or mistyped field: one
// soadyn.Error naming it.
#include "common.hpp"

#include "soadyn/io/mjcf.hpp"
#include "soadyn/io/scenario_file.hpp"

#include <string>
#include <vector>

namespace soadyn::python {

namespace {

constexpr int kModelStateVersion = 1;
constexpr int kDataStateVersion = 1;
constexpr int kScenarioStateVersion = 1;

py::list doubles(const double* x, int n) {
  py::list out;
  for (int k = 0; k < n; ++k) out.append(x[k]);
  return out;
}

template <class Matrix>
py::list matrices(const std::vector<Matrix>& ms) {  // each column-major, back to back
  py::list out;
  for (const auto& a : ms) out.append(doubles(a.data(), int(a.size())));
  return out;
}

// the state's fields, read with the field named in any error
struct Reader {
  const char* where;
  py::dict fields;

  [[noreturn]] void refuse(const std::string& key, const std::string& what) const {
    throw Error(std::string(where) + ": state field '" + key + "': " + what +
                " (a state written by this soadyn's pickle, not edited)");
  }
  py::object get(const std::string& key) const {
    if (!fields.contains(key)) refuse(key, "missing");
    return fields[key.c_str()];
  }
  template <class T>
  T as(const std::string& key) const {
    try {
      return get(key).cast<T>();
    } catch (const py::cast_error&) {
      refuse(key, "wrong type");
    }
  }
  template <class Fixed>
  std::vector<Fixed> fixed_list(const std::string& key, size_t count) const {
    const auto rows = as<std::vector<std::vector<double>>>(key);
    if (rows.size() != count) refuse(key, "expected " + std::to_string(count) + " entries, got " + std::to_string(rows.size()));
    std::vector<Fixed> out(count);
    for (size_t i = 0; i < count; ++i) {
      if (rows[i].size() != size_t(Fixed::SizeAtCompileTime)) refuse(key, "entry " + std::to_string(i) + " has the wrong size");
      out[i] = Eigen::Map<const Fixed>(rows[i].data());
    }
    return out;
  }
  template <class T>
  std::vector<T> list(const std::string& key, size_t count) const {
    auto out = as<std::vector<T>>(key);
    if (out.size() != count) refuse(key, "expected " + std::to_string(count) + " entries, got " + std::to_string(out.size()));
    return out;
  }
};

// the (tag, version, fields) triple; refuses anything else in one line
py::dict unpack(const py::object& state, const char* where, const char* tag, int version) {
  const std::string expected = std::string(" (a ") + tag + " state, version " + std::to_string(version) + ")";
  if (!py::isinstance<py::tuple>(state) || py::len(state) != 3)
    throw Error(std::string(where) + ": expected a (tag, version, fields) tuple" + expected);
  const py::tuple t = state;
  if (!py::isinstance<py::str>(t[0]) || t[0].cast<std::string>() != tag)
    throw Error(std::string(where) + ": expected the tag '" + tag + "', got " + std::string(py::repr(t[0])));
  if (!py::isinstance<py::int_>(t[1]) || t[1].cast<long long>() != version)
    throw Error(std::string(where) + ": state version " + std::string(py::repr(t[1])) + ": this soadyn reads version " +
                std::to_string(version) + " only");
  if (!py::isinstance<py::dict>(t[2])) throw Error(std::string(where) + ": expected a dict of fields" + expected);
  return t[2];
}

py::tuple model_state(const Model& m) {
  const int n = m.nbodies;
  std::vector<int> joints;
  std::vector<double> lower, upper, effort;
  std::vector<Mat3> R;
  std::vector<Vec3> p, frame_p;
  std::vector<Mat3> frame_R;
  for (int i = 0; i < n; ++i) {
    joints.push_back(int(m.joint_type[i]));
    // a 1-DOF joint's travel and effort (BodySpec's); the others have none
    const int k = m.idx_v[i];
    lower.push_back(m.lower[k]);
    upper.push_back(m.upper[k]);
    effort.push_back(m.effort[k]);
    R.push_back(m.placement[i].R);
    p.push_back(m.placement[i].p);
  }
  for (const Placement& X : m.frame_placement) {
    frame_R.push_back(X.R);
    frame_p.push_back(X.p);
  }
  py::dict f;
  f["body_names"] = m.body_names;
  f["joint_names"] = m.joint_names;
  f["parent"] = m.parent;
  f["joint_type"] = joints;
  f["axis"] = matrices(m.axis);
  f["pitch"] = m.pitch;
  f["placement_R"] = matrices(R);
  f["placement_p"] = matrices(p);
  f["mass"] = m.mass;
  f["com"] = matrices(m.com);
  f["inertia"] = matrices(m.inertia);
  f["inertia_origin"] = matrices(m.inertia_origin);
  f["lower"] = lower;
  f["upper"] = upper;
  f["effort"] = effort;
  f["merged_names"] = m.merged_names;
  f["frame_names"] = m.frame_names;
  f["frame_body"] = m.frame_body;
  f["frame_R"] = matrices(frame_R);
  f["frame_p"] = matrices(frame_p);
  f["warnings"] = m.warnings;
  f["world_mass"] = m.world_mass;
  f["world_first_moment"] = doubles(m.world_first_moment.data(), 3);
  f["gravity"] = doubles(m.gravity.data(), 3);
  return py::make_tuple("soadyn.Model", kModelStateVersion, f);
}

Model model_from_state(const py::object& state) {
  const char* where = "Model.__setstate__";
  const Reader r{where, unpack(state, where, "soadyn.Model", kModelStateVersion)};
  const auto names = r.as<std::vector<std::string>>("body_names");
  const size_t n = names.size();
  const auto joint_names = r.list<std::string>("joint_names", n);
  const auto parent = r.list<int>("parent", n);
  const auto joints = r.list<int>("joint_type", n);
  const auto axis = r.fixed_list<Vec3>("axis", n);
  // a helical joint's pitch (states from before helical joints have none: all zero)
  const auto pitch = r.fields.contains("pitch") ? r.list<double>("pitch", n) : std::vector<double>(n, 0.0);
  const auto R = r.fixed_list<Mat3>("placement_R", n);
  const auto p = r.fixed_list<Vec3>("placement_p", n);
  const auto mass = r.list<double>("mass", n);
  const auto com = r.fixed_list<Vec3>("com", n);
  const auto inertia = r.fixed_list<Mat3>("inertia", n);
  const auto inertia_origin = r.fixed_list<Mat3>("inertia_origin", n);
  const auto lower = r.list<double>("lower", n), upper = r.list<double>("upper", n), effort = r.list<double>("effort", n);
  const auto g = r.list<double>("gravity", 3);

  // the bodies, rebuilt and checked by the library (parents before children, masses, inertias, 𝓜 > 0)
  std::vector<BodySpec> specs(n);
  for (size_t i = 0; i < n; ++i) {
    BodySpec& b = specs[i];
    if (joints[i] < 0 || joints[i] > int(JointType::Fixed) || JointType(joints[i]) == JointType::Fixed)
      r.refuse("joint_type", "entry " + std::to_string(i) + " is not a moving joint");
    b.name = names[i];
    b.joint_name = joint_names[i];
    b.parent = parent[i];
    if (b.parent >= int(i)) r.refuse("parent", "entry " + std::to_string(i) + " is not an earlier body");
    b.joint = JointType(joints[i]);
    b.axis = axis[i];
    b.pitch = pitch[i];
    b.placement = {R[i], p[i]};
    b.mass = mass[i];
    b.com = com[i];
    b.inertia = inertia[i];
    b.lower = lower[i];
    b.upper = upper[i];
    b.effort = effort[i];
  }
  Model m = Model::build(specs, Vec3(g[0], g[1], g[2]), InertiaCheck::Warn);
  // the stored bits where build's arithmetic (normalizing, symmetrizing, I_cm + parallel axis) may round otherwise
  for (size_t i = 0; i < n; ++i) {
    if ((m.axis[i] - axis[i]).cwiseAbs().maxCoeff() > 1e-12) r.refuse("axis", "entry " + std::to_string(i) + " is not a unit vector");
    if ((m.inertia_origin[i] - inertia_origin[i]).cwiseAbs().maxCoeff() > 1e-9 * std::max(1.0, inertia_origin[i].cwiseAbs().maxCoeff()))
      r.refuse("inertia_origin", "entry " + std::to_string(i) + " disagrees with mass, com and inertia");
    if ((m.inertia[i] - inertia[i]).cwiseAbs().maxCoeff() > 1e-12 * std::max(1.0, inertia[i].cwiseAbs().maxCoeff()))
      r.refuse("inertia", "entry " + std::to_string(i) + " is not symmetric");
    m.axis[i] = axis[i];
    m.inertia[i] = inertia[i];  // a merged body's R I Rᵀ sum may be off symmetric in its last bits
    m.inertia_origin[i] = inertia_origin[i];
  }
  m.classify_joints();  // the kinds carry the axes: from the stored bits too
  // what no BodySpec carries: frames, merged names, the world's share, the warnings
  const auto frame_names = r.as<std::vector<std::string>>("frame_names");
  const size_t nf = frame_names.size();
  const auto frame_body = r.list<int>("frame_body", nf);
  const auto frame_R = r.fixed_list<Mat3>("frame_R", nf);
  const auto frame_p = r.fixed_list<Vec3>("frame_p", nf);
  m.frame_names.clear();
  m.frame_body.clear();
  m.frame_placement.clear();
  for (size_t f = 0; f < nf; ++f) m.add_frame(frame_names[f], frame_body[f], {frame_R[f], frame_p[f]});
  m.merged_names = r.list<std::vector<std::string>>("merged_names", n);
  m.warnings = r.as<std::vector<std::string>>("warnings");
  m.world_mass = r.as<double>("world_mass");
  const auto wf = r.list<double>("world_first_moment", 3);
  m.world_first_moment = Vec3(wf[0], wf[1], wf[2]);
  return m;
}

// Data's result arrays, each the library's storage in its own (column-major) order
std::vector<std::pair<const char*, Eigen::Map<VecX>>> data_arrays(Data& D) {
  const auto flat = [](double* p, Eigen::Index n) { return Eigen::Map<VecX>(p, n); };
  return {{"M", flat(D.M.data(), D.M.size())},
          {"bias", flat(D.bias.data(), D.bias.size())},
          {"tau", flat(D.tau.data(), D.tau.size())},
          {"qdd", flat(D.qdd.data(), D.qdd.size())},
          {"R", flat(D.R.empty() ? nullptr : D.R[0].data(), 9 * Eigen::Index(D.R.size()))},
          {"eta", flat(D.eta.data(), D.eta.size())},
          {"d", flat(D.d.data(), D.d.size())},
          {"s", flat(D.s.data(), D.s.size())},
          {"r", flat(D.r.data(), D.r.size())},
          {"G", flat(D.G.data(), D.G.size())},
          {"V", flat(D.V.data(), D.V.size())},
          {"Vbar", flat(D.Vbar.data(), D.Vbar.size())}};
}

py::tuple data_state(const PyData& self) {
  py::dict f;
  f["model"] = self.model;
  for (auto& [name, a] : data_arrays(*self.data)) f[name] = owned(VecX(a));
  return py::make_tuple("soadyn.Data", kDataStateVersion, f);
}

// a Data for `model` (a Python Model) holding the state's arrays
PyData data_from_fields(const py::dict& fields, const py::object& model) {
  const char* where = "Data.__setstate__";
  const Reader r{where, fields};
  if (!py::isinstance<Model>(model)) r.refuse("model", "expected a soadyn.Model");
  PyData out(model.cast<const Model&>());
  out.model = model;
  for (auto& [name, a] : data_arrays(*out.data)) {
    const auto values = r.as<py::array_t<double, py::array::c_style | py::array::forcecast>>(name);
    if (values.ndim() != 1 || values.shape(0) != a.size())
      r.refuse(name, "expected " + std::to_string(a.size()) + " numbers for this model");
    a = Eigen::Map<const VecX>(values.data(), a.size());  // into the storage the views show
  }
  return out;
}

py::tuple scenario_state(const py::object& self) {
  const Scenario& sc = self.cast<const Scenario&>();
  py::dict f;
  f["path"] = sc.path;
  f["text"] = sc.text;
  f["robot_text"] = sc.robot_text;  // stored in its runs' files (h5log.hpp /robot)
  f["robot_path"] = sc.robot_path;
  f["name"] = sc.name;
  f["description"] = sc.description;
  f["model"] = py::cast(sc.model);  // a copy, pickled as a Model
  f["q0"] = doubles(sc.q0.data(), int(sc.q0.size()));
  f["v0"] = doubles(sc.v0.data(), int(sc.v0.size()));
  const SimulationSettings& s = sc.simulation;
  py::dict settings("sensitivities_initial_state"_a = s.sensitivities.initial_state,
                    "sensitivities_parameters"_a = s.sensitivities.parameters);
  for (const SettingInfo& info : setting_table()) settings[py::str(std::string(info.name))] = setting_value(s, info);
  f["settings"] = settings;
  py::list torques, springs, dampers;
  for (const auto& u : sc.inputs.torques) torques.append(py::make_tuple(u.joint, u.dof, u.constant, u.amplitude, u.frequency, u.phase));
  for (const auto& u : sc.inputs.springs) springs.append(py::make_tuple(u.joint, u.dof, u.coord, u.stiffness, u.rest));
  for (const auto& u : sc.inputs.dampers) dampers.append(py::make_tuple(u.joint, u.dof, u.damping));
  f["torques"] = torques;
  f["springs"] = springs;
  f["dampers"] = dampers;
  f["controllers"] = sc.inputs.controllers.size();
  // prescribed motions and loops, like controllers, are read again from the text (their tables)
  f["prescribed"] = sc.inputs.prescribed.size();
  f["loops"] = sc.inputs.loops.size();
  f["log_frames"] = sc.log_frames;
  f["files"] = sc.files;  // the files it was read from: never a run's output
  py::list model_files;  // an MJCF model's files as handed to MuJoCo: stored in its runs' files (/model_files)
  for (const ModelFile& mf : sc.model_files) model_files.append(py::make_tuple(mf.name, py::bytes(mf.data)));
  f["model_files"] = model_files;
  return py::make_tuple("soadyn.Scenario", kScenarioStateVersion, f);
}

// The loops of a Scenario loaded from an MJCF file alone (load_scenario("robot.xml")): its
// equalities, from its stored files (or its text), on a model of the state's bodies (freed roots
// when the state's model has them)
std::vector<LoopConstraint> mjcf_loops(const Scenario& sc, const Reader& r) {
  const std::vector<ModelFile> files = sc.model_files.empty() ? std::vector<ModelFile>{{"soadyn-model.in-memory.xml", sc.text}}
                                                              : sc.model_files;
  MjcfOptions o;
  o.inertia_check = InertiaCheck::Balance;
  MjcfModel mj = parse_mjcf_files(files, sc.path, o);
  if (mj.model.nq != sc.model.nq) {
    o.free_root = true;
    mj = parse_mjcf_files(files, sc.path, o);
  }
  if (mj.model.nq != sc.model.nq || mj.model.body_names != sc.model.body_names)
    r.refuse("model_files", "they compile to another model than the state's");
  return mj.loops;
}

Scenario scenario_from_state(const py::object& state) {
  const char* where = "Scenario.__setstate__";
  const Reader r{where, unpack(state, where, "soadyn.Scenario", kScenarioStateVersion)};
  Scenario sc;
  sc.path = r.as<std::string>("path");
  sc.text = r.as<std::string>("text");
  sc.robot_text = r.as<std::string>("robot_text");
  sc.robot_path = r.as<std::string>("robot_path");
  sc.name = r.as<std::string>("name");
  sc.description = r.as<std::string>("description");
  if (r.fields.contains("files")) sc.files = r.as<std::vector<std::string>>("files");  // absent from older states
  if (r.fields.contains("model_files"))  // absent from older states
    for (const auto& [name, data] : r.as<std::vector<std::pair<std::string, py::bytes>>>("model_files"))
      sc.model_files.push_back({name, std::string(data)});
  const py::object model = r.get("model");
  if (!py::isinstance<Model>(model)) r.refuse("model", "expected a soadyn.Model");
  sc.model = model.cast<const Model&>();
  const Model& m = sc.model;
  const auto q0 = r.list<double>("q0", size_t(m.nq)), v0 = r.list<double>("v0", size_t(m.nv));
  sc.q0 = Eigen::Map<const VecX>(q0.data(), m.nq);
  sc.v0 = Eigen::Map<const VecX>(v0.data(), m.nv);
  const Reader s{where, r.as<py::dict>("settings")};
  SimulationSettings& o = sc.simulation;
  for (const SettingInfo& info : setting_table()) {
    try {
      set_setting_value(o, info, s.get(std::string(info.name)));
    } catch (const py::cast_error&) {
      s.refuse(std::string(info.name), "wrong type");
    }
  }
  o.sensitivities.initial_state = s.as<bool>("sensitivities_initial_state");
  o.sensitivities.parameters = s.as<std::vector<std::string>>("sensitivities_parameters");
  // the inputs, their indices checked against the model (evaluate() indexes q and v with them)
  const auto in_range = [&](const char* key, int k, int n) {
    if (k < 0 || k >= n) r.refuse(key, "an index " + std::to_string(k) + " outside 0.." + std::to_string(n - 1));
  };
  for (const auto& t : r.as<std::vector<std::tuple<std::string, int, double, double, double, double>>>("torques")) {
    in_range("torques", std::get<1>(t), m.nv);
    sc.inputs.torques.push_back({std::get<0>(t), std::get<1>(t), std::get<2>(t), std::get<3>(t), std::get<4>(t), std::get<5>(t)});
  }
  for (const auto& t : r.as<std::vector<std::tuple<std::string, int, int, double, double>>>("springs")) {
    in_range("springs", std::get<1>(t), m.nv);
    in_range("springs", std::get<2>(t), m.nq);
    sc.inputs.springs.push_back({std::get<0>(t), std::get<1>(t), std::get<2>(t), std::get<3>(t), std::get<4>(t)});
  }
  for (const auto& t : r.as<std::vector<std::tuple<std::string, int, double>>>("dampers")) {
    in_range("dampers", std::get<1>(t), m.nv);
    sc.inputs.dampers.push_back({std::get<0>(t), std::get<1>(t), std::get<2>(t)});
  }
  sc.log_frames = r.as<std::vector<std::string>>("log_frames");
  for (const auto& name : sc.log_frames)
    if (m.frame_index(name) < 0) r.refuse("log_frames", "a frame the model does not have");
  // controllers, prescribed motions and loops from the text, where their tables are (the counts
  // absent from older states: none)
  const auto count = [&](const char* key) { return r.fields.contains(key) ? r.as<size_t>(key) : size_t(0); };
  const size_t controllers = count("controllers"), prescribed = count("prescribed"), loops = count("loops");
  if (loops > 0 && is_mjcf_text(sc.text)) {
    // an MJCF model loaded alone: its connects and welds, compiled again from the files it handed MuJoCo
    sc.inputs.loops = mjcf_loops(sc, r);
    if (sc.inputs.loops.size() != loops) r.refuse("text", "its equality constraints are not the state's loops");
  } else if (controllers + prescribed + loops > 0) {
    // an MJCF robot compiled from the files the scene handed MuJoCo, as its runs store them
    Scenario text = parse_scenario(sc.text, sc.path, false, std::nullopt,
                                   sc.robot_text.empty() ? std::nullopt : std::optional<std::string>(sc.robot_text),
                                   sc.model_files.empty() ? nullptr : &sc.model_files);
    if (text.inputs.controllers.size() != controllers || text.inputs.prescribed.size() != prescribed ||
        text.inputs.loops.size() != loops)
      r.refuse("text", "its controllers, prescribed motions or loops are not the state's");
    sc.inputs.controllers = std::move(text.inputs.controllers);
    sc.inputs.prescribed = std::move(text.inputs.prescribed);
    sc.inputs.loops = std::move(text.inputs.loops);
  }
  return sc;
}

}  // namespace

void bind_pickle(py::module_& m) {
  auto model = py::reinterpret_borrow<py::class_<Model>>(m.attr("Model"));
  model.def(py::pickle([](const Model& self) -> py::object { return model_state(self); },
                       [](const py::object& state) { return model_from_state(state); }))
      .def("__copy__", [](const Model& self) { return Model(self); })
      .def("__deepcopy__", [](const Model& self, const py::dict&) { return Model(self); }, "memo"_a);

  auto data = py::reinterpret_borrow<py::class_<PyData>>(m.attr("Data"));
  data.def(py::pickle([](const PyData& self) -> py::object { return data_state(self); },
                      [](const py::object& state) {
                        const py::dict f = unpack(state, "Data.__setstate__", "soadyn.Data", kDataStateVersion);
                        return data_from_fields(f, Reader{"Data.__setstate__", f}.get("model"));
                      }))
      // a copy shares the model (Data never changes it) and owns its arrays; a deep copy copies both
      .def("__copy__", [](const PyData& self) {
        return data_from_fields(unpack(data_state(self), "Data.__copy__", "soadyn.Data", kDataStateVersion), self.model);
      })
      .def("__deepcopy__", [](const PyData& self, const py::dict& memo) {
        const py::object model = py::module_::import("copy").attr("deepcopy")(self.model, memo);
        return data_from_fields(unpack(data_state(self), "Data.__deepcopy__", "soadyn.Data", kDataStateVersion), model);
      }, "memo"_a)
      .def_readonly("model", &PyData::model, "the Model this Data was made for");

  auto scenario = py::reinterpret_borrow<py::class_<Scenario>>(m.attr("Scenario"));
  scenario.def(py::pickle([](const py::object& self) -> py::object { return scenario_state(self); },
                          [](const py::object& state) { return scenario_from_state(state); }))
      .def("__copy__", [](const Scenario& self) { return Scenario(self); })
      .def("__deepcopy__", [](const Scenario& self, const py::dict&) { return Scenario(self); }, "memo"_a);
}

}  // namespace soadyn::python
