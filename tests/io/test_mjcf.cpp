// MJCF import against MuJoCo itself: the same file compiled by mj_loadXML, 𝓜 from mj_fullM and
// the bias from qfrc_bias at seeded random states, against soadyn's model of it; frames of welded
// bodies and sites against MuJoCo's xpos/site_xpos; ignored features listed; errors located.
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/frames.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/io/mjcf.hpp"
#include "soadyn/io/scenario_file.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>

using namespace soadyn;
using ::testing::HasSubstr;

namespace {

const std::string kDir = SOADYN_SOURCE_DIR "/tests/data/mjcf/";

struct Mj {
  std::unique_ptr<mjModel, void (*)(mjModel*)> m{nullptr, mj_deleteModel};
  std::unique_ptr<mjData, void (*)(mjData*)> d{nullptr, mj_deleteData};
  explicit Mj(const std::string& path) {
    char error[1000] = "";
    m.reset(mj_loadXML(path.c_str(), nullptr, error, sizeof error));
    if (!m) throw std::runtime_error(error);
    m->opt.disableflags |= mjDSBL_CONTACT | mjDSBL_CONSTRAINT | mjDSBL_PASSIVE | mjDSBL_LIMIT;
    for (int k = 0; k < m->nv; ++k) m->dof_armature[k] = 0.0;  // rotor inertia: not soadyn's
    d.reset(mj_makeData(m.get()));
  }
};

// soadyn's (q, v) as MuJoCo's (qpos, qvel), and the map T with qvel = T v: identity but for a free
// joint, whose MuJoCo velocity is [linear (world); angular (body axes)] and soadyn's [ω; η̇] (world)
MatX to_mujoco(const Model& model, const MjcfModel& mj, const VecX& q, const VecX& v,
               mjData* d) {
  MatX T = MatX::Identity(model.nv, model.nv);
  for (int k = 0; k < model.nq; ++k) d->qpos[k] = q(k);
  for (const auto& [iq, offset] : mj.qpos0) d->qpos[iq] += offset;
  for (int i = 0; i < model.nbodies; ++i)
    if (model.joint_type[i] == JointType::Free) {
      const int iq = model.idx_q[i], iv = model.idx_v[i];
      const Mat3 R = Eigen::Quaterniond(q(iq + 3), q(iq + 4), q(iq + 5), q(iq + 6)).toRotationMatrix();
      T.block(iv, iv, 6, 6).setZero();
      T.block<3, 3>(iv, iv + 3) = Mat3::Identity();
      T.block<3, 3>(iv + 3, iv) = R.transpose();
    }
  const VecX qvel = T * v;
  for (int k = 0; k < model.nv; ++k) d->qvel[k] = qvel(k);
  return T;
}

// MuJoCo's qacc from soadyn's (q, v, q̈): the time derivative of qvel = T(q) v, T as in to_mujoco.
// For a free joint, MuJoCo's [ṗ (world); ω_b = Rᵀ ω] has the rate [p̈; Rᵀ ω̇ + (d/dt Rᵀ) ω] and
// d/dt(Rᵀ) ω = −Rᵀ ω̃ ω = 0: so qacc = T q̈ exactly.
VecX qacc_of(const Model& model, const VecX& q, const VecX& v, const VecX& qdd) {
  VecX out = qdd;
  (void)v;
  for (int i = 0; i < model.nbodies; ++i)
    if (model.joint_type[i] == JointType::Free) {
      const int iq = model.idx_q[i], iv = model.idx_v[i];
      const Mat3 R = Eigen::Quaterniond(q(iq + 3), q(iq + 4), q(iq + 5), q(iq + 6)).toRotationMatrix();
      // soadyn's second half is η̈, the origin's acceleration in the world: MuJoCo's p̈
      out.segment<3>(iv) = qdd.segment<3>(iv + 3);
      out.segment<3>(iv + 3) = R.transpose() * qdd.segment<3>(iv);
    }
  return out;
}

VecX random_state(const Model& model, std::mt19937& rng, VecX* v) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  VecX q = model.neutral_configuration();
  for (int k = 0; k < model.nq; ++k) q(k) += 0.8 * u(rng);
  model.normalize(q);
  *v = VecX::NullaryExpr(model.nv, [&] { return 2.0 * u(rng); });
  return q;
}

class AgainstMuJoCo : public ::testing::TestWithParam<std::string> {};

TEST_P(AgainstMuJoCo, MassMatrixAndBiasAtRandomStates) {
  const std::string path = kDir + GetParam();
  const MjcfModel mj = parse_mjcf(read_text_file(path), path, true);
  const Model& model = mj.model;
  Mj ref(path);
  ASSERT_EQ(model.nq, ref.m->nq);
  ASSERT_EQ(model.nv, ref.m->nv);
  Data data(model);
  std::mt19937 rng(7);
  MatX Mmj(model.nv, model.nv);
  double worst = 0.0, worst_qdd = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    VecX v;
    const VecX q = random_state(model, rng, &v);
    const MatX T = to_mujoco(model, mj, q, v, ref.d.get());
    mj_forward(ref.m.get(), ref.d.get());
    mj_fullM(ref.m.get(), Mmj.data(), ref.d->qM);  // symmetric: row or column order alike
    const MatX Mexpect = T.transpose() * Mmj * T;
    const VecX bias_mj = Eigen::Map<const VecX>(ref.d->qfrc_bias, model.nv);
    const VecX bexpect = T.transpose() * bias_mj;
    update_kinematics(model, data, q);
    mass_matrix(model, data);
    update_velocities(model, data, v);
    bias_forces(model, data);
    const double eM = (data.M - Mexpect).cwiseAbs().maxCoeff() / Mexpect.cwiseAbs().maxCoeff();
    const double eb = (data.bias - bexpect).cwiseAbs().maxCoeff() / (1.0 + bexpect.cwiseAbs().maxCoeff());
    EXPECT_LT(eM, 1e-12) << trial;
    EXPECT_LT(eb, 1e-11) << trial;
    // q̈ by each forward-dynamics route (the massless frames of a multi-joint body included)
    // against mj_forward's qacc (τ = 0; contacts, constraints and passive forces off), mapped back:
    // qacc = T q̈ + Ṫ v, and Ṫ v = [0; −ω × (Rᵀ ω)]-like terms vanish for the linear part of a free
    // joint only in world axes, so the comparison is in MuJoCo's coordinates
    const VecX qacc = Eigen::Map<const VecX>(ref.d->qacc, model.nv);
    double eq = 0.0;
    for (const FdMethod route : {FdMethod::Dense, FdMethod::Sparse, FdMethod::ArticulatedBody}) {
      forward_dynamics(model, data, VecX::Zero(model.nv), route);
      eq = std::max(eq, (qacc_of(model, q, v, data.qdd) - qacc).norm() / (1.0 + qacc.norm()));
    }
    EXPECT_LT(eq, 1e-9) << trial;
    worst = std::max({worst, eM, eb});
    worst_qdd = std::max(worst_qdd, eq);
  }
  std::printf("%s: largest relative difference from MuJoCo over 20 states: M and bias %.1e, qdd %.1e\n",
              GetParam().c_str(), worst, worst_qdd);
}

INSTANTIATE_TEST_SUITE_P(Files, AgainstMuJoCo, ::testing::Values("arm.xml", "floating.xml", "arm_twin.xml"));

// the same robot written as URDF and as MJCF: the same model
TEST(Mjcf, TheSameRobotAsUrdfAndAsMjcfHasTheSame_M_AndBias) {
  const Model urdf = load_scenario(SOADYN_SOURCE_DIR "/tests/data/urdf/arm.urdf").model;
  const Model mjcf = load_scenario(kDir + "arm_twin.xml").model;
  ASSERT_EQ(urdf.nq, mjcf.nq);
  ASSERT_EQ(urdf.joint_names, mjcf.joint_names);
  Data du(urdf), dm(mjcf);
  std::mt19937 rng(11);
  for (int trial = 0; trial < 10; ++trial) {
    VecX v;
    const VecX q = random_state(urdf, rng, &v);
    for (auto [model, data] : {std::pair{&urdf, &du}, std::pair{&mjcf, &dm}}) {
      update_kinematics(*model, *data, q);
      mass_matrix(*model, *data);
      update_velocities(*model, *data, v);
      bias_forces(*model, *data);
    }
    EXPECT_LT((du.M - dm.M).cwiseAbs().maxCoeff(), 1e-13 * du.M.cwiseAbs().maxCoeff()) << trial;
    EXPECT_LT((du.bias - dm.bias).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + du.bias.cwiseAbs().maxCoeff())) << trial;
  }
}

// welded bodies and sites are frames, where MuJoCo puts them
TEST(Mjcf, WeldedBodiesAndSitesAreFramesWhereMuJoCoPutsThem) {
  const std::string path = kDir + "arm.xml";
  const MjcfModel mj = parse_mjcf(read_text_file(path), path, true);
  const Model& model = mj.model;
  EXPECT_LT(model.body_index("camera"), 0);  // merged into fore
  Mj ref(path);
  Data data(model);
  std::mt19937 rng(3);
  VecX v;
  const VecX q = random_state(model, rng, &v);
  to_mujoco(model, mj, q, v, ref.d.get());
  mj_kinematics(ref.m.get(), ref.d.get());
  update_kinematics(model, data, q);
  for (const char* site : {"lens", "tool"}) {
    const int s = mj_name2id(ref.m.get(), mjOBJ_SITE, site);
    const int f = model.frame_index(site);
    ASSERT_GE(f, 0) << site;
    const Placement X = frame_placement(model, data, f);
    EXPECT_LT((X.p - Eigen::Map<const Vec3>(ref.d->site_xpos + 3 * s)).norm(), 1e-13) << site;
    const Mat3 R = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(ref.d->site_xmat + 9 * s);
    EXPECT_LT((X.R - R).norm(), 1e-13) << site;
  }
  const int b = mj_name2id(ref.m.get(), mjOBJ_BODY, "camera");
  const Placement X = frame_placement(model, data, model.frame_index("camera"));
  EXPECT_LT((X.p - Eigen::Map<const Vec3>(ref.d->xpos + 3 * b)).norm(), 1e-13);
}

TEST(Mjcf, StatesWhatItIgnoresAndMapsDampingAndStiffness) {
  const Scenario sc = load_scenario(kDir + "arm.xml");
  ASSERT_EQ(sc.model.warnings.size(), 1u);
  EXPECT_THAT(sc.model.warnings[0], HasSubstr("ignored: "));
  EXPECT_THAT(sc.model.warnings[0], HasSubstr("1 contact pair"));
  EXPECT_THAT(sc.model.warnings[0], HasSubstr("1 actuator"));
  EXPECT_THAT(sc.model.warnings[0], ::testing::Not(HasSubstr("range")));
  // a hinge's range is its limits, in soadyn's q (qpos − qpos0; degrees read as such)
  const int yaw = sc.model.idx_v[sc.model.joint_index("yaw")];
  EXPECT_NEAR(sc.model.lower[yaw], -170.0 * M_PI / 180.0, 1e-14);
  EXPECT_NEAR(sc.model.upper[yaw], 170.0 * M_PI / 180.0, 1e-14);
  const int shoulder = sc.model.idx_v[sc.model.joint_index("shoulder")];
  EXPECT_TRUE(std::isinf(sc.model.lower[shoulder]));
  ASSERT_EQ(sc.inputs.dampers.size(), 1u);
  EXPECT_EQ(sc.inputs.dampers[0].joint, "shoulder_roll");
  EXPECT_NEAR(sc.inputs.dampers[0].damping, 0.5, 1e-15);
  ASSERT_EQ(sc.inputs.springs.size(), 1u);
  EXPECT_NEAR(sc.inputs.springs[0].stiffness, 3.0, 1e-15);
  EXPECT_NEAR(sc.inputs.springs[0].rest, 5.0 * M_PI / 180.0, 1e-15);  // springref, degrees
  EXPECT_NEAR(sc.model.gravity.z(), -9.81, 1e-15);
  const Scenario fl = load_scenario(kDir + "floating.xml");
  EXPECT_THAT(fl.model.warnings.at(0), HasSubstr("1 DOF armature"));
  EXPECT_TRUE(fl.model.has_free_joint());
  EXPECT_NEAR(fl.q0(0), 0.1, 1e-15);  // the free joint starts at the drawn pose
}

// a scenario names an MJCF robot by model: (or urdf:, the same key)
TEST(Mjcf, AScenariosModelKeyNamesAnMjcfFile) {
  const Scenario sc = parse_scenario("model: arm.xml\nsimulation: {t_end: 0.1}\n", kDir + "scene.yaml");
  EXPECT_EQ(sc.model.nv, 6);
  EXPECT_EQ(sc.inputs.dampers.size(), 1u);
  try {
    parse_scenario("model: arm.xml\nurdf: arm.xml\n", kDir + "scene.yaml");
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("give either 'urdf' or 'model'"));
  }
}

// a site named as a body is said, not dropped silently; the other sites are frames
TEST(Mjcf, ASiteNamedAsABodyIsReported) {
  const std::string xml = R"(<mujoco><worldbody><site name="marker"/>
    <body name="a"><joint type="hinge"/><geom type="sphere" size="0.1" contype="0" conaffinity="0"/>
      <site name="a"/><site name="tip" pos="0 0 0.2"/></body></worldbody></mujoco>)";
  const MjcfModel mj = parse_mjcf(xml, "inline.xml", false);
  EXPECT_GE(mj.model.frame_index("tip"), 0);
  EXPECT_EQ(mj.model.frame_body[size_t(mj.model.frame_index("marker"))], -1);
  ASSERT_EQ(mj.model.warnings.size(), 1u);
  EXPECT_EQ(mj.model.warnings[0], "sites not kept as frames (a body has the name): a");
}

TEST(Mjcf, CompilerErrorsNameFileLineAndElement) {
  const std::string path = kDir + "bad_joint.xml";
  try {
    load_scenario(path);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr(path + ":4: joint: "));
    EXPECT_THAT(e.what(), HasSubstr("bogus"));
  }
}

}  // namespace
