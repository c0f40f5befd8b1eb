// The learning environment's side of the compiled loop (the twin of nnrobust/learning/): an
// action applied to a SteppedLoop, the reward of a period, and the pool of threads the vector
// environment steps its episodes on. docs/learning.md documents the formulas.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "closed_loop.hpp"

namespace nnrobust {

// What an action is (nnrobust.learning.env.ACTION_MODES): the command, a residual added to the
// compiled law's command (the law's state and signals advance as in a run), or the logarithms of
// the factors on the compiled law's position and velocity gains for the period (Law::scale_gains).
enum ActionMode { ACTION_TORQUE = 0, ACTION_RESIDUAL = 1, ACTION_GAINS = 2 };

// The reward's weights and the arm's limits (nnrobust.learning.env.Reward and Episodes):
// r = -(error |e_p| / L + effort mean((tau / tau_max)^2) + limits mean(beyond a limit)).
struct RewardSpec {
  double error = 1.0, effort = 0.01, limits = 0.1;
  Vector torque_limit, lower, upper, speed_limit;
  Vector action_scale;  // tau_max (torque), s tau_max (residual) or ln G (gains): the command is clip(a) .* scale
  int mode = ACTION_TORQUE;
};

// One period of `loop` with `command` applied as `mode` says ([N m] for torque and residual; the
// two gain factors' logarithms for gains); false when the run has ended.
bool apply_command(SteppedLoop &loop, const Vector &command, int mode);

// One period of `loop` under the raw action `a` (scale's size: n, or 2 for gains), clipped to
// [-1, 1], times `scale` and applied as `mode` says; false when the run has ended.
bool step_action(SteppedLoop &loop, const double *a, const Vector &scale, int mode);

// The reward of the period just stepped, from the next observation `obs` (the observed error and
// the measured state) and the applied torque; `size` is the path's size L.
double period_reward(const RewardSpec &spec, const double *obs, const Vector &applied, double size, int m);

// A persistent pool of threads: run(count, job) calls job(i) for every i < count on the pool's
// threads and the calling thread, and rethrows the first exception. Threads wait on a condition
// variable between calls, so a call costs a wake-up, not a thread start.
class StepPool {
 public:
  static constexpr int SPIN_MICROSECONDS = 200;  // how long an idle thread polls before it sleeps
  explicit StepPool(int threads);
  ~StepPool();
  StepPool(const StepPool &) = delete;
  StepPool &operator=(const StepPool &) = delete;
  int threads() const { return static_cast<int>(workers_.size()) + 1; }
  void run(size_t count, const std::function<void(size_t)> &job);

 private:
  void work();
  void serve();

  std::vector<std::thread> workers_;
  std::mutex lock_;
  std::condition_variable start_, done_;
  const std::function<void(size_t)> *job_ = nullptr;
  size_t count_ = 0;
  std::atomic<size_t> next_{0};
  std::atomic<long> posted_{0};  // the generation last posted, read while spinning
  std::atomic<int> busy_{0};  // workers still at the posted step, polled by the caller
  long generation_ = 0;
  bool stop_ = false;
  std::exception_ptr failure_;
};

// The arrays of one step of several loops (row i is loop i's): the raw actions in, the next
// observations, applied torques, rewards and whether each runs on out. A loop that ended keeps
// its row of observations.
struct StepRows {
  const double *actions;
  double *observations, *applied, *rewards;
  bool *running;
  const double *sizes;  // each loop's path size L
  size_t action_size, observation_size, joints;
};

// How many blocks of loops step_loops hands out per thread of its pool.
constexpr size_t BLOCKS_PER_THREAD = 4;

// One period of every loop on the pool (the vector environment's step; the single environment's
// with one loop).
void step_loops(StepPool &pool, const std::vector<SteppedLoop *> &loops, const RewardSpec &spec, const StepRows &rows);

}  // namespace nnrobust
