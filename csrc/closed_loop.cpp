#include "closed_loop.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "controllers.hpp"
#include "export/arena.hpp"
#include "controllers/laws/law.hpp"
#include "model/nominal.hpp"
#include "pin_calls.hpp"
#include "plant/stick_slip.hpp"
#include "subtasks/criterion.hpp"

// The allocation counter benchmarks/allocation_counter.cpp defines when it is preloaded
// (LD_PRELOAD): the calling thread's calls to the malloc family so far. Absent, this is null.
extern "C" __attribute__((weak, visibility("default"))) long nnrobust_allocations();

namespace nnrobust {

bool (*law_in_arena)(const LoopSpec &spec) = nullptr;

bool law_runs_in_arena(const LoopSpec &spec) { return arena_wrapped() && law_in_arena && law_in_arena(spec); }

namespace {
// The arena of a law's step, as an exported law's (csrc/export/law_api.cpp): a request it cannot
// hold goes to the system allocator, which the allocation counter then shows (loop_profile.py)
constexpr std::size_t law_arena_bytes = std::size_t{1} << 20;

double seconds_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
long allocations_now() { return nnrobust_allocations ? nnrobust_allocations() : 0; }
}  // namespace

PartClock::PartClock(LoopTrace &trace) : tr_(trace), last_(seconds_now()), allocations_(allocations_now()) {
  tr_.part_seconds = Vector::Zero(kLoopParts);
  tr_.part_allocations = Vector::Constant(kLoopParts, nnrobust_allocations ? 0.0 : unset);
}

void PartClock::lap(LoopPart part) {
  const double now = seconds_now();
  tr_.part_seconds[part] += now - last_;
  if (nnrobust_allocations) {
    const long count = allocations_now();
    tr_.part_allocations[part] += static_cast<double>(count - allocations_);
    allocations_ = count;
  }
  last_ = now;
}

namespace {

// Result.from_trace's per-sample quantities of the true robot at q: the chain points, the
// manipulability sqrt(det(J J^T)) of the task Jacobian and the weighted criterion h. `work` holds
// the Jacobians and products between calls (no allocation once sized).
void record_kinematics(LoadedModel &m, const LoopSpec &s, const Criteria &criteria, const Vector &q, long k,
                       LoopTrace &tr, KinematicsWork &work) {
  auto &model = m.model;
  auto &data = m.data;
  pin::computeJointJacobians(model, data, q);  // one kinematics pass: placements and Jacobians
  pin::updateFramePlacement(model, data, m.frame);
  const int joints = model.njoints - 1;
  for (int j = 0; j < joints; ++j) tr.chain.block<1, 3>(k, 3 * j) = data.oMi[j + 1].translation().transpose();
  tr.chain.block<1, 3>(k, 3 * joints) = data.oMf[m.frame].translation().transpose();
  work.J6.setZero(6, model.nv);
  pin::getFrameJacobian(model, data, m.frame, pinocchio::LOCAL_WORLD_ALIGNED, work.J6);
  work.J = work.J6.topRows(s.m);
  work.JJt.noalias() = work.J * work.J.transpose();
  tr.manipulability[k] = std::sqrt(std::max(det_small(work.JJt), 0.0));
  if (!s.criteria.empty()) {
    work.points = Eigen::Map<const Rows>(tr.chain.row(k).data(), joints + 1, 3);
    tr.h[k] = criteria.value(q, work.J, work.points);
  }
}

// simulation.period_substeps: the plant steps of one control period, cut for its step_rate.
int period_substeps(const LoopSpec &s, double speed) {
  const double needed = std::ceil(s.period * speed / s.max_step_rotation);
  return needed <= s.substeps ? s.substeps : static_cast<int>(std::min<double>(needed, s.max_period_substeps));
}

}  // namespace

SteppedLoop::SteppedLoop(LoadedModel &model, LoadedModel *nominal_model, const LoopSpec &s, bool with_law)
    : model_(model), s_(s), criteria_(std::make_unique<Criteria>(s)) {
  const int n = model.model.nv;
  const long steps = s.steps;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  tr_.q = Rows::Constant(steps, n, nan);
  tr_.dq = tr_.q;
  tr_.tau = tr_.q;
  tr_.tau_cmd = tr_.q;
  tr_.z = Rows::Constant(steps, s.z0.size(), nan);
  tr_.signals = Rows::Constant(steps, s.law_signals, nan);
  tr_.chain = Rows::Constant(steps, 3 * (model.model.njoints), nan);
  tr_.manipulability = Vector::Constant(steps, nan);
  tr_.h = tr_.manipulability;
  tr_.done = steps;
  if (with_law) {  // none on the hybrid loop, whose law is Python's
    nominal_ = make_nominal(s, nominal_model);
    controller_ = std::make_unique<Controller>(s, *nominal_);
    out_ = std::make_unique<Output>();
    out_->tau = Vector::Zero(n);
    out_->z = Vector::Zero(s.z0.size());
    out_->signals = Vector::Zero(s.law_signals);
    if (law_runs_in_arena(s)) {
      arena_ = std::make_unique<Arena>(law_arena_bytes);
      failure_.reserve(1023);
    }
  }
  plant_ = std::make_unique<Plant>(model, s);
  if (plant_->any_sticky() && !plant_->engine) stick_slip_ = std::make_unique<StickSlipIntegrator>(*plant_, s.v0);
  q_ = s.q0;
  v_ = s.v0;
  z_ = s.z0;
  tau_ = Vector::Zero(n);
  tau_cmd_ = Vector::Zero(n);
  commands_ = Rows::Zero(plant_->delay + 1, n);
  kinematics_.J6.setZero(6, n);  // record_kinematics's buffers, sized before any step
  kinematics_.J.setZero(s.m, n);
  kinematics_.JJt.setZero(s.m, s.m);
  kinematics_.points.setZero(model.model.njoints, 3);
  if (steps > 0) plant_->sensor.measure(0, q_, v_, qm_, vm_);
  if (s.profile) clock_ = std::make_unique<PartClock>(tr_);
}

SteppedLoop::~SteppedLoop() = default;

void SteppedLoop::wrong_sizes(Eigen::Index tau, Eigen::Index z, Eigen::Index signals) const {
  if (tau != q_.size() || z != z_.size())  // a law compiled apart may get them wrong
    throw std::length_error("the law " + s_.law + " returned " + std::to_string(tau) + " torques and a " +
                            "state of " + std::to_string(z) + " (needs " + std::to_string(q_.size()) + " and " +
                            std::to_string(z_.size()) + ")");
  throw std::length_error("the law " + s_.law + " returned " + std::to_string(signals) +
                          " signals; its Python twin declares " + std::to_string(s_.law_signals));
}

const Output &SteppedLoop::control() {
  if (!controller_) throw std::logic_error("SteppedLoop::control: this loop was built without its law");
  Output &kept = *out_;
  if (!arena_) {
    kept = controller_->compute(time(), qm_, vm_, z_);
    return kept;
  }
  // Every temporary of the law's step comes from the arena and is freed in the step; what leaves
  // it is copied into the loop's own buffers (sized in the constructor: no allocation) and an
  // error's text into failure_ (reserved), since nothing of the arena may outlive the step.
  Eigen::Index sizes[3] = {0, 0, 0};
  enum { none, invalid, length, logic, other } failed = none;
  {
    ArenaScope scope(*arena_);
    try {
      const Output out = controller_->compute(time(), qm_, vm_, z_);
      sizes[0] = out.tau.size(), sizes[1] = out.z.size(), sizes[2] = out.signals.size();
      if (sizes[0] == kept.tau.size() && sizes[1] == kept.z.size() && sizes[2] == kept.signals.size()) {
        kept.tau = out.tau;
        kept.z = out.z;
        kept.signals = out.signals;
      }
    } catch (const std::exception &err) {
      const std::size_t length_of = std::min(std::strlen(err.what()), failure_.capacity());
      failure_.assign(err.what(), length_of);
      failed = dynamic_cast<const std::invalid_argument *>(&err) ? invalid
               : dynamic_cast<const std::length_error *>(&err)   ? length
               : dynamic_cast<const std::logic_error *>(&err)    ? logic
                                                                 : other;
    } catch (...) {
      failure_.assign("unknown error");
      failed = other;
    }
  }
  switch (failed) {
    case invalid: throw std::invalid_argument(failure_);
    case length: throw std::length_error(failure_);
    case logic: throw std::logic_error(failure_);
    case other: throw std::runtime_error(failure_);
    case none: break;
  }
  if (arena_->live() != 0) {
    // blocks of the arena are held by the law: never freed to the system allocator, they and the
    // law are left allocated (a defect of the law, said once; the run ends here)
    const long held = arena_->live();
    (void)controller_.release();
    (void)nominal_.release();
    (void)arena_.release();
    throw std::logic_error("the law " + s_.law + " kept " + std::to_string(held) +
                           " block(s) of memory its step allocated: a law allocates what it keeps from one "
                           "step to the next in its constructor");
  }
  if (sizes[0] != kept.tau.size() || sizes[1] != kept.z.size() || sizes[2] != kept.signals.size())
    wrong_sizes(sizes[0], sizes[1], sizes[2]);
  return kept;
}

bool SteppedLoop::scale_gains(double position, double velocity) {
  if (!controller_) throw std::logic_error("SteppedLoop::scale_gains: this loop was built without its law");
  return controller_->law->scale_gains(position, velocity);
}

void SteppedLoop::observe(double *obs) const {
  if (!controller_) throw std::logic_error("SteppedLoop::observe: this loop was built without its law");
  const int n = model_.model.nv;
  const TaskReference &r = controller_->reference_kept(time(), qm_, vm_);  // the law's next compute takes it
  const Eigen::Index p = r.ts.x.size();  // the position rows: 2 planar, 3 spatial
  Eigen::Map<Vector> out(obs, observation_size());
  out.segment(0, n) = qm_;
  out.segment(n, n) = vm_;
  out.segment(2 * n, p) = r.ts.x - r.e.head(p);  // p_d = x - e: the desired position
  const Eigen::Index m = r.e.size();
  out.segment(2 * n + p, m) = r.e;
  out.segment(2 * n + p + m, m) = r.de;
  out.segment(2 * n + p + 2 * m, m) = r.dxd;
  out.segment(2 * n + p + 3 * m, m) = r.ddxd;
}

int SteppedLoop::observation_size() const {
  const int n = model_.model.nv, m = s_.m;
  return 2 * n + std::min(m, 3) + 4 * m;
}

void SteppedLoop::end(const std::string &status) {
  tr_.status = status;
  tr_.done = k_;
}

bool SteppedLoop::advance(const Output &out) {
  if (!running()) throw std::logic_error("SteppedLoop::advance: the run has ended (" + tr_.status + ")");
  if (out.tau.size() != q_.size() || out.z.size() != z_.size()) wrong_sizes(out.tau.size(), out.z.size(), 0);
  const long k = k_;
  const double t = time();
  Plant &plant = *plant_;
  Vector &q = q_, &v = v_;
  // the commands of the last delay + 1 periods, a ring: the applied one is the oldest (the first
  // command until delay + 1 were given)
  const long held = commands_.rows();
  commands_.row(commanded_ % held) = out.tau;
  ++commanded_;
  tau_cmd_ = commands_.row(commanded_ <= held ? 0 : commanded_ % held);
  const Vector &tau_cmd = tau_cmd_;
  plant.applied_torque(tau_cmd, v, tau_);
  const Vector &tau = tau_;
  tr_.q.row(k) = q;
  tr_.dq.row(k) = v;
  tr_.tau.row(k) = tau;
  tr_.tau_cmd.row(k) = tau_cmd;
  if (z_.size()) tr_.z.row(k) = z_;
  if (controller_) {
    if (out.signals.size() != s_.law_signals) wrong_sizes(q_.size(), z_.size(), out.signals.size());
    tr_.signals.row(k) = out.signals;
  }
  lap(kPartBookkeeping);
  if (q.allFinite()) record_kinematics(model_, s_, *criteria_, q, k, tr_, kinematics_);
  lap(kPartRecord);
  ++k_;
  if (!out.tau.allFinite() || !q.allFinite() || !v.allFinite()) {
    tr_.status = "diverged";
    tr_.divergence_index = k;
    tr_.done = k + 1;
    return false;
  }
  Eigen::Index worst;
  if (v.cwiseAbs().maxCoeff(&worst) > s_.max_speed) {
    tr_.status = "diverged";
    tr_.divergence_index = k;
    tr_.divergence_joint = static_cast<int>(worst);
    tr_.done = k + 1;
    return false;
  }
  z_ = out.z;
  lap(kPartBookkeeping);
  plant.begin_period(t);  // the loads held over this period
  if (plant.engine) {  // MuJoCo steps the plant; a state or torque it discarded ends the run
    if (!plant.engine->advance(t, tau, s_.period, *plant.disturbance, [&](int i) { return plant.load(i); }, q, v)) {
      tr_.status = "diverged";
      tr_.divergence_index = k;
      tr_.done = k + 1;
      return false;
    }
  } else {
    const int n_steps = period_substeps(s_, plant.step_rate(q, v, s_.period));
    tr_.refined_periods += n_steps != s_.substeps;
    const double h = s_.period / n_steps;
    if (stick_slip_) {  // simulation.simulate with the plant's stick-slip integrator
      for (int i = 0; i < n_steps; ++i) stick_slip_->advance(t + i * h, q, v, tau, h, i == 0);
    } else {
      Rk4Work &w = rk4_;  // the stages (k1q is v itself), sized once
      for (int i = 0; i < n_steps; ++i) {  // simulation._rk4_step with the torque held
        const double ti = t + i * h;
        w.k1v = plant.acceleration(ti, q, v, tau);
        w.k2q = v + 0.5 * h * w.k1v;
        w.q_stage = q + 0.5 * h * v;
        w.k2v = plant.acceleration(ti + 0.5 * h, w.q_stage, w.k2q, tau);
        w.k3q = v + 0.5 * h * w.k2v;
        w.q_stage = q + 0.5 * h * w.k2q;
        w.k3v = plant.acceleration(ti + 0.5 * h, w.q_stage, w.k3q, tau);
        w.k4q = v + h * w.k3v;
        w.q_stage = q + h * w.k3q;
        w.k4v = plant.acceleration(ti + h, w.q_stage, w.k4q, tau);
        q = q + (h / 6.0) * (v + 2.0 * w.k2q + 2.0 * w.k3q + w.k4q);
        v = v + (h / 6.0) * (w.k1v + 2.0 * w.k2v + 2.0 * w.k3v + w.k4v);
      }
    }
  }
  lap(kPartPlant);
  if (k_ < s_.steps) plant.sensor.measure(k_, q, v, qm_, vm_);  // the next instant's measurement
  lap(kPartMeasure);
  return k_ < s_.steps;
}

LoopTrace SteppedLoop::finish() {
  if (stick_slip_) {
    tr_.friction_events = stick_slip_->events_count();
    tr_.unresolved_events = stick_slip_->unresolved();
  }
  return std::move(tr_);
}

LoopTrace run_loop(LoadedModel &model, LoadedModel *nominal_model, const LoopSpec &s, bool (*interrupted)(),
                   const ExternalLaw *external) {
  SteppedLoop loop(model, nominal_model, s, external == nullptr);
  Output given;  // an external law's
  while (loop.running()) {
    const long k = loop.step();
    if (interrupted && k % 256 == 0 && k > 0 && interrupted()) {
      loop.end("interrupted");
      break;
    }
    loop.lap(kPartBookkeeping);  // the poll is the loop's, not the law's
    if (external) {
      given.z = loop.state();
      if (!(*external)(loop.time(), loop.measured_q(), loop.measured_v(), loop.state(), given.tau, given.z)) {
        loop.end("failed");
        break;
      }
      loop.lap(kPartLaw);
      loop.advance(given);
    } else {
      const Output &out = loop.control();
      loop.lap(kPartLaw);
      loop.advance(out);
    }
  }
  return loop.finish();
}

ControlStep twin_control(LoadedModel *nominal_model, const LoopSpec &s, double t, const Vector &q, const Vector &v,
                         const Vector &z) {
  const std::unique_ptr<Nominal> nominal = make_nominal(s, nominal_model);
  Controller controller(s, *nominal);
  const Output out = controller.compute(t, q, v, z);
  return {out.tau, out.z, out.signals};
}

Vector twin_criterion_gradient(LoadedModel *nominal_model, const LoopSpec &s, const Vector &q) {
  const std::unique_ptr<Nominal> nominal = make_nominal(s, nominal_model);
  const Criteria criteria(s);
  return criteria.gradient(*nominal, q, nominal->task_state(q, Vector::Zero(q.size())));
}

double twin_criterion_value(LoadedModel &robot, const LoopSpec &s, const Vector &q) {
  const Criteria criteria(s);
  LoopTrace tr;
  tr.chain = Rows::Zero(1, 3 * robot.model.njoints);
  tr.manipulability = tr.h = Vector::Constant(1, std::numeric_limits<double>::quiet_NaN());
  KinematicsWork work;
  record_kinematics(robot, s, criteria, q, 0, tr, work);
  return tr.h[0];
}

Vector twin_plant_acceleration(LoadedModel &model, const LoopSpec &s, double t, const Vector &q, const Vector &v,
                               const Vector &tau) {
  Plant plant{model, s};
  plant.begin_period(t);
  return plant.acceleration(t, q, v, tau);
}

namespace {
std::atomic<bool> batch_stop{false};
bool batch_stopped() { return batch_stop.load(); }
}  // namespace

std::vector<LoopTrace> run_batch(const std::vector<BatchItem> &items, int threads, bool (*interrupted)()) {
  std::vector<LoopTrace> traces(items.size());
  std::atomic<size_t> next{0};
  std::atomic<int> running{0};
  batch_stop = false;
  const int count = std::max(1, std::min<int>(threads, static_cast<int>(items.size())));
  std::vector<std::thread> pool;
  running = count;
  std::exception_ptr failure;  // the first error of any run, raised in the calling thread
  std::mutex failure_lock;
  for (int w = 0; w < count; ++w)
    pool.emplace_back([&]() {
      for (size_t i = next++; i < items.size(); i = next++) {
        try {
          traces[i] = run_loop(*items[i].plant, items[i].nominal, *items[i].spec, &batch_stopped);
        } catch (...) {
          const std::lock_guard<std::mutex> hold(failure_lock);
          if (!failure) failure = std::current_exception();
          batch_stop = true;
        }
      }
      --running;
    });
  while (running.load() > 0) {  // the calling thread watches for Ctrl-C and SIGTERM
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (interrupted && !batch_stop.load() && interrupted()) batch_stop = true;
  }
  for (auto &t : pool) t.join();
  batch_stop = false;
  if (failure) std::rethrow_exception(failure);
  return traces;
}

}  // namespace nnrobust
