// simulate(sc, options) (run.hpp): the one-call run returns the samples an observer sees, as
// columns; writes the run file `soadyn run -o` writes; refuses an output before touching anything.
#include "soadyn/io/run.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/io/run_file.hpp"

#include "test_util.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace soadyn;

namespace {

const std::string kDir = SOADYN_SOURCE_DIR "/scenarios/";

std::string tmp(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("soadyn_options_" + std::to_string(getpid()) + "_" + name)).string();
}

std::string contents(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Keeps what an observer is told, to compare with the Trajectory.
struct Kept : RunObserver {
  std::vector<Sample> samples;
  int finished = 0;
  void on_sample(const Sample& s) override { samples.push_back(s); }
  void on_finish(const RunSummary&) override { ++finished; }
};

}  // namespace

// Every column of the Trajectory holds what the observer was told, sample for sample, body for
// body; sample(k) gives it back; the summary is the run's, with the scenario's own settings.
TEST(SimulateOptions, TrajectoryHoldsWhatTheObserverSaw) {
  const Scenario sc = load_scenario(kDir + "satellite_two_arrays.yaml");
  Kept kept;
  SimulateOptions o;
  o.observer = &kept;
  const Trajectory tr = simulate(sc, o);
  ASSERT_TRUE(tr.summary.completed) << tr.summary.status;
  EXPECT_EQ(kept.finished, 1);
  ASSERT_EQ(tr.size(), Eigen::Index(kept.samples.size()));
  ASSERT_GT(tr.size(), 10);
  EXPECT_NEAR(tr.t(tr.size() - 1), sc.simulation.t_end, 1e-12);
  EXPECT_EQ(tr.q.cols(), sc.model.nq);
  EXPECT_EQ(tr.body_position.cols(), 3 * sc.model.nbodies);
  EXPECT_EQ(tr.joint_names, sc.model.joint_names);
  for (Eigen::Index k = 0; k < tr.size(); k += 7) {
    const Sample& s = kept.samples[size_t(k)];
    EXPECT_EQ(tr.t(k), s.t);
    // copies, bit for bit
    EXPECT_EQ(tr.q.row(k).transpose(), s.q);
    EXPECT_EQ(tr.v.row(k).transpose(), s.qd);
    EXPECT_EQ(tr.total_energy(k), s.total);
    EXPECT_EQ(tr.angular_momentum.row(k).transpose(), s.angular);
    for (int i = 0; i < sc.model.nbodies; ++i) {
      EXPECT_EQ(Vec3(tr.body_position.row(k).segment<3>(3 * i)), Vec3(s.body_position.col(i))) << "body " << i;
      EXPECT_EQ(Eigen::Vector4d(tr.body_orientation.row(k).segment<4>(4 * i)), Eigen::Vector4d(s.body_orientation.col(i)));
    }
    const Sample back = tr.sample(k);
    EXPECT_EQ(back.q, s.q);
    EXPECT_EQ(back.body_com, s.body_com);
    EXPECT_EQ(back.body_orientation, s.body_orientation);
  }
  // the balance error the Trajectory computes from its columns is the run's own books' (simulate.cpp)
  const VecX b = tr.balance_error();
  EXPECT_NEAR(b.cwiseAbs().maxCoeff(), tr.summary.max_energy_balance_error, 1e-12);
  EXPECT_NEAR(std::abs(b(b.size() - 1)), tr.summary.final_energy_balance_error, 1e-12);
  // no torques, no dampers: the balance is the energy's drift
  EXPECT_LT((tr.energy_error() - b).cwiseAbs().maxCoeff(), 1e-15);
}

// The run file holds the rows the Trajectory holds; with keep_samples = false the file alone.
TEST(SimulateOptions, OutputFileHoldsTheTrajectory) {
  const Scenario sc = load_scenario(kDir + "double_pendulum.yaml");
  const std::string out = tmp("pendulum.h5");
  std::filesystem::remove(out);
  SimulateOptions o;
  o.settings = sc.simulation;
  o.settings->t_end = 0.5;
  o.output = out;
  const Trajectory tr = simulate(sc, o);
  ASSERT_TRUE(tr.summary.completed) << tr.summary.status;
  const RunContents f = read_run_file(out);
  ASSERT_EQ(f.rows(), tr.size());
  const MatX& q = f.values("/q");
  ASSERT_EQ(q.rows(), tr.size());
  EXPECT_LT((q - MatX(tr.q)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_NEAR(f.solver.max_energy_balance_error, tr.summary.max_energy_balance_error, 1e-15);
  EXPECT_FALSE(std::filesystem::exists(out + ".lock"));

  o.keep_samples = false;
  o.force = false;  // a run file may be replaced by a run file
  const Trajectory none = simulate(sc, o);
  EXPECT_TRUE(none.summary.completed);
  EXPECT_EQ(none.size(), 0);
  EXPECT_EQ(read_run_file(out).rows(), tr.size());
  std::filesystem::remove(out);
}

// A refused output touches nothing: the scenario itself, a foreign file, a file over the size
// limit, a directory that does not exist.
TEST(SimulateOptions, RefusedOutputTouchesNothing) {
  const std::string scene = tmp("scene.yaml"), foreign = tmp("notes.txt"), big = tmp("big.h5");
  std::filesystem::copy_file(kDir + "double_pendulum.yaml", scene, std::filesystem::copy_options::overwrite_existing);
  { std::ofstream(foreign) << "a user's notes\n"; }
  std::filesystem::remove(big);
  const Scenario sc = load_scenario(scene);
  const std::string before = contents(scene);
  SimulateOptions o;
  o.output = scene;
  EXPECT_THROW(simulate(sc, o), Error);
  o.force = true;  // an input is never an output, forced or not
  EXPECT_THROW(simulate(sc, o), Error);
  EXPECT_EQ(contents(scene), before);
  o.force = false;
  o.output = foreign;
  EXPECT_THROW(simulate(sc, o), Error);
  EXPECT_EQ(contents(foreign), "a user's notes\n");
  o.output = big;
  o.max_output_bytes = 1000;
  try {
    simulate(sc, o);
    ADD_FAILURE() << "a run over max_output_bytes was not refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(big), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("max_output_bytes"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(big));
  EXPECT_FALSE(std::filesystem::exists(big + ".lock"));
  // bad settings are refused before the output is looked at
  o.max_output_bytes = 1e12;
  o.settings = sc.simulation;
  o.settings->t_end = -1;
  EXPECT_THROW(simulate(sc, o), Error);
  EXPECT_FALSE(std::filesystem::exists(big));
  std::filesystem::remove(scene);
  std::filesystem::remove(foreign);
}

// A controller in the options: its τ is in the control column at every sample (continuous: τ(t, q, v)
// of that sample), and one that throws ends the run there with what it said, samples kept.
TEST(SimulateOptions, ControllerTorquesAreLoggedAndAFailureEndsTheRun) {
  const Scenario sc = load_scenario(kDir + "three_link_arm.yaml");
  const int nv = sc.model.nv;
  const VecX target = VecX::Constant(nv, 0.3);
  SimulateOptions o;
  o.settings = sc.simulation;
  o.settings->t_end = 0.4;
  o.settings->control_dt = 0;  // continuous
  o.controller = [&](double, const VecX& q, const VecX& v, Eigen::Ref<VecX> tau) { tau += 20 * (target - q) - 2 * v; };
  const Trajectory tr = simulate(sc, o);
  ASSERT_TRUE(tr.summary.completed) << tr.summary.status;
  ASSERT_EQ(tr.control.cols(), nv);
  for (Eigen::Index k = 0; k < tr.size(); ++k) {
    const VecX expected = 20 * (target - tr.q.row(k).transpose()) - 2 * tr.v.row(k).transpose();
    EXPECT_LT((tr.control.row(k).transpose() - expected).norm(), 1e-9 * (1 + expected.norm())) << "sample " << k;
  }
  EXPECT_GT(tr.control.cwiseAbs().maxCoeff(), 1.0);

  o.controller = [](double t, const VecX&, const VecX&, Eigen::Ref<VecX>) {
    if (t > 0.1) throw std::runtime_error("the plant went away");
  };
  const Trajectory failed = simulate(sc, o);
  EXPECT_FALSE(failed.summary.completed);
  EXPECT_NE(failed.summary.status.find("the plant went away"), std::string::npos) << failed.summary.status;
  ASSERT_GT(failed.size(), 1);
  EXPECT_LT(failed.t(failed.size() - 1), 0.11);
}
