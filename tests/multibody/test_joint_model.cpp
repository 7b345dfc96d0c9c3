// The joint kinds Model::build classifies joints into (joint_model.hpp): which kind each joint
// gets, and each kind's motion, subspace and carries table against the joint interface of
// joint.cpp (written per JointType, independently of the kinds).
#include "test_util.hpp"

#include "soadyn/multibody/joint_model.hpp"

#include <set>

namespace soadyn::test {
namespace {

TEST(JointModel, ClassifiesEveryJointIntoItsKind) {
  const Mat3 e = Mat3::Identity(), turn = Eigen::AngleAxisd(0.3, Vec3::UnitX()).toRotationMatrix();
  const Vec3 skew_axis = Vec3(1, 1, 0).normalized();
  const struct {
    JointType type;
    Vec3 axis;
    Mat3 placement;
    const char* kind;
    double sign;
  } cases[] = {
      {JointType::Revolute, Vec3::UnitZ(), e, "revolute-axis-z", 1},
      {JointType::Revolute, -Vec3::UnitX(), e, "revolute-axis-x", -1},
      {JointType::Revolute, Vec3::UnitY(), turn, "turned-revolute-axis-y", 1},
      {JointType::Revolute, -Vec3::UnitZ(), turn, "turned-revolute-axis-z", -1},
      {JointType::Revolute, skew_axis, e, "revolute", 0},
      {JointType::Prismatic, Vec3::UnitX(), e, "prismatic-axis-x", 1},
      {JointType::Prismatic, -Vec3::UnitY(), turn, "prismatic-axis-y", -1},
      {JointType::Prismatic, skew_axis, turn, "prismatic", 0},
      {JointType::Ball, Vec3::UnitZ(), turn, "ball", 0},
      {JointType::Planar, Vec3::UnitZ(), e, "planar", 0},
      {JointType::Free, Vec3::UnitZ(), e, "free", 0},
      {JointType::Helical, Vec3::UnitZ(), turn, "helical", 0},
  };
  for (const auto& c : cases) {
    const JointModel j = classify_joint(c.type, c.axis, c.placement);
    EXPECT_STREQ(kind_name(j), c.kind) << to_string(c.type);
    if (c.sign != 0)
      std::visit(
          [&](const auto& k) {
            if constexpr (requires { k.sign; }) EXPECT_EQ(k.sign, c.sign) << c.kind;
            else ADD_FAILURE() << c.kind << " has no sign";
          },
          j);
    EXPECT_EQ(turns_by_angle(j), std::string(c.kind).find("revolute-axis") != std::string::npos) << c.kind;
  }
  EXPECT_THROW(classify_joint(JointType::Fixed, Vec3::UnitZ(), e), Error);
  // an unturned prismatic axis is told from a turned one
  EXPECT_FALSE(std::get<joints::PrismaticAxis<0>>(classify_joint(JointType::Prismatic, Vec3::UnitX(), e)).turned);
  EXPECT_TRUE(std::get<joints::PrismaticAxis<0>>(classify_joint(JointType::Prismatic, Vec3::UnitX(), turn)).turned);
}

// each kind's motion(q), subspace(Rj, Rb) and carries(k, m) against joint_motion, joint_subspace and
// joint_carries of its JointType, at random q and joint frames, for every kind
TEST(JointModel, EachKindAgreesWithTheJointInterface) {
  Rng rng(4242);
  const Mat3 e = Mat3::Identity();
  const Vec3 skew_axis = Vec3(0.3, -0.5, 0.8).normalized();
  std::vector<std::pair<JointType, Vec3>> joints_in;
  std::vector<Mat3> placements;
  for (int k = 0; k < 3; ++k)
    for (const double s : {1.0, -1.0}) {
      joints_in.push_back({JointType::Revolute, s * Vec3::Unit(k)});
      joints_in.push_back({JointType::Prismatic, s * Vec3::Unit(k)});
    }
  joints_in.push_back({JointType::Revolute, skew_axis});
  joints_in.push_back({JointType::Prismatic, skew_axis});
  joints_in.push_back({JointType::Ball, Vec3::UnitZ()});
  joints_in.push_back({JointType::Planar, skew_axis});
  joints_in.push_back({JointType::Free, Vec3::UnitZ()});
  joints_in.push_back({JointType::Helical, skew_axis});
  std::set<std::string> kinds;
  for (const auto& [type, axis] : joints_in)
    for (const Mat3& X : {e, rng.rotation()}) {
      const JointModel j = classify_joint(type, axis, X);
      kinds.insert(kind_name(j));
      const int nq = joint_nq(type), nv = joint_nv(type);
      for (int trial = 0; trial < 5; ++trial) {
        double q[7];
        for (int c = 0; c < nq; ++c) q[c] = rng.uniform(-3, 3);
        Mat3 R_ref, R;
        Vec3 p_ref, p;
        joint_motion(type, axis, q, R_ref, p_ref);
        std::visit([&](const auto& k) { k.motion(q, R, p); }, j);
        EXPECT_TRUE(near_rel(R, R_ref, 1e-14)) << kind_name(j);
        EXPECT_TRUE((p - p_ref).norm() <= 1e-14 * (1 + p_ref.norm())) << kind_name(j);
        const Mat3 Rj = rng.rotation(), Rb = Rj * R_ref;
        Mat6X G_ref(6, nv), G(6, nv);
        joint_subspace(type, axis, Rj, Rb, G_ref);
        std::visit([&](const auto& k) { k.subspace(Rj, Rb, G.leftCols(nv)); }, j);
        EXPECT_TRUE(near_rel(G, G_ref, 1e-14)) << kind_name(j);
      }
      for (int k = 0; k < nv; ++k)
        for (int m = 0; m < nv; ++m)
          std::visit([&](const auto& kind) { EXPECT_EQ(kind.carries(k, m), joint_carries(type, k, m)) << kind_name(j); },
                     j);
    }
  EXPECT_EQ(kinds.size(), std::variant_size_v<JointModel>);  // every kind was met
}

}  // namespace
}  // namespace soadyn::test
