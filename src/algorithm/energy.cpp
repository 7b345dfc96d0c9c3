// Kinetic and potential energy and momentum of the system from its [kin] and [vel] state
// (algorithms.hpp).
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"

namespace soadyn {

double kinetic_energy(const Model& model, const Data& data) {
  data.require("kinetic_energy", true);
  double T = 0.0;
  for (int i = 0; i < model.nbodies; ++i) {
    const Vec3 w = data.Vbar.col(i).head<3>(), rd = data.Vbar.col(i).tail<3>();
    T += 0.5 * (w.dot(inertia_cm(data, i) * w) + model.mass[i] * rd.squaredNorm());
  }
  return T;
}

double potential_energy(const Model& model, const Data& data) {
  data.require("potential_energy", false);
  Vec3 first_moment = model.world_first_moment;
  for (int i = 0; i < model.nbodies; ++i) first_moment += model.mass[i] * data.r.col(i);
  return 0.0 - model.gravity.dot(first_moment);  // 0 − x: never a negative zero
}

Momentum momentum(const Model& model, const Data& data) {
  data.require("momentum", true);
  Momentum h;
  for (int i = 0; i < model.nbodies; ++i) {
    const Vec3 p = model.mass[i] * data.Vbar.col(i).tail<3>();
    h.linear += p;
    h.angular += inertia_cm(data, i) * data.Vbar.col(i).head<3>() + Vec3(data.r.col(i)).cross(p);
  }
  return h;
}

}  // namespace soadyn
