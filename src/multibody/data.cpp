#include "soadyn/multibody/data.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace soadyn {

double memory_limit_bytes() {
  double limit = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGESIZE));
  for (int resource : {RLIMIT_AS, RLIMIT_DATA}) {
    rlimit r{};
    if (getrlimit(resource, &r) == 0 && r.rlim_cur != RLIM_INFINITY) limit = std::min(limit, double(r.rlim_cur));
  }
  return limit;
}

void check_memory(double bytes, int nv, const std::string& what) {
  const double limit = memory_limit_bytes();
  if (bytes <= limit) return;
  char msg[256];
  std::snprintf(msg, sizeof msg, "the model has nv = %d: %s need about %.1f GB, more than the %.1f GB this process may use",
                nv, what.c_str(), bytes / 1e9, limit / 1e9);
  throw Error(msg);
}

namespace {
// runs before Data's first member is built
int checked_bodies(const Model& m) {
  check_memory(8.0 * double(m.nv) * (3.0 * double(m.nv) + 6.0 * double(m.npaths)), m.nv,
               "its nv×nv matrices (𝓜 and its Cholesky factor) and minverse's blocks");
  return m.nbodies;
}
}  // namespace

Data::Data(const Model& m)
    : R(checked_bodies(m), Mat3::Identity()),
      eta(Mat3X::Zero(3, m.nbodies)),
      d(Mat3X::Zero(3, m.nbodies)),
      s(Mat3X::Zero(3, m.nbodies)),
      r(Mat3X::Zero(3, m.nbodies)),
      G(Mat6X::Zero(6, m.nv)),
      inertia(m.nbodies),
      V(Mat6X::Zero(6, m.nbodies)),
      Vbar(Mat6X::Zero(6, m.nbodies)),
      coriolis(Mat6X::Zero(6, m.nbodies)),
      gyroscopic(Mat6X::Zero(6, m.nbodies)),
      M(MatX::Zero(m.nv, m.nv)),
      A(Mat6X::Zero(6, m.nbodies)),
      F(Mat6X::Zero(6, m.nbodies)),
      bias(VecX::Zero(m.nv)),
      tau(VecX::Zero(m.nv)),
      qdd(VecX::Zero(m.nv)) {
  const int N = m.nbodies, nv = m.nv;
  work.turn = Eigen::Matrix2Xd::Zero(2, N);
  auto& c = work.composite;
  c.K.resize(N);
  c.S0 = c.F0 = Mat6X::Zero(6, nv);
  c.F0t = Eigen::Matrix<double, Eigen::Dynamic, 6>::Zero(nv, 6);
  auto& l = work.local;
  l.K.resize(N);
  l.Fcol = Mat6X::Zero(6, nv);
  l.V = l.A = l.F = Mat6X::Zero(6, N);
  l.Xr.assign(N, Mat3::Identity());
  l.Xp = Mat3X::Zero(3, N);
  l.R.assign(N, Mat3::Identity());
  l.eta = l.d = Mat3X::Zero(3, N);
  l.G = Mat6X::Zero(6, nv);
  work.factor.L = MatX::Zero(nv, nv);
  work.factor.llt = Eigen::LLT<MatX>(nv);
  auto& a = work.articulated;
  a.P.assign(N, Mat6::Zero());
  a.z = a.U1 = Mat6X::Zero(6, N);
  a.Dinv1 = VecX::Zero(N);
  a.u = VecX::Zero(nv);
  a.U.reserve(N);
  a.Dinv.reserve(N);
  for (int i = 0; i < N; ++i) {
    a.U.emplace_back(Mat6G::Zero(6, m.nv_i[i]));
    a.Dinv.emplace_back(MatGG::Zero(m.nv_i[i], m.nv_i[i]));
  }
  auto& o = work.origin;
  o.S = o.UD = Mat6X::Zero(6, nv);
  o.P.assign(N, Mat6::Zero());
  o.Z = Eigen::Matrix<double, Eigen::Dynamic, 6>::Zero(nv, 6);
  o.A = MatX::Zero(nv, 6 * m.npaths);
  o.row = VecX::Zero(6 * nv);
}

void Data::check(const Model& model, const char* where, const char* what, Eigen::Index got, int expected) const {
  if (G.cols() != model.nv || int(R.size()) != model.nbodies)
    throw Error(std::string(where) + ": this Data was built for another model (nv " + std::to_string(G.cols()) +
                ", model nv " + std::to_string(model.nv) + ")");
  if (got != expected)
    throw Error(std::string(where) + ": " + what + ": expected " + std::to_string(expected) + " entries, got " +
                std::to_string(got));
}

void Data::refuse_stage(const char* where, bool velocities) const {
  if (!stages.kinematics)
    throw Error(std::string(where) + ": needs [kin], which this Data does not hold: call update_kinematics(model, data, q)" +
                (velocities ? " and update_velocities(model, data, v)" : "") + " first");
  throw Error(std::string(where) + ": needs [vel], which this Data does not hold" +
              " (update_kinematics at a new q clears it): call update_velocities(model, data, v) first");
}

}  // namespace soadyn
