// The parts of a run's loop (run_loop.hpp): its observers and its scheduler.
#include "run_loop.hpp"

#include "stiffness.hpp"

#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/multibody/text.hpp"

#include <Eigen/LU>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace soadyn::detail {

namespace {
std::string at_time(double t) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", t);
  return buf;
}
}  // namespace

void Observers::sample(const Sample& s) {
  for (LoopObserver* o : list_) o->on_sample(s);
}

void Observers::event(const LimitEvent& e) {
  summary_.events.push_back(e);
  for (LoopObserver* o : list_) o->on_event(e);
}

void Observers::progress() {
  for (LoopObserver* o : list_) o->on_progress(summary_);
}

void Observers::finish(double t, const VecX& y) {
  for (LoopObserver* o : list_) o->on_finish(t, y, summary_);
}

void EnergyBooks::on_sample(const Sample& s) {
  // E(0) with the impacts at t = 0 added back: their loss is in L
  if (!started_) E0_ = s.total + s.impact_loss, started_ = true;
  // the run's energy scale so far: a run from rest with E(0) = 0 is measured against the energy
  // its inputs and given motions bring in, not against the little T of its first samples
  scale_ = std::max({scale_, std::abs(E0_), s.kinetic, std::abs(s.work_inputs), std::abs(s.work_prescribed)});
  last_ = std::abs(s.total - E0_ - s.work_inputs - s.work_prescribed + s.impact_loss);
  max_ = std::max(max_, last_);
}

void EnergyBooks::write(RunSummary& r) const {
  const double scale = std::max(scale_, 1e-300);
  r.final_energy_balance_error = last_ / scale;
  r.max_energy_balance_error = max_ / scale;
}

LimitWatch::LimitWatch(const Model& m) : model_(m), past_at_(size_t(m.nv), -1.0), past_q_(size_t(m.nv), 0.0) {}

void LimitWatch::on_sample(const Sample& s) {
  const Model& m = model_;
  // q past lower − tol or upper + tol, tol a rounding of q's size
  for (int i = 0; i < m.nbodies; ++i) {
    if (m.nq_i[i] != 1 || m.nv_i[i] != 1) continue;
    const int k = m.idx_v[i];
    const double q = s.q(m.idx_q[i]), tol = 1e-9 * std::max(1.0, std::abs(q));
    if (past_at_[size_t(k)] < 0 && (q < m.lower[size_t(k)] - tol || q > m.upper[size_t(k)] + tol))
      past_at_[size_t(k)] = s.t, past_q_[size_t(k)] = q;
  }
}

void LimitWatch::on_finish(double, const VecX&, RunSummary& r) {
  const Model& m = model_;
  std::string past;
  for (int k = 0; k < m.nv; ++k)
    if (past_at_[size_t(k)] >= 0)
      past += (past.empty() ? "" : ", ") + m.v_names()[size_t(k)] + " (to " + short_number(past_q_[size_t(k)]) + " at t = " +
              short_number(past_at_[size_t(k)]) + " s; limits " + short_number(m.lower[size_t(k)]) + ", " +
              short_number(m.upper[size_t(k)]) + ")";
  if (!past.empty())
    r.warnings.push_back("joints past their limits, which this run does not enforce (simulation: limits: true "
                         "does): " + past);
}

void StiffnessCheck::on_finish(double t, const VecX& y, RunSummary& r) {
  if (method_ != Method::CvodeAdams || r.stats.steps < kStiffSteps || !(r.t_reached > 0)) return;
  // h̄ ρ: the mean step times the larger spectral radius of ∂f/∂y at the start and the end
  const double h = r.t_reached / double(r.stats.steps);
  const double rho = std::fmax(spectral_radius(sys_, 0.0, y0_), spectral_radius(sys_, t, y));
  if (!std::isfinite(rho)) return;  // neither state gave an estimate
  r.stiffness_index = h * rho;
  if (r.stiffness_index < kStiffIndex) return;
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "the run looks stiff: %ld cvode-adams steps of %.3g s on average, held by stability (mean step x the "
                "largest |eigenvalue| of df/dy, %.3g, is %.2g), not by accuracy; cvode-bdf (method: cvode-bdf, or "
                "--method cvode-bdf) takes its steps from the accuracy alone",
                r.stats.steps, h, rho, r.stiffness_index);
  r.stiffness_hint = buf;
}

void CallerObservers::on_sample(const Sample& s) {
  if (samples_) samples_->push_back(s);
  if (observer_) observer_->on_sample(s);
}

void CallerObservers::on_event(const LimitEvent& e) {
  if (observer_) observer_->on_event(e);
}

void CallerObservers::on_progress(RunSummary& r) {
  if (observer_) observer_->on_progress(r);
}

void CallerObservers::on_finish(double, const VecX&, RunSummary& r) {
  if (observer_) observer_->on_finish(r);
}

Scheduler::Scheduler(System& sys, const SimulationSettings& s, ControlFunction law, Observers& observers)
    : sys_(sys),
      t_end_(s.t_end),
      output_dt_(output_interval(s)),
      control_dt_(s.control_dt),
      outputs_(long(soadyn::output_count(s))),
      law_(std::move(law)),
      observers_(observers) {
  for (const PrescribedInput& p : sys.inputs.prescribed)
    for (const double c : p.target.corners())
      if (c > 0 && c < t_end_) corners_.push_back(c);
  std::sort(corners_.begin(), corners_.end());
  corners_.erase(std::unique(corners_.begin(), corners_.end()), corners_.end());
}

void Scheduler::add(EventKind& kind) {
  kinds_.push_back(&kind);
  offsets_.push_back(nroots_);
  nroots_ += kind.count();
}

// CVODE every output_dt; fixed-step methods (steps of exactly dt) every `stride` steps, output_dt =
// stride·dt, never between two steps (the k-th output lands on step k·stride, whose time it reports
// as k·output_dt, the time a CVODE run at that output_dt reports); both at t_end last
double Scheduler::output_time(long k) const { return k == outputs_ ? t_end_ : double(k) * output_dt_; }

void Scheduler::start(Integrator& integrator, double t, VecX& y) {
  if (law_) at_stop(t, y);
  for (EventKind* kind : kinds_) report(kind->start(t, y));
  if (law_ || !kinds_.empty()) integrator.restart(t, y);
}

double Scheduler::energy_lost() const {
  double lost = 0.0;
  for (const EventKind* kind : kinds_) lost += kind->energy_lost();
  return lost;
}

namespace {
bool same_time(double a, double b) { return std::abs(a - b) <= 1e-12 * std::max(1.0, std::abs(b)); }
}  // namespace

Schedule::Stop Scheduler::next_stop(double t_out) {
  // the next tick t_k = k · control_dt or the next corner: t_out itself within rounding, or before it
  const double tick = law_ ? double(ticks_) * control_dt_ : std::numeric_limits<double>::infinity();
  const double corner = next_corner_ < corners_.size() ? corners_[next_corner_] : std::numeric_limits<double>::infinity();
  const double next = std::min(tick, corner);
  if (same_time(next, t_out)) return {t_out, true};
  if (next < t_out) return {next, true};
  return {t_out, false};
}

void Scheduler::at_stop(double t, VecX& y) {
  // a corner: only the restart that follows
  while (next_corner_ < corners_.size() && (corners_[next_corner_] < t || same_time(corners_[next_corner_], t)))
    ++next_corner_;
  if (!law_ || !same_time(double(ticks_) * control_dt_, t)) return;
  // τ_c(t_k, q, v), held until the next tick
  sys_.control.setZero();
  sys_.expand(t, y.data());  // the model's q and v at (t, y)
  law_(t, sys_.q, sys_.v, sys_.control);
  ++ticks_;
}

void Scheduler::roots(double t, const double* y, double* g) {
  for (size_t j = 0; j < kinds_.size(); ++j) kinds_[j]->roots(t, y, g + offsets_[j]);
}

void Scheduler::at_roots(double t, VecX& y, const std::vector<int>& which) {
  // events that do not let time advance (a joint pinned between pushes) would loop for ever
  events_here_ = t == t_events_ ? events_here_ + 1 : 0;
  t_events_ = t;
  if (events_here_ > 100)
    throw SimulationError("joint limits: more than 100 events at t = " + at_time(t) + " s without time advancing", t);
  // each kind acts on its own roots, numbered from 0
  for (size_t j = 0; j < kinds_.size(); ++j) {
    which_.clear();
    const int lo = offsets_[j], hi = lo + kinds_[j]->count();
    for (const int r : which)
      if (r >= lo && r < hi) which_.push_back(r - lo);
    if (!which_.empty()) report(kinds_[j]->at_roots(t, y, which_));
  }
}

LoopSingularity::LoopSingularity(System& sys)
    : sys_(sys), data_(sys.model), ld_(sys.model, sys.inputs.loops), ydot_(sys.size()), zero_(VecX::Zero(sys.model.nv)) {}

void LoopSingularity::rows_at(const double* y) {
  // the state's q is the model's (loops and prescribed motion are not taken together)
  update_kinematics(sys_.model, data_, Eigen::Map<const VecX>(y, sys_.model.nq));
  update_velocities(sys_.model, data_, zero_);
  loop_rows(sys_.model, data_, sys_.inputs.loops, ld_);
}

void LoopSingularity::choose(const double* y) {
  rows_at(y);
  // the independent rows by pivoted QR of Kᵀ, then as many columns by pivoted QR of those rows
  Eigen::ColPivHouseholderQR<MatX> by_rows(ld_.K.transpose());
  by_rows.setThreshold(kLoopRankTolerance);
  const int r = int(by_rows.rank());
  rows_.assign(by_rows.colsPermutation().indices().data(), by_rows.colsPermutation().indices().data() + r);
  const MatX Kr = ld_.K(rows_, Eigen::all);
  Eigen::ColPivHouseholderQR<MatX> by_cols(Kr);
  cols_.assign(by_cols.colsPermutation().indices().data(), by_cols.colsPermutation().indices().data() + r);
}

void LoopSingularity::roots(double, const double* y, double* g) {
  rows_at(y);
  // det K[r, c] over the rows' norms: scale-free, its sign the block's orientation
  const MatX block = ld_.K(rows_, cols_);
  double scale = 1.0;
  for (const int i : rows_) scale *= std::max(ld_.K.row(i).norm(), 1e-300);
  g[0] = rows_.empty() ? 1.0 : block.determinant() / scale;
}

std::vector<LimitEvent> LoopSingularity::start(double, VecX& y) {
  choose(y.data());
  return {};
}

std::vector<LimitEvent> LoopSingularity::at_roots(double t, VecX& y, const std::vector<int>&) {
  sys_.rhs(t, y.data(), ydot_.data());  // a dead point: its check throws, naming t and the loop
  choose(y.data());                     // else another block serves from here
  return {};
}

void Scheduler::report(const std::vector<LimitEvent>& events) {
  for (const LimitEvent& e : events) observers_.event(e);
}

}  // namespace soadyn::detail
