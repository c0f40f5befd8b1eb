#include "learning.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "controllers.hpp"

namespace nnrobust {

bool step_action(SteppedLoop &loop, const double *a, const Vector &scale, int mode) {
  const Vector command = Eigen::Map<const Vector>(a, scale.size()).cwiseMax(-1.0).cwiseMin(1.0).cwiseProduct(scale);
  return apply_command(loop, command, mode);
}

bool apply_command(SteppedLoop &loop, const Vector &command, int mode) {
  Output out;
  if (mode == ACTION_GAINS) {
    if (command.size() != 2 || !loop.scale_gains(std::exp(command[0]), std::exp(command[1])))
      throw std::invalid_argument("gains mode: the law needs position and velocity gains and the action 2 entries");
    out = loop.control();
  } else if (mode == ACTION_RESIDUAL) {
    out = loop.control();
    out.tau += command;
  } else {
    out.tau = command;
    out.z = loop.state();
    out.signals = Vector::Constant(loop.signal_count(), std::numeric_limits<double>::quiet_NaN());
  }
  return loop.advance(out);
}

double period_reward(const RewardSpec &spec, const double *obs, const Vector &applied, double size, int m) {
  const Eigen::Index n = applied.size(), p = std::min(m, 3);
  const Eigen::Map<const Vector> q(obs, n), dq(obs + n, n), e(obs + 2 * n + p, p);
  double beyond = 0.0;
  for (Eigen::Index i = 0; i < n; ++i)
    beyond += (q[i] < spec.lower[i] || q[i] > spec.upper[i] || std::abs(dq[i]) > spec.speed_limit[i]) ? 1.0 : 0.0;
  const double effort = applied.cwiseQuotient(spec.torque_limit).squaredNorm() / static_cast<double>(n);
  return -(spec.error * e.norm() / size + spec.effort * effort + spec.limits * beyond / static_cast<double>(n));
}

StepPool::StepPool(int threads) {
  for (int w = 1; w < std::max(1, threads); ++w) workers_.emplace_back([this] { serve(); });
}

StepPool::~StepPool() {
  {
    const std::lock_guard<std::mutex> hold(lock_);
    stop_ = true;
  }
  start_.notify_all();
  for (auto &w : workers_) w.join();
}

void StepPool::run(size_t count, const std::function<void(size_t)> &job) {
  if (workers_.empty() || count < 2) {  // the calling thread alone: no wake-up
    for (size_t i = 0; i < count; ++i) job(i);
    return;
  }
  {
    const std::lock_guard<std::mutex> hold(lock_);
    job_ = &job;
    count_ = count;
    next_ = 0;
    busy_ = static_cast<int>(workers_.size());
    failure_ = nullptr;
    ++generation_;
    posted_.store(generation_, std::memory_order_release);
  }
  start_.notify_all();
  work();
  // the workers finish within microseconds of the caller (the same blocks of work): poll for them
  // a little before sleeping, since a wake-up from a condition variable can take longer than a step
  const auto spin_until = std::chrono::steady_clock::now() + std::chrono::microseconds(SPIN_MICROSECONDS);
  while (busy_.load(std::memory_order_acquire) != 0 && std::chrono::steady_clock::now() < spin_until)
    std::this_thread::yield();
  std::unique_lock<std::mutex> hold(lock_);
  done_.wait(hold, [this] { return busy_.load(std::memory_order_acquire) == 0; });
  job_ = nullptr;
  if (failure_) std::rethrow_exception(failure_);
}

void StepPool::work() {
  for (size_t i = next_++; i < count_; i = next_++) {
    try {
      (*job_)(i);
    } catch (...) {
      const std::lock_guard<std::mutex> hold(lock_);
      if (!failure_) failure_ = std::current_exception();
    }
  }
}

void StepPool::serve() {
  long seen = 0;
  for (;;) {
    // spin a little first: a vector environment posts its next step within microseconds, and a
    // thread woken from a condition variable can take longer than the step itself
    const auto spin_until = std::chrono::steady_clock::now() + std::chrono::microseconds(SPIN_MICROSECONDS);
    while (posted_.load(std::memory_order_acquire) == seen && std::chrono::steady_clock::now() < spin_until)
      std::this_thread::yield();
    {
      std::unique_lock<std::mutex> hold(lock_);
      start_.wait(hold, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
    }
    work();
    {
      const std::lock_guard<std::mutex> hold(lock_);
      busy_.fetch_sub(1, std::memory_order_release);
    }
    done_.notify_one();
  }
}

void step_loops(StepPool &pool, const std::vector<SteppedLoop *> &loops, const RewardSpec &spec, const StepRows &rows) {
  const size_t na = rows.action_size, no = rows.observation_size, nj = rows.joints, count = loops.size();
  const auto one = [&](size_t i) {
    SteppedLoop &loop = *loops[i];
    rows.running[i] = step_action(loop, rows.actions + i * na, spec.action_scale, spec.mode);
    const Vector &applied = loop.applied_torque();
    Eigen::Map<Vector>(rows.applied + i * nj, static_cast<Eigen::Index>(nj)) = applied;
    if (rows.running[i]) loop.observe(rows.observations + i * no);
    rows.rewards[i] = period_reward(spec, rows.observations + i * no, applied, rows.sizes[i], loop.task_rows());
  };
  // contiguous blocks of loops, BLOCKS_PER_THREAD per thread: a loop's step takes microseconds, so
  // handing out loops one by one would cost as much in contention as it saves in balance, and one
  // block per thread left a thread that woke late with nothing to do while the caller did it all
  const size_t blocks = std::min<size_t>(count, BLOCKS_PER_THREAD * static_cast<size_t>(pool.threads()));
  const std::function<void(size_t)> job = [&](size_t b) {
    for (size_t i = b * count / blocks; i < (b + 1) * count / blocks; ++i) one(i);
  };
  pool.run(blocks, job);
}

}  // namespace nnrobust
