#include "closed_loop.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "controllers.hpp"
#include "nominal.hpp"
#include "pin_calls.hpp"
#include "plant/stick_slip.hpp"
#include "subtasks/criterion.hpp"

namespace nnrobust {
namespace {

// Result.from_trace's per-sample quantities of the true robot at q: the chain points, the
// manipulability sqrt(det(J J^T)) of the task Jacobian and the weighted criterion h.
void record_kinematics(LoadedModel &m, const LoopSpec &s, const Criteria &criteria, const Vector &q, long k,
                       LoopTrace &tr) {
  auto &model = m.model;
  auto &data = m.data;
  pin::computeJointJacobians(model, data, q);  // one kinematics pass: placements and Jacobians
  pin::updateFramePlacement(model, data, m.frame);
  const int joints = model.njoints - 1;
  for (int j = 0; j < joints; ++j) tr.chain.block<1, 3>(k, 3 * j) = data.oMi[j + 1].translation().transpose();
  tr.chain.block<1, 3>(k, 3 * joints) = data.oMf[m.frame].translation().transpose();
  pin::Matrix6x J6 = pin::Matrix6x::Zero(6, model.nv);
  pin::getFrameJacobian(model, data, m.frame, pinocchio::LOCAL_WORLD_ALIGNED, J6);
  const Matrix J = J6.topRows(s.m);
  tr.manipulability[k] = std::sqrt(std::max(det_small(J * J.transpose()), 0.0));
  if (!s.criteria.empty()) {
    const Matrix points = Eigen::Map<const Rows>(tr.chain.row(k).data(), joints + 1, 3);
    tr.h[k] = criteria.value(q, J, points);
  }
}

// The controller's nominal model: the closed form, or the Pinocchio model `nominal_model`.
std::unique_ptr<Nominal> make_nominal(const LoopSpec &s, LoadedModel *nominal_model) {
  if (s.nominal == "closed-form")
    return std::make_unique<ClosedFormNominal>(Fields{"LoopSpec.nominal_params: the closed form", s.nominal_params});
  if (s.nominal != "pinocchio") throw std::invalid_argument("LoopSpec.nominal: unknown nominal model " + s.nominal);
  if (nominal_model == nullptr) throw std::invalid_argument("the nominal model 'pinocchio' needs its model");
  return std::make_unique<PinocchioNominal>(*nominal_model, s.m);
}

// simulation.period_substeps: the plant steps of one control period, cut for its step_rate.
int period_substeps(const LoopSpec &s, double speed) {
  const double needed = std::ceil(s.period * speed / s.max_step_rotation);
  return needed <= s.substeps ? s.substeps : static_cast<int>(std::min<double>(needed, s.max_period_substeps));
}

}  // namespace

LoopTrace run_loop(LoadedModel &model, LoadedModel *nominal_model, const LoopSpec &s, bool (*interrupted)(),
                   const ExternalLaw *external) {
  const int n = model.model.nv;
  const long steps = s.steps;
  LoopTrace tr;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  tr.q = Rows::Constant(steps, n, nan);
  tr.dq = tr.q;
  tr.tau = tr.q;
  tr.tau_cmd = tr.q;
  tr.z = Rows::Constant(steps, s.z0.size(), nan);
  tr.signals = Rows::Constant(steps, s.law_signals, nan);
  tr.chain = Rows::Constant(steps, 3 * (model.model.njoints), nan);
  tr.manipulability = Vector::Constant(steps, nan);
  tr.h = tr.manipulability;
  const Criteria criteria(s);  // h, recorded on the true robot
  std::unique_ptr<Nominal> nominal;
  std::optional<Controller> controller;  // none on the hybrid loop, whose law is `external`
  if (!external) {
    nominal = make_nominal(s, nominal_model);
    controller.emplace(s, *nominal);
  }
  Plant plant{model, s};
  std::unique_ptr<StickSlipIntegrator> stick_slip;
  if (plant.any_sticky() && !plant.engine) stick_slip = std::make_unique<StickSlipIntegrator>(plant, s.v0);
  Vector q = s.q0, v = s.v0, z = s.z0, tau = Vector::Zero(n), qm, vm;
  std::deque<Vector> commands;
  tr.done = steps;
  for (long k = 0; k < steps; ++k) {
    if (interrupted && k % 256 == 0 && k > 0 && interrupted()) {
      tr.status = "interrupted";
      tr.done = k;
      break;
    }
    const double t = static_cast<double>(k) * s.period;
    plant.sensor.measure(k, q, v, qm, vm);
    Output out;
    if (external) {
      out.z = z;
      if (!(*external)(t, qm, vm, z, out.tau, out.z)) {
        tr.status = "failed";
        tr.done = k;
        break;
      }
    } else {
      out = controller->compute(t, qm, vm, z);
    }
    commands.push_back(out.tau);
    if (static_cast<int>(commands.size()) > plant.delay + 1) commands.pop_front();
    const Vector tau_cmd = commands.front();
    tau = plant.applied_torque(tau_cmd, v);
    tr.q.row(k) = q;
    tr.dq.row(k) = v;
    tr.tau.row(k) = tau;
    tr.tau_cmd.row(k) = tau_cmd;
    if (z.size()) tr.z.row(k) = z;
    if (!external) {
      if (out.signals.size() != s.law_signals)
        throw std::length_error("the law " + s.law + " returned " + std::to_string(out.signals.size()) +
                                " signals; its Python twin declares " + std::to_string(s.law_signals));
      tr.signals.row(k) = out.signals;
    }
    if (q.allFinite()) record_kinematics(model, s, criteria, q, k, tr);
    if (!out.tau.allFinite() || !q.allFinite() || !v.allFinite()) {
      tr.status = "diverged";
      tr.divergence_index = k;
      tr.done = k + 1;
      break;
    }
    Eigen::Index worst;
    if (v.cwiseAbs().maxCoeff(&worst) > s.max_speed) {
      tr.status = "diverged";
      tr.divergence_index = k;
      tr.divergence_joint = static_cast<int>(worst);
      tr.done = k + 1;
      break;
    }
    z = out.z;
    plant.begin_period(t);  // the loads held over this period
    if (plant.engine) {  // MuJoCo steps the plant; a state or torque it discarded ends the run
      if (!plant.engine->advance(t, tau, s.period, plant.disturbance, [&](int i) { return plant.load(i); }, q, v)) {
        tr.status = "diverged";
        tr.divergence_index = k;
        tr.done = k + 1;
        break;
      }
      continue;
    }
    const int n_steps = period_substeps(s, plant.step_rate(q, v, s.period));
    tr.refined_periods += n_steps != s.substeps;
    const double h = s.period / n_steps;
    if (stick_slip) {  // simulation.simulate with the plant's stick-slip integrator
      for (int i = 0; i < n_steps; ++i) stick_slip->advance(t + i * h, q, v, tau, h, i == 0);
      continue;
    }
    for (int i = 0; i < n_steps; ++i) {  // simulation._rk4_step with the torque held
      const double ti = t + i * h;
      const Vector k1q = v, k1v = plant.acceleration(ti, q, v, tau);
      const Vector k2q = v + 0.5 * h * k1v, k2v = plant.acceleration(ti + 0.5 * h, q + 0.5 * h * k1q, k2q, tau);
      const Vector k3q = v + 0.5 * h * k2v, k3v = plant.acceleration(ti + 0.5 * h, q + 0.5 * h * k2q, k3q, tau);
      const Vector k4q = v + h * k3v, k4v = plant.acceleration(ti + h, q + h * k3q, k4q, tau);
      q = q + (h / 6.0) * (k1q + 2.0 * k2q + 2.0 * k3q + k4q);
      v = v + (h / 6.0) * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    }
  }
  if (stick_slip) {
    tr.friction_events = stick_slip->events_count();
    tr.unresolved_events = stick_slip->unresolved();
  }
  return tr;
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
  record_kinematics(robot, s, criteria, q, 0, tr);
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
