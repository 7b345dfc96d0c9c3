// The parts of a run's loop (simulate.cpp): the scheduler, which owns the output grid, the control
// ticks and the events and is the Schedule the integrator steps through (integrators.hpp); and the
// observers attached to the loop: the caller's (the HDF5 log, a Trajectory's recorder, a vector of
// samples), the energy books, the watch on limits not enforced and the stiffness assessment.
// Internal.
#pragma once

#include "soadyn/sim/limits.hpp"
#include "soadyn/sim/simulate.hpp"

#include <vector>

namespace soadyn::detail {

// What the loop tells each observer, in the order attached: every logged sample, every event
// (before the next sample), the run's progress after each output, and its end with the state it
// ended at.  The summary is passed to be added to: observers attached before the caller's fill
// their part of it before the caller's are told.
class LoopObserver {
 public:
  virtual ~LoopObserver() = default;
  virtual void on_sample(const Sample&) {}
  virtual void on_event(const LimitEvent&) {}
  virtual void on_progress(RunSummary&) {}
  virtual void on_finish(double /*t*/, const VecX& /*y*/, RunSummary&) {}
};

// The observers of one run, told in turn; each event is also kept in the summary.
class Observers {
 public:
  explicit Observers(RunSummary& summary) : summary_(summary) {}
  void attach(LoopObserver& o) { list_.push_back(&o); }
  void sample(const Sample& s);
  void event(const LimitEvent& e);
  void progress();
  void finish(double t, const VecX& y);

 private:
  RunSummary& summary_;
  std::vector<LoopObserver*> list_;
};

// The energy balance's error at each sample, |E(t) − E(0) − W(t) − W_p(t) + L(t)|, E(0) the first
// sample's (before any impact there: the energy it took is in L); its maximum and last value go into
// the summary relative to the run's energy scale so far, max(|E(0)|, peak T, peak |W|, peak |W_p|).
class EnergyBooks : public LoopObserver {
 public:
  void on_sample(const Sample& s) override;
  void on_progress(RunSummary& r) override { write(r); }
  void on_finish(double, const VecX&, RunSummary& r) override { write(r); }

 private:
  void write(RunSummary& r) const;
  bool started_ = false;
  double E0_ = 0.0, scale_ = 0.0, max_ = 0.0, last_ = 0.0;  // max_, last_: J, before scaling
};

// Limits off on a model with limits: the first sample past each 1-DOF joint's bound, said in one
// warning at the end.
class LimitWatch : public LoopObserver {
 public:
  explicit LimitWatch(const Model& model);
  void on_sample(const Sample& s) override;
  void on_finish(double t, const VecX& y, RunSummary& r) override;

 private:
  const Model& model_;
  std::vector<double> past_at_, past_q_;  // t and q of the first sample past, t < 0: none
};

// A cvode-adams run of many steps whose mean step h̄ sat at the edge of stability, h̄ ρ(∂f/∂y) ≥
// kStiffIndex (stiffness.hpp): the summary says so once and names cvode-bdf.
class StiffnessCheck : public LoopObserver {
 public:
  StiffnessCheck(System& sys, Method method, const VecX& y0) : sys_(sys), method_(method), y0_(y0) {}
  void on_finish(double t, const VecX& y, RunSummary& r) override;

 private:
  System& sys_;
  Method method_;
  VecX y0_;
};

// The caller's: every sample into a vector, and a RunObserver told everything (nullptr: none).
class CallerObservers : public LoopObserver {
 public:
  CallerObservers(RunObserver* observer, std::vector<Sample>* samples) : observer_(observer), samples_(samples) {}
  void on_sample(const Sample& s) override;
  void on_event(const LimitEvent& e) override;
  void on_progress(RunSummary& r) override;
  void on_finish(double t, const VecX& y, RunSummary& r) override;

 private:
  RunObserver* observer_;
  std::vector<Sample>* samples_;
};

// One kind of event the scheduler watches (joint limits now): root functions of (t, y), what
// happens where they are at the start and where one crosses zero (y changed in place), each event
// reported, and the kinetic energy the events have taken so far (L(t), in the energy balance).
class EventKind {
 public:
  virtual ~EventKind() = default;
  virtual int count() const = 0;
  virtual void roots(double t, const double* y, double* g) = 0;
  virtual std::vector<LimitEvent> start(double t, VecX& y) = 0;
  virtual std::vector<LimitEvent> at_roots(double t, VecX& y, const std::vector<int>& which) = 0;
  virtual double energy_lost() const = 0;
};

// The joint limits (limits.hpp) as events of a System.
class LimitEvents : public EventKind {
 public:
  LimitEvents(JointLimits& limits, System& sys) : limits_(limits), sys_(sys) {}
  int count() const override { return limits_.count(); }
  void roots(double t, const double* y, double* g) override { limits_.roots(sys_, t, y, g); }
  std::vector<LimitEvent> start(double t, VecX& y) override { return limits_.start(sys_, t, y); }
  std::vector<LimitEvent> at_roots(double t, VecX& y, const std::vector<int>& which) override {
    return limits_.on_roots(sys_, t, y, which);
  }
  double energy_lost() const override { return limits_.energy_lost(); }

 private:
  JointLimits& limits_;
  System& sys_;
};

// A dead point of the closed loops (loops.hpp) as an event, for the methods that locate events
// (CVODE): g = det K[r, c] / Π |K[r_i, :]|, the square block of K's rows r and columns c (as many
// as A's rank, picked by pivoted QR: the best-conditioned block) chosen at the start and again at
// each root.  Its sign changes where that block turns singular: at a dead point, where every
// such block does (K loses rank: at the root, located to CVODE's precision, System::rhs's check
// stops the run naming t and the loop), or where another block would serve (picked there, the
// run goes on).  Without it the steps stride over a dead point (A's margin falls as the square of
// the distance to it).
class LoopSingularity : public EventKind {
 public:
  explicit LoopSingularity(System& sys);
  int count() const override { return 1; }
  void roots(double t, const double* y, double* g) override;
  std::vector<LimitEvent> start(double t, VecX& y) override;
  std::vector<LimitEvent> at_roots(double t, VecX& y, const std::vector<int>& which) override;
  double energy_lost() const override { return 0.0; }

 private:
  void rows_at(const double* y);  // K at y's q into ld_
  void choose(const double* y);   // rows_ and cols_ at y
  System& sys_;
  Data data_;
  LoopData ld_;
  std::vector<int> rows_, cols_;
  VecX ydot_, zero_;  // zero_: the velocities K is taken at (K does not depend on them)
};

// The run's schedule: the output grid (outputs every output_interval, the last at t_end), the
// control ticks of a sampled controller (τ_c(t_k, q, v) held in System::control from tick
// k = t / control_dt on), the corners of prescribed motions and the events of its event kinds,
// whose root functions it lays end to end.
class Scheduler : public Schedule {
 public:
  // `law`: the sampled controller (empty: none, or continuous); each event goes to `observers`
  Scheduler(System& sys, const SimulationSettings& settings, ControlFunction law, Observers& observers);
  void add(EventKind& kind);
  // outputs k = 1 … output_count(), at output_time(k)
  long output_count() const { return outputs_; }
  double output_time(long k) const;
  // at t = 0, before the first sample: the first control tick, the events already there, and a
  // restart of the integrator when either may have changed what it integrates
  void start(Integrator& integrator, double t, VecX& y);
  long control_ticks() const { return ticks_; }
  double energy_lost() const;  // L(t): the events' so far

  Stop next_stop(double t_out) override;
  void at_stop(double t, VecX& y) override;
  bool exact_stops() const override { return bool(law_) || !corners_.empty(); }
  int root_count() const override { return nroots_; }
  void roots(double t, const double* y, double* g) override;
  void at_roots(double t, VecX& y, const std::vector<int>& which) override;

 private:
  void report(const std::vector<LimitEvent>& events);

  System& sys_;
  double t_end_, output_dt_, control_dt_;
  long outputs_;
  ControlFunction law_;
  Observers& observers_;
  std::vector<EventKind*> kinds_;
  std::vector<int> offsets_;  // kinds_[j]'s first root function
  int nroots_ = 0;
  long ticks_ = 0;            // control ticks taken: the next one at ticks_ · control_dt
  // the prescribed motions' corners after t = 0 (JointTarget::corners), in order: the steps end
  // at each (the integrator restarts there, so that no step strides over a slew that has not
  // begun), next_corner_ the next one ahead
  std::vector<double> corners_;
  size_t next_corner_ = 0;
  std::vector<int> which_;    // one kind's roots, at_roots' scratch
  long events_here_ = 0;      // events in a row at t_events_, time not advancing
  double t_events_ = -1.0;
};

}  // namespace soadyn::detail
