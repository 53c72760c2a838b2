#include "libsamp/data/track_joining.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "libsamp/core/assignment.h"
#include "libsamp/data/tracking.h"

namespace samp::tracking_internal {
namespace {

using Matrix4d = Eigen::Matrix4d;
using Vector4d = Eigen::Vector4d;

// Weighted least-squares constant-velocity fit of observations in the ground
// plane, state (position, velocity) at time t_ref, with a zero-velocity prior
// of std. dev. max_speed / 2 and a model error growing with the time from t_ref.
struct MotionFit {
  Vector4d state = Vector4d::Zero();
  Matrix4d covariance = Matrix4d::Identity();
  double time = 0.0;
};

MotionFit FitConstantVelocity(const std::vector<Observation>& observations, const std::vector<int>& members,
                              double t_ref, const TrackerOptions& o) {
  const double s_v = o.max_speed / 2.0;
  Matrix4d information = Matrix4d::Zero();
  information.bottomRightCorner<2, 2>() = Eigen::Matrix2d::Identity() / (s_v * s_v);
  Vector4d rhs = Vector4d::Zero();
  for (int m : members) {
    const Observation& ob = observations[m];
    const double dt = ob.time - t_ref;
    Eigen::Matrix<double, 2, 4> a;
    a << 1, 0, dt, 0, 0, 1, 0, dt;
    const double model = 0.5 * o.acceleration_sigma * dt * dt;
    const Eigen::Matrix2d w = (ob.ground_covariance + model * model * Eigen::Matrix2d::Identity()).inverse();
    information += a.transpose() * w * a;
    rhs += a.transpose() * w * ob.ground;
  }
  MotionFit fit;
  fit.time = t_ref;
  fit.covariance = information.inverse();
  fit.state = fit.covariance * rhs;
  return fit;
}

MotionFit Extrapolate(const MotionFit& fit, double time, const TrackerOptions& o) {
  const double dt = time - fit.time;
  const Matrix4d f = Transition(dt);
  MotionFit out;
  out.time = time;
  out.state = f * fit.state;
  out.covariance = f * fit.covariance * f.transpose() + ProcessNoise(dt, o.acceleration_sigma);
  return out;
}

// The cost of continuing `head` (observations, increasing frames) with `tail`
// (all later): squared Mahalanobis distance of the two constant-velocity fits
// (each of fit_window observations next to the gap) at the gap's middle, plus
// size, height and axis terms; kNoAssignment beyond the axis gate.
double LinkCost(const std::vector<Observation>& observations, const std::vector<int>& head,
                const std::vector<int>& tail, const TrackerOptions& o) {
  const size_t k = static_cast<size_t>(o.fit_window);
  const std::vector<int> h(head.end() - std::min(k, head.size()), head.end());
  const std::vector<int> t(tail.begin(), tail.begin() + std::min(k, tail.size()));
  const double t_head = observations[h.back()].time, t_tail = observations[t.front()].time;
  const double t_mid = 0.5 * (t_head + t_tail);
  const MotionFit a = Extrapolate(FitConstantVelocity(observations, h, t_head, o), t_mid, o);
  const MotionFit b = Extrapolate(FitConstantVelocity(observations, t, t_tail, o), t_mid, o);
  const Vector4d difference = a.state - b.state;
  const double d2_motion = difference.dot((a.covariance + b.covariance).ldlt().solve(difference));
  auto means = [&](const std::vector<int>& members, Eigen::Vector3d* size, double* height, double* height_var,
                   double* axis) {
    *size = Eigen::Vector3d::Zero();
    *height = *height_var = 0.0;
    std::vector<double> axes;
    for (int m : members) {
      *size += observations[m].size;
      *height += observations[m].height;
      *height_var += observations[m].height_variance;
      axes.push_back(observations[m].axis);
    }
    *size /= double(members.size());
    if (o.robust_cues) {  // the median of each dimension: one wrong box does not move it
      for (int i = 0; i < 3; ++i) {
        std::vector<double> v;
        for (int m : members) v.push_back(observations[m].size[i]);
        std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
        (*size)[i] = v[v.size() / 2];
      }
    }
    *height /= double(members.size());
    *height_var /= double(members.size()) * double(members.size());
    *axis = MeanAxis(axes);
  };
  Eigen::Vector3d size_h, size_t;
  double height_h, height_t, var_h, var_t, axis_h, axis_t;
  means(h, &size_h, &height_h, &var_h, &axis_h);
  means(t, &size_t, &height_t, &var_t, &axis_t);
  const double nh = double(h.size()), nt = double(t.size());
  double d2_size = (size_h - size_t).squaredNorm() / (o.size_sigma * o.size_sigma * (1.0 / nh + 1.0 / nt));
  double d2_height = (height_h - height_t) * (height_h - height_t) / (var_h + var_t);
  double axis_difference = AxisDifference(axis_h, axis_t);
  int outlying_cues = 0;
  if (std::abs(axis_difference) > o.yaw_gate_deg * kPi / 180.0) {
    if (!o.robust_cues) return kNoAssignment;
    axis_difference = o.yaw_gate_deg * kPi / 180.0;
    ++outlying_cues;
  }
  if (o.robust_cues) {  // a single cue outside its gate costs the gate's value
    if (!(d2_size <= o.size_gate_chi2)) d2_size = o.size_gate_chi2, ++outlying_cues;
    if (!(d2_height <= o.height_gate_chi2)) d2_height = o.height_gate_chi2, ++outlying_cues;
    if (outlying_cues > 1) return kNoAssignment;
  }
  const double s_yaw = o.yaw_sigma_deg * kPi / 180.0;
  const double turn = 0.5 * (t_tail - t_head);  // a turning car: up to ~0.5 rad/s
  const double d2_axis = axis_difference * axis_difference / (s_yaw * s_yaw * (1.0 / nh + 1.0 / nt) + turn * turn);
  return d2_motion + d2_size + d2_height + d2_axis;
}

int FirstFrame(const std::vector<Observation>& obs, const std::vector<int>& t) { return obs[t.front()].frame; }
int LastFrame(const std::vector<Observation>& obs, const std::vector<int>& t) { return obs[t.back()].frame; }

}  // namespace

// Joins fragment ends to later fragment starts (one-to-one, Hungarian on the
// gated link costs). Returns the number of joins.
int JoinFragments(const std::vector<Observation>& observations, const TrackerOptions& o,
                  std::vector<std::vector<int>>* tracks) {
  std::vector<std::vector<int>>& t = *tracks;
  const int n = static_cast<int>(t.size());
  std::vector<double> cost(static_cast<size_t>(n) * n, kNoAssignment);
  bool any = false;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      // A single detection (a false positive, mostly) joins nothing.
      if (i == j || t[i].size() < 2 || t[j].size() < 2) continue;
      const int gap = FirstFrame(observations, t[j]) - LastFrame(observations, t[i]) - 1;
      if (gap < 0 || gap > o.max_join_gap) continue;
      const double c = LinkCost(observations, t[i], t[j], o);
      if (c <= o.join_gate_chi2) {
        cost[static_cast<size_t>(i) * n + j] = c;
        any = true;
      }
    }
  }
  if (!any) return 0;
  const std::vector<int> next = SolveAssignment(cost, n, n);
  std::vector<char> has_previous(n, 0);
  int joins = 0;
  for (int i = 0; i < n; ++i)
    if (next[i] >= 0) has_previous[next[i]] = 1, ++joins;
  std::vector<std::vector<int>> joined;
  for (int i = 0; i < n; ++i) {
    if (has_previous[i]) continue;
    std::vector<int> chain;
    for (int j = i; j >= 0; j = next[j]) chain.insert(chain.end(), t[j].begin(), t[j].end());
    joined.push_back(std::move(chain));
  }
  t = std::move(joined);
  return joins;
}

namespace {

// Cost of a link inside a track; 0 when one side is empty.
double InnerCost(const std::vector<Observation>& observations, const std::vector<int>& head,
                 const std::vector<int>& tail, const TrackerOptions& o) {
  if (head.empty() || tail.empty()) return 0.0;
  const int gap = FirstFrame(observations, tail) - LastFrame(observations, head) - 1;
  if (gap > o.max_join_gap) return kNoAssignment;
  return std::min(kNoAssignment, LinkCost(observations, head, tail, o));
}

// Two tracks whose detections come within `radius` (ground plane) in frames at
// most one apart.
bool ComeClose(const std::vector<Observation>& observations, const std::vector<int>& a, const std::vector<int>& b,
               double radius) {
  for (int i : a)
    for (int j : b)
      if (std::abs(observations[i].frame - observations[j].frame) <= 1 &&
          (observations[i].ground - observations[j].ground).norm() <= radius)
        return true;
  return false;
}

}  // namespace

// Swaps tails between pairs of tracks while the best swap lowers the sum of
// the two link costs by more than swap_margin. Returns the number of swaps.
int ResolveSwitches(const std::vector<Observation>& observations, const TrackerOptions& o,
                    std::vector<std::vector<int>>* tracks) {
  std::vector<std::vector<int>>& t = *tracks;
  constexpr double kSwapRadius = 5.0;  // m: only tracks that come this close can have switched
  int swaps = 0;
  for (int pass = 0; pass < 1000; ++pass) {
    double best_gain = o.swap_margin;
    int best_x = -1, best_y = -1, best_split = 0;
    for (size_t x = 0; x < t.size(); ++x) {
      for (size_t y = x + 1; y < t.size(); ++y) {
        const int lo = std::max(FirstFrame(observations, t[x]), FirstFrame(observations, t[y]));
        const int hi = std::min(LastFrame(observations, t[x]), LastFrame(observations, t[y]));
        if (lo > hi + o.max_join_gap + 1) continue;  // far apart in time
        if (!ComeClose(observations, t[x], t[y], kSwapRadius)) continue;
        std::set<int> splits;
        for (int m : t[x]) splits.insert(observations[m].frame);
        for (int m : t[y]) splits.insert(observations[m].frame);
        for (int s : splits) {
          auto split = [&](const std::vector<int>& track, std::vector<int>* head, std::vector<int>* tail) {
            head->clear(), tail->clear();
            for (int m : track) (observations[m].frame < s ? head : tail)->push_back(m);
          };
          std::vector<int> xh, xt, yh, yt;
          split(t[x], &xh, &xt);
          split(t[y], &yh, &yt);
          // Both tracks continue across the split, each part with two detections at least:
          // links of different lengths are not comparable by their costs.
          if (xh.size() < 2 || yh.size() < 2 || xt.size() < 2 || yt.size() < 2) continue;
          const double current = InnerCost(observations, xh, xt, o) + InnerCost(observations, yh, yt, o);
          const double swapped_a = InnerCost(observations, xh, yt, o), swapped_b = InnerCost(observations, yh, xt, o);
          if (swapped_a >= kNoAssignment || swapped_b >= kNoAssignment) continue;
          if (swapped_a > o.join_gate_chi2 || swapped_b > o.join_gate_chi2) continue;
          const double gain = std::min(current, 1e12) - (swapped_a + swapped_b);
          if (gain > best_gain) best_gain = gain, best_x = int(x), best_y = int(y), best_split = s;
        }
      }
    }
    if (best_x < 0) break;
    std::vector<int> xh, xt, yh, yt;
    for (int m : t[best_x]) (observations[m].frame < best_split ? xh : xt).push_back(m);
    for (int m : t[best_y]) (observations[m].frame < best_split ? yh : yt).push_back(m);
    xh.insert(xh.end(), yt.begin(), yt.end());
    yh.insert(yh.end(), xt.begin(), xt.end());
    t[best_x] = std::move(xh);
    t[best_y] = std::move(yh);
    t.erase(std::remove_if(t.begin(), t.end(), [](const std::vector<int>& v) { return v.empty(); }), t.end());
    ++swaps;
  }
  return swaps;
}

}  // namespace samp::tracking_internal
