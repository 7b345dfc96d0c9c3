// MuJoCo's RK4 on a fixed-base scenario, for the work-precision charts: the scenario is loaded by
// soadyn, written as MJCF (merged bodies, hinge/slide joints, full inertias), checked to give the
// same 𝓜 at the initial state, stepped with mj_step to t_end, and the final state printed as JSON.
//   soadyn_mujoco_rk4 SCENARIO.yaml DT T_END
// With --rollouts K: K rollouts of T_END / DT steps from K initial states (q0, v0 + 0.01 k), timed
// (wall clock) as a loop of mj_step and as soadyn's rollout() with rk4 on 1 and 2 threads; prints
// rollouts per second of each and the largest difference between their final states.
//   soadyn_mujoco_rk4 SCENARIO.yaml DT T_END --rollouts K
#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/sim/rollout.hpp"
#include "soadyn/io/scenario_file.hpp"

#include <mujoco/mujoco.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <sstream>
#include <string>

using namespace soadyn;

namespace {

std::string v3(const Vec3& v) {
  char b[128];
  std::snprintf(b, sizeof b, "%.17g %.17g %.17g", v.x(), v.y(), v.z());
  return b;
}

std::string mjcf(const Model& m) {
  std::ostringstream os;
  os << "<mujoco><option gravity=\"" << v3(m.gravity) << "\" integrator=\"RK4\">"
     << "<flag contact=\"disable\" limit=\"disable\" passive=\"disable\" constraint=\"disable\"/></option>"
     << "<compiler angle=\"radian\" balanceinertia=\"false\" boundmass=\"0\" boundinertia=\"0\"/><worldbody>";
  std::vector<int> open;  // bodies whose <body> is still open
  for (int i = 0; i < m.nbodies; ++i) {
    while (!open.empty() && open.back() != m.parent[i]) {
      os << "</body>";
      open.pop_back();
    }
    const Eigen::Quaterniond q(m.placement[i].R);
    const Mat3& I = m.inertia[i];
    char quat[160], inertia[300];
    std::snprintf(quat, sizeof quat, "%.17g %.17g %.17g %.17g", q.w(), q.x(), q.y(), q.z());
    std::snprintf(inertia, sizeof inertia, "%.17g %.17g %.17g %.17g %.17g %.17g", I(0, 0), I(1, 1), I(2, 2), I(0, 1),
                  I(0, 2), I(1, 2));
    os << "<body name=\"" << m.body_names[i] << "\" pos=\"" << v3(m.placement[i].p) << "\" quat=\"" << quat << "\">"
       << "<joint name=\"" << m.joint_names[i] << "\" type=\""
       << (m.joint_type[i] == JointType::Revolute ? "hinge" : "slide") << "\" axis=\"" << v3(m.axis[i]) << "\"/>"
       << "<inertial pos=\"" << v3(m.com[i]) << "\" mass=\"" << m.mass[i] << "\" fullinertia=\"" << inertia << "\"/>";
    open.push_back(i);
  }
  for (size_t k = 0; k < open.size(); ++k) os << "</body>";
  os << "</worldbody></mujoco>";
  return os.str();
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// K rollouts by mj_step against soadyn's rollout(), same model, method, step and initial states
int rollouts(const Scenario& sc, mjModel* mm, mjData* md, long steps, long K) {
  const Model& m = sc.model;
  MatX Y0(m.nq + m.nv, K);
  for (long k = 0; k < K; ++k) Y0.col(k) << sc.q0, (sc.v0.array() + 0.01 * double(k)).matrix();
  MatX final_mj(m.nq + m.nv, K);
  const auto t0 = std::chrono::steady_clock::now();
  for (long k = 0; k < K; ++k) {
    mj_resetData(mm, md);
    for (int i = 0; i < m.nq; ++i) md->qpos[i] = Y0(i, k);
    for (int i = 0; i < m.nv; ++i) md->qvel[i] = Y0(m.nq + i, k);
    for (long s = 0; s < steps; ++s) mj_step(mm, md);
    for (int i = 0; i < m.nq; ++i) final_mj(i, k) = md->qpos[i];
    for (int i = 0; i < m.nv; ++i) final_mj(m.nq + i, k) = md->qvel[i];
  }
  const double mujoco = double(K) / seconds_since(t0);
  RolloutSettings rs;
  rs.method = Method::Rk4;
  rs.dt = mm->opt.timestep;
  rs.steps = steps;
  rs.energies = false;
  MatX states(m.nq + m.nv, steps * K), energies(0, K);
  double per_second[2] = {0, 0};
  for (int threads : {1, 2}) {
    rs.threads = threads;
    const auto t1 = std::chrono::steady_clock::now();
    const RolloutReport rep = rollout(m, sc.inputs, Y0, nullptr, nullptr, rs, states, energies);
    per_second[threads - 1] = double(K) / seconds_since(t1);
    if (rep.completed != K) throw Error("soadyn's rollouts did not all complete: " + rep.status[0]);
  }
  double diff = 0;
  for (long k = 0; k < K; ++k) diff = std::max(diff, (states.col(k * steps + steps - 1) - final_mj.col(k)).cwiseAbs().maxCoeff());
  std::printf("{\"K\": %ld, \"steps\": %ld, \"dt\": %.9g, \"mujoco_rollouts_per_second\": %.6g, "
              "\"soadyn_rollouts_per_second_1_thread\": %.6g, \"soadyn_rollouts_per_second_2_threads\": %.6g, "
              "\"max_final_state_difference\": %.3g}\n",
              K, steps, rs.dt, mujoco, per_second[0], per_second[1], diff);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const bool many = argc == 6 && std::string(argv[4]) == "--rollouts";
  if (argc != 4 && !many) {
    std::fprintf(stderr, "usage: soadyn_mujoco_rk4 SCENARIO.yaml DT T_END [--rollouts K]\n");
    return 2;
  }
  try {
    mju_user_warning = [](const char*) {};  // counted in mjData::warning, checked below
    const Scenario sc = load_scenario(argv[1]);
    const Model& m = sc.model;
    if (m.has_free_joint() || !sc.inputs.empty()) throw Error("fixed-base scenes without inputs only");
    const double dt = std::atof(argv[2]), t_end = std::atof(argv[3]);
    const std::string xml = mjcf(m);
    mjVFS vfs;
    mj_defaultVFS(&vfs);
    mj_makeEmptyFileVFS(&vfs, "scene.xml", int(xml.size()));
    std::memcpy(vfs.filedata[vfs.nfile - 1], xml.data(), xml.size());
    char err[1000] = "";
    mjModel* mm = mj_loadXML("scene.xml", &vfs, err, sizeof err);
    mj_deleteVFS(&vfs);
    if (!mm) throw Error(std::string("MuJoCo: ") + err);
    mjData* md = mj_makeData(mm);
    const long steps = std::max(1L, std::lround(t_end / dt));
    mm->opt.timestep = t_end / double(steps);  // land on t_end exactly, as soadyn's fixed steps do
    for (int k = 0; k < m.nq; ++k) md->qpos[k] = sc.q0(k);
    for (int k = 0; k < m.nv; ++k) md->qvel[k] = sc.v0(k);
    // the same 𝓜 at the initial state
    mj_forward(mm, md);
    MatX Mmj(m.nv, m.nv);
    mj_fullM(mm, Mmj.data(), md->qM);
    Data d(m);
    update_kinematics(m, d, sc.q0);
    mass_matrix(m, d);
    const double diff = (Mmj - d.M).cwiseAbs().maxCoeff();
    if (!(diff <= 1e-9 * d.M.cwiseAbs().maxCoeff())) throw Error("MuJoCo's mass matrix differs by " + std::to_string(diff));
    if (many) {
      const int rc = rollouts(sc, mm, md, steps, std::atol(argv[5]));
      mj_deleteData(md);
      mj_deleteModel(mm);
      return rc;
    }
    const std::clock_t c0 = std::clock();
    for (long k = 0; k < steps; ++k) mj_step(mm, md);
    const double cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
    // MuJoCo resets an unstable run to its initial state and counts a warning: report a blow-up
    if (md->warning[mjWARN_BADQACC].number + md->warning[mjWARN_BADQVEL].number + md->warning[mjWARN_BADQPOS].number > 0) {
      std::fprintf(stderr, "soadyn_mujoco_rk4: MuJoCo's run blew up\n");
      return 3;
    }
    auto num = [](double x) { return std::isfinite(x) ? x : 1e308; };  // JSON has no NaN: a huge error
    std::printf("{\"cpu\": %.9g, \"steps\": %ld, \"q\": [", cpu, steps);
    for (int k = 0; k < m.nq; ++k) std::printf("%s%.17g", k ? ", " : "", num(md->qpos[k]));
    std::printf("], \"qd\": [");
    for (int k = 0; k < m.nv; ++k) std::printf("%s%.17g", k ? ", " : "", num(md->qvel[k]));
    std::printf("]}\n");
    mj_deleteData(md);
    mj_deleteModel(mm);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "soadyn_mujoco_rk4: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
