// A scenario's `inertial: {body: {mass, com, inertia}}`: mass properties over those of the model's
// bodies (a URDF's, an MJCF file's or the scenario's own), as soadyn identify writes a fitted scene.
#include "scenario_reader.hpp"

#include "soadyn/algorithm/regressor.hpp"

namespace soadyn::scenario_detail {

void read_inertial(const Reader& rd, const YAML::Node& n, Model& m) {
  const std::string f = "inertial";
  if (!n.IsMap()) rd.fail(n, f, "expected a map from body name to {mass, com, inertia}, got " + Reader::show(n));
  for (auto it = n.begin(); it != n.end(); ++it) {
    const std::string name = rd.string(it->first, f);
    const std::string fb = f + "." + name;
    const int i = m.body_index(name);
    if (i < 0)
      rd.fail(it->first, f, "no body named '" + excerpt(name) + "'" + did_you_mean(name, m.body_names) +
                                " (the bodies after fixed joints are merged)");
    const YAML::Node b = it->second;
    rd.keys(b, fb, {"mass", "com", "inertia"});
    const double mass = rd.positive(rd.require(b, "mass", fb), fb + ".mass");
    const Vec3 c = rd.vec3(rd.require(b, "com", fb), fb + ".com");
    const Mat3 I = rd.inertia(rd.require(b, "inertia", fb), fb + ".inertia");
    if ((I - I.transpose()).cwiseAbs().maxCoeff() > 1e-12 * std::max(1.0, I.cwiseAbs().maxCoeff()))
      rd.fail(b["inertia"], fb + ".inertia", "expected a symmetric 3x3 matrix");
    // π_i = (m, m c, I about the origin): with_parameters checks it is a rigid body's
    VecX pi = parameters(m);
    const Mat3 Io = 0.5 * (I + I.transpose()) + parallel_axis(mass, c);
    pi.segment<kParametersPerBody>(kParametersPerBody * i) << mass, mass * c.x(), mass * c.y(), mass * c.z(), Io(0, 0),
        Io(0, 1), Io(1, 1), Io(0, 2), Io(1, 2), Io(2, 2);
    try {
      m = with_parameters(m, pi);
    } catch (const Error& e) {
      rd.fail(b, fb, std::string(e.what()).substr(std::string("with_parameters: ").size()));
    }
    m.com[i] = c;  // as written, not m c / m
    m.inertia[i] = 0.5 * (I + I.transpose());
  }
}

}  // namespace soadyn::scenario_detail
