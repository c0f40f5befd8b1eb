// Stick-slip integration of the plant: the twin of nnrobust/plant/stick_slip.py, step for step
// (the same events, the same Illinois location, the same active-set choice of modes).
#pragma once

#include <limits>
#include <vector>

#include "plant.hpp"

namespace nnrobust {

constexpr double kEventTolerance = 1e-12;  // stick_slip.EVENT_TOLERANCE [s]
constexpr int kMaxEvents = 64;             // stick_slip.MAX_EVENTS
constexpr int kMaxLocateIterations = 60;   // stick_slip.MAX_LOCATE_ITERATIONS

class StickSlipIntegrator {
 public:
  StickSlipIntegrator(Plant &plant, const Vector &v0) : plant_(plant), mode(v0.size()) {
    for (int i = 0; i < v0.size(); ++i) mode[i] = (plant.sticky(i) && v0[i] == 0.0) ? 0 : (v0[i] < 0 ? -1 : 1);
  }

  // StickSlipIntegrator.advance with rk4_flow: (q, v) at t + h under the torque tau
  void advance(double t, Vector &q, Vector &v, const Vector &tau, double h, bool new_command) {
    const int n = static_cast<int>(q.size());
    bool rest = false;
    for (int i = 0; i < n; ++i) rest = rest || (plant_.sticky(i) && v[i] == 0.0);
    if (new_command && rest) settle(t, q, v, tau, mode);
    const double end = t + h;
    for (int round = 0; round <= kMaxEvents; ++round) {
      held_mode_ = mode;
      const Modes &held_mode = held_mode_;
      slipping_.clear();
      held_.clear();
      for (int i = 0; i < n; ++i)
        if (plant_.sticky(i)) (held_mode[i] != 0 ? slipping_ : held_).push_back(i);
      const std::vector<int> &slipping = slipping_, &held = held_;
      const double span = end - t;
      Vector &q1 = q_end_, &v1 = v_end_;
      flow(t, q, v, tau, held_mode, span, q1, v1);
      events(end, q1, v1, tau, held_mode, slipping, held, g_end_);
      const Vector &g_end = g_end_;
      triggered_.clear();
      for (int i = 0; i < g_end.size(); ++i)
        if (g_end[i] <= 0.0) triggered_.push_back(i);
      if (triggered_.empty()) {
        q = q1;
        v = v1;
        return;
      }
      events(t, q, v, tau, held_mode, slipping, held, g_start_);
      const Vector &g_start = g_start_;
      double first = span;
      int which = -1;
      for (int i : triggered_) {
        auto g = [&](double s_) {
          flow(t, q, v, tau, held_mode, s_, q_try_, v_try_);
          events(t + s_, q_try_, v_try_, tau, held_mode, slipping, held, g_try_);
          return g_try_[i];
        };
        const double s_i = event_time(g, g_start[i], span, g_end[i]);
        if (s_i >= 0.0 && (s_i < first || which < 0)) {
          first = s_i;
          which = i;
        }
      }
      if (which < 0) {  // only events the step cannot resolve: a joint that barely moves
        q = q1;
        v = v1;
        return;
      }
      if (first >= span) {
        q = q1;
        v = v1;
      } else if (first > 0.0) {
        flow(t, q, v, tau, held_mode, first, q_try_, v_try_);
        q = q_try_;
        v = v_try_;
      }
      t = t + first;
      const int n_slip = static_cast<int>(slipping.size());
      if (which < n_slip) v[slipping[which]] = 0.0;
      ++events_;
      mode = held_mode;
      settle(t, q, v, tau, mode);
      if (which >= n_slip) {  // a held joint breaks away toward its holding torque
        const int joint = held[which - n_slip];
        if (mode[joint] == 0) {
          plant_.constrained_acceleration(t, q, v, tau, held_mode, hold_);
          mode[joint] = hold_[which - n_slip] > 0 ? 1 : -1;
        }
      }
      if (first >= span) return;
    }
    ++unresolved_;
  }

  long events_count() const { return events_; }
  long unresolved() const { return unresolved_; }

 private:
  Plant &plant_;

 public:
  Modes mode;

 private:
  long events_ = 0, unresolved_ = 0;

  // stick_slip.rk4_flow, into q_out, v_out (neither may be q or v): the stages in the work
  // buffers below, so that a flow allocates nothing once they are sized
  void flow(double t, const Vector &q, const Vector &v, const Vector &tau, const Modes &md, double h, Vector &q_out,
            Vector &v_out) {
    a1_ = plant_.constrained_acceleration(t, q, v, tau, md, hold_);
    v2_ = v + 0.5 * h * a1_;
    q_stage_ = q + 0.5 * h * v;
    a2_ = plant_.constrained_acceleration(t + 0.5 * h, q_stage_, v2_, tau, md, hold_);
    v3_ = v + 0.5 * h * a2_;
    q_stage_ = q + 0.5 * h * v2_;
    a3_ = plant_.constrained_acceleration(t + 0.5 * h, q_stage_, v3_, tau, md, hold_);
    v4_ = v + h * a3_;
    q_stage_ = q + h * v3_;
    a4_ = plant_.constrained_acceleration(t + h, q_stage_, v4_, tau, md, hold_);
    q_out = q + (h / 6.0) * (v + 2.0 * v2_ + 2.0 * v3_ + v4_);
    v_out = v + (h / 6.0) * (a1_ + 2.0 * a2_ + 2.0 * a3_ + a4_);
  }

  // stick_slip._events, into g: mode_i v_i of the slipping joints, then 1 - |f_i| / F_s,i of the
  // held
  void events(double t, const Vector &q, const Vector &v, const Vector &tau, const Modes &md,
              const std::vector<int> &slipping, const std::vector<int> &held, Vector &g) {
    const int ns = static_cast<int>(slipping.size()), nh = static_cast<int>(held.size());
    g.resize(ns + nh);
    for (int i = 0; i < ns; ++i) g[i] = md[slipping[i]] * v[slipping[i]];
    if (nh == 0) return;
    plant_.constrained_acceleration(t, q, v, tau, md, hold_);
    for (int i = 0; i < nh; ++i) g[ns + i] = 1.0 - std::abs(hold_[i]) / plant_.friction.stiction[held[i]];
  }

  // work buffers (sized on first use; a step then allocates nothing in advance, flow or events)
  Modes held_mode_;
  std::vector<int> slipping_, held_, triggered_;
  Vector q_end_, v_end_, q_try_, v_try_, g_end_, g_start_, g_try_;
  Vector a1_, a2_, a3_, a4_, v2_, v3_, v4_, q_stage_, hold_;

  // A box QP's work buffers for k joints at rest, and each active set's for nf free ones, one per
  // size (per_size.hpp; the arithmetic is the one of the fresh temporaries they replace)
  struct FreeSet {
    Matrix W;
    Vector rhs, x;
    Eigen::PartialPivLU<Matrix> lu;
    explicit FreeSet(int nf) : W(Matrix::Zero(nf, nf)), rhs(Vector::Zero(nf)), x(Vector::Zero(nf)), lu(nf) {}
  };
  struct BoxWork {
    Matrix W;
    Vector c, stat, coul, bound, f, target, d, a, Wf;
    Eigen::VectorXi side;
    std::vector<int> free, bound_set;
    PerSize<FreeSet> sets;
    explicit BoxWork(int k)
        : W(Matrix::Zero(k, k)), c(Vector::Zero(k)), stat(c), coul(c), bound(c), f(c), target(c), d(c), a(c), Wf(c),
          side(Eigen::VectorXi::Zero(k)) {
      free.reserve(k);
      bound_set.reserve(k);
      for (int nf = 1; nf <= k; ++nf) sets.at(k, nf);  // every active set's, with the QP's
    }
  };

  // stick_slip.settle: the modes of the joints at rest (v_i = 0) chosen in place in `md`
  void settle(double t, const Vector &q, const Vector &v, const Vector &tau, Modes &md) {
    const int n = static_cast<int>(q.size());
    std::vector<int> &rest = rest_;
    rest.clear();
    for (int i = 0; i < n; ++i)
      if (plant_.sticky(i) && v[i] == 0.0) rest.push_back(i);
    if (rest.empty()) return;
    for (int i : rest) md[i] = 0;
    const Matrix &M = plant_.mass(q);  // the plant's: net_torque and bias leave it alone
    r_ = plant_.net_torque(t, q, v, tau, md) - plant_.bias(q, v);
    lu_.compute(M);
    if (identity_.rows() != n) identity_.setIdentity(n, n);
    Minv_ = lu_.solve(identity_);  // inverse(), without the identity's temporary
    Minv_r_ = lu_.solve(r_);
    const int k = static_cast<int>(rest.size());
    BoxWork &w = box_.at(n, k);
    for (int i = 0; i < k; ++i) {
      w.c[i] = Minv_r_[rest[i]];
      w.stat[i] = plant_.friction.stiction[rest[i]];
      w.coul[i] = plant_.friction.coulomb[rest[i]];
      for (int j = 0; j < k; ++j) w.W(i, j) = Minv_(rest[i], rest[j]);
    }
    box_qp(w, w.stat);
    slides_.assign(k, false);
    for (int i = 0; i < k; ++i) slides_[i] = w.side[i] != 0;
    auto stiction = [&]() {
      for (int i = 0; i < k; ++i)
        if (slides_[i] && w.stat[i] > w.coul[i]) return true;
      return false;
    };
    while (stiction()) {
      for (int i = 0; i < k; ++i) w.bound[i] = slides_[i] ? w.coul[i] : std::numeric_limits<double>::infinity();
      box_qp(w, w.bound);
      bool broke = false;
      for (int i = 0; i < k; ++i)
        if (!slides_[i] && std::abs(w.f[i]) > w.stat[i]) slides_[i] = broke = true;
      if (!broke) break;
    }
    w.Wf.noalias() = w.W * w.f;
    w.a = w.c - w.Wf;  // the rest's accelerations c - W f
    for (int i = 0; i < k; ++i) md[rest[i]] = (w.side[i] != 0 && w.side[i] * w.a[i] > 0) ? w.side[i] : 0;
  }

  // settle's work buffers
  std::vector<int> rest_;
  std::vector<bool> slides_;
  Vector r_, Minv_r_;
  Matrix Minv_, identity_;
  Eigen::PartialPivLU<Matrix> lu_;
  PerSize<BoxWork> box_;  // per count of joints at rest

 public:
  // stick_slip.box_qp: min 1/2 f'W f - c'f subject to |f_i| <= bound_i, by a primal active set,
  // on w's W and c, into w.f and w.side
  static void box_qp(BoxWork &w, const Vector &bound) {
    const Matrix &W = w.W;
    const Vector &c = w.c;
    Vector &f = w.f;
    Eigen::VectorXi &side = w.side;
    const int k = static_cast<int>(c.size());
    f.setZero();
    side.setZero();
    std::vector<int> &fr = w.free, &bd = w.bound_set;
    for (int it = 0; it < 4 * k + 8; ++it) {
      fr.clear();
      bd.clear();
      for (int i = 0; i < k; ++i) (side[i] == 0 ? fr : bd).push_back(i);
      Vector &target = w.target;
      target = f;
      if (!fr.empty()) {
        const int nf = static_cast<int>(fr.size());
        FreeSet &set = w.sets.at(k, nf);
        for (int i = 0; i < nf; ++i) {
          double sum = 0.0;
          for (int j : bd) sum += W(fr[i], j) * f[j];
          set.rhs[i] = c[fr[i]] - sum;
          for (int j = 0; j < nf; ++j) set.W(i, j) = W(fr[i], fr[j]);
        }
        set.lu.compute(set.W);
        set.x = set.lu.solve(set.rhs);
        for (int i = 0; i < nf; ++i) target[fr[i]] = set.x[i];
      }
      Vector &d = w.d;
      d = target - f;
      double step = 1.0;
      int blocking = -1;
      for (int i : fr) {
        if (d[i] != 0.0) {
          const double room = ((d[i] > 0 ? bound[i] : -bound[i]) - f[i]) / d[i];
          if (room < step) {
            step = room;
            blocking = i;
          }
        }
      }
      f = f + step * d;
      if (blocking >= 0) {
        side[blocking] = d[blocking] > 0 ? 1 : -1;
        f[blocking] = side[blocking] * bound[blocking];
        continue;
      }
      w.Wf.noalias() = W * f;
      Vector &a = w.a;
      a = c - w.Wf;
      int worst = -1;
      double worst_value = -std::numeric_limits<double>::infinity();
      for (int i = 0; i < k; ++i) {
        const double wrong = side[i] != 0 ? -side[i] * a[i] : -std::numeric_limits<double>::infinity();
        if (wrong > worst_value) {
          worst_value = wrong;
          worst = i;
        }
      }
      if (!(worst_value > 0.0)) break;
      side[worst] = 0;
    }
  }

 private:
  // stick_slip._event_time (-1: None)
  template <class G>
  static double event_time(G &&g, double g_start, double span, double g_end) {
    if (g_start > 0) return locate(g, 0.0, g_start, span, g_end);
    if (g_start < 0) return 0.0;
    for (double s_ = 0.5 * span; s_ > kEventTolerance; s_ *= 0.5) {
      const double gs = g(s_);
      if (gs > 0) return locate(g, s_, gs, span, g_end);
    }
    return -1.0;
  }

  // stick_slip._locate (Illinois)
  template <class G>
  static double locate(G &&g, double lo, double g_lo, double hi, double g_hi) {
    int side = 0;
    for (int it = 0; it < kMaxLocateIterations; ++it) {
      if (hi - lo <= kEventTolerance || g_hi >= -1e-12) break;
      double s_ = hi - g_hi * (hi - lo) / (g_hi - g_lo);
      if (!(lo < s_ && s_ < hi)) s_ = 0.5 * (lo + hi);
      const double gs = g(s_);
      if (gs <= 0.0) {
        hi = s_;
        g_hi = gs;
        if (side == -1) g_lo *= 0.5;
        side = -1;
      } else {
        lo = s_;
        g_lo = gs;
        if (side == 1) g_hi *= 0.5;
        side = 1;
      }
    }
    return hi;
  }
};

}  // namespace nnrobust
