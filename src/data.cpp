#include "soadyn/data.hpp"

namespace soadyn {

Data::Data(const Model& m)
    : R(m.nbodies, Mat3::Identity()),
      eta(Mat3X::Zero(3, m.nbodies)),
      d(Mat3X::Zero(3, m.nbodies)),
      s(Mat3X::Zero(3, m.nbodies)),
      r(Mat3X::Zero(3, m.nbodies)),
      G(Mat6X::Zero(6, m.nv)),
      turn(Eigen::Matrix2Xd::Zero(2, m.nbodies)),
      M(m.nbodies),
      V(Mat6X::Zero(6, m.nbodies)),
      Vbar(Mat6X::Zero(6, m.nbodies)),
      coriolis(Mat6X::Zero(6, m.nbodies)),
      gyroscopic(Mat6X::Zero(6, m.nbodies)),
      K(m.nbodies),
      S0(Mat6X::Zero(6, m.nv)),
      F0(Mat6X::Zero(6, m.nv)),
      F0t(Eigen::Matrix<double, Eigen::Dynamic, 6>::Zero(m.nv, 6)),
      Kl(m.nbodies),
      Fl(Mat6X::Zero(6, m.nv)),
      Mass(MatX::Zero(m.nv, m.nv)),
      A(Mat6X::Zero(6, m.nbodies)),
      F(Mat6X::Zero(6, m.nbodies)),
      bias(VecX::Zero(m.nv)),
      Vb(Mat6X::Zero(6, m.nbodies)),
      Ab(Mat6X::Zero(6, m.nbodies)),
      Fb(Mat6X::Zero(6, m.nbodies)),
      Xr(m.nbodies, Mat3::Identity()),
      Xp(Mat3X::Zero(3, m.nbodies)),
      tau(VecX::Zero(m.nv)),
      qdd(VecX::Zero(m.nv)),
      L(MatX::Zero(m.nv, m.nv)),
      llt(m.nv),
      P(m.nbodies, Mat6::Zero()),
      z(Mat6X::Zero(6, m.nbodies)),
      U1(Mat6X::Zero(6, m.nbodies)),
      Dinv1(VecX::Zero(m.nbodies)),
      Dinv(m.nbodies),
      u(VecX::Zero(m.nv)) {
  U.reserve(m.nbodies);
  for (int i = 0; i < m.nbodies; ++i) {
    U.emplace_back(Mat6G::Zero(6, m.nv_i[i]));
    Dinv[i] = MatGG::Zero(m.nv_i[i], m.nv_i[i]);
  }
}

void Data::check(const Model& model, const char* where, const char* what, Eigen::Index got, int expected) const {
  if (G.cols() != model.nv || int(R.size()) != model.nbodies)
    throw Error(std::string(where) + ": this Data was built for another model (nv " + std::to_string(G.cols()) +
                ", model nv " + std::to_string(model.nv) + ")");
  if (got != expected)
    throw Error(std::string(where) + ": " + what + ": expected " + std::to_string(expected) + " entries, got " +
                std::to_string(got));
}

}  // namespace soadyn
