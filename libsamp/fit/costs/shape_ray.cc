#include "libsamp/fit/costs/shape_ray.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "libsamp/core/error.h"

namespace samp {

namespace {

// RayDistance: at most this many sphere-tracing steps, each at least half a
// voxel; Newton steps on the bracketed crossing; at most kMaxRayRatio |phi|.
constexpr int kMaxMarchSteps = 24;
constexpr int kNewtonSteps = 3;
constexpr double kMaxRayRatio = 5.0;
// FirstCrossing: at most this many sphere-tracing steps from the grid box
// entry; golden-section steps refining a miss's closest approach.
constexpr int kMaxTraceSteps = 64;
constexpr int kGoldenSteps = 16;

void PointOnRay(const double* origin, const double* direction, double t, double* p) {
  for (int a = 0; a < 3; ++a) p[a] = origin[a] + t * direction[a];
}

// Whether v lies on the side `sign` (+-1) of the surface: sign < 0 ? v < 0 :
// v > 0, without a branch on the ray's side (the product by +-1 is exact;
// false for 0 and NaN).
inline bool SameSide(double sign, double v) { return sign * v > 0.0; }

// stop(s) for the lockstep slots s whose bits are set in `stops`, from the
// highest down: the slots above the one handing over then all go on (or hold
// new work), so the last slot may move into it. Each slot's outcome is
// computed first without a branch; what remains is one branch per stopping
// slot and round instead of one per slot and round.
template <typename Stop>
inline void HandOverStopped(uint32_t stops, Stop stop) {
  while (stops != 0) {
    const int s = 31 - __builtin_clz(stops);
    stops &= ~(1u << s);
    stop(s);
  }
}

// The crossing of origin + t direction bracketed in [lo, hi] (phi v_lo at lo
// and v_hi at hi on either side of 0): a secant, then Newton steps kept
// inside the bracket until |phi| is negligible. In: origin, direction, lo,
// hi, v_lo, v_hi; out: t, and c, g_c, v (phi), cell and in_cell
// (DenseValuePair::EvaluateCells) at t.
struct Refinement {
  const double* origin;
  const double* direction;
  double lo, hi, v_lo, v_hi;
  double t, c[3], g_c[3], v;
  ShapeLookup::DenseCell cell;
  bool in_cell;
};

// A job for the bracket [lo, hi] of origin + t direction, phi v_lo and v_hi there.
Refinement Bracket(const double* origin, const double* direction, double lo, double hi, double v_lo, double v_hi) {
  Refinement job;
  job.origin = origin;
  job.direction = direction;
  job.lo = lo;
  job.hi = hi;
  job.v_lo = v_lo;
  job.v_hi = v_hi;
  return job;
}

// The crossings of n jobs, in four lockstep slots whose values, gradients
// and cells are taken several at a time (DenseValuePair::EvaluateCells,
// each lane EvaluateDense's bit for bit).
void RefineCrossings(const ShapeLookup& lookup, const ShapeLookup::DenseValuePair& pair, Refinement* jobs, int n) {
  constexpr int kSlots = 4;
  const double tolerance = 1e-9 * lookup.grid().voxel_size;
  int slot_job[kSlots], step[kSlots], num_slots = 0, next = 0;
  auto start = [&](int s) {
    Refinement& j = jobs[next];
    j.t = j.lo + (j.hi - j.lo) * j.v_lo / (j.v_lo - j.v_hi);
    slot_job[s] = next++;
    step[s] = 0;
  };
  while (num_slots < kSlots && next < n) start(num_slots++);
  while (num_slots > 0) {
    double x[kSlots], y[kSlots], z[kSlots], v[kSlots];
    for (int s = 0; s < num_slots; ++s) {
      Refinement& j = jobs[slot_job[s]];
      PointOnRay(j.origin, j.direction, j.t, j.c);
      x[s] = j.c[0];
      y[s] = j.c[1];
      z[s] = j.c[2];
    }
    ShapeLookup::DenseCell cells[kSlots];
    bool in_cell[kSlots];
    double g[kSlots][3];
    pair.EvaluateCells(num_slots, x, y, z, cells, in_cell, v, g);
    for (int s = 0; s < num_slots; ++s) {
      Refinement& j = jobs[slot_job[s]];
      j.in_cell = in_cell[s];
      if (in_cell[s]) j.cell = cells[s];
      for (int a = 0; a < 3; ++a) j.g_c[a] = g[s][a];
    }
    for (int s = 0; s < num_slots;) {
      Refinement& j = jobs[slot_job[s]];
      const double* d = j.direction;
      const double slope = j.g_c[0] * d[0] + j.g_c[1] * d[1] + j.g_c[2] * d[2];
      if (!(step[s] == kNewtonSteps || std::abs(v[s]) <= tolerance || slope == 0.0 || !std::isfinite(slope))) {
        j.t = std::min(std::max(j.t - v[s] / slope, j.lo), j.hi);
        ++step[s];
        ++s;
        continue;
      }
      // Done: the next job takes the slot, else the last slot's job.
      j.v = v[s];
      if (next < n) {
        start(s);
        ++s;
      } else if (--num_slots > s) {
        slot_job[s] = slot_job[num_slots];
        step[s] = step[num_slots];
        v[s] = v[num_slots];
      }
    }
  }
}

// One crossing (RefineCrossings with a single job).
double RefineCrossing(const ShapeLookup& lookup, const double* phi_z, const double* origin,
                      const double* direction, double lo, double hi, double v_lo, double v_hi, double* c,
                      double* g_c, double* v) {
  Refinement job = Bracket(origin, direction, lo, hi, v_lo, v_hi);
  RefineCrossings(lookup, ShapeLookup::DenseValuePair(lookup, phi_z), &job, 1);
  for (int a = 0; a < 3; ++a) {
    c[a] = job.c[a];
    g_c[a] = job.g_c[a];
  }
  *v = job.v;
  return job.t;
}

// The span [*enter, *leave] of o_cam + lambda u (lambda >= 0) inside the grid
// box; false when the ray passes it.
bool GridBoxSpan(const GridSpec& grid, const double* o_cam, const double* u, double* enter, double* leave) {
  const Eigen::Vector3d lo = grid.MinCorner(), hi = grid.MaxCorner();
  *enter = 0.0;
  *leave = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (std::abs(u[a]) < 1e-12) {
      if (o_cam[a] < lo[a] || o_cam[a] > hi[a]) *enter = *leave + 1.0;
      continue;
    }
    const double t0 = (lo[a] - o_cam[a]) / u[a], t1 = (hi[a] - o_cam[a]) / u[a];
    // The two in order (swapped when t0 > t1), without a branch.
    const double near = t0 > t1 ? t1 : t0, far = t0 > t1 ? t0 : t1;
    *enter = std::max(*enter, near);
    *leave = std::min(*leave, far);
  }
  return *enter <= *leave;
}

// Golden-section search for the smallest phi along the ray in [a, b]; the
// best lambda found, *best_phi its phi (or `fallback` and its phi when the
// search finds nothing below it).
double ClosestApproach(const ShapeLookup& lookup, const double* phi_z, const double* o_cam, const double* u,
                       double a, double b, double fallback, double fallback_phi) {
  auto phi_at = [&](double l) {
    double p[3];
    PointOnRay(o_cam, u, l, p);
    return lookup.EvaluateDense(phi_z, p, nullptr, nullptr);
  };
  if (!(b > a)) return fallback;
  constexpr double kInvPhi = 0.6180339887498949;
  double x1 = b - kInvPhi * (b - a), x2 = a + kInvPhi * (b - a);
  double f1 = phi_at(x1), f2 = phi_at(x2);
  for (int k = 0; k < kGoldenSteps; ++k) {
    if (f1 < f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - kInvPhi * (b - a);
      f1 = phi_at(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + kInvPhi * (b - a);
      f2 = phi_at(x2);
    }
  }
  const double x = f1 < f2 ? x1 : x2;
  return std::min(f1, f2) < fallback_phi ? x : fallback;
}

}  // namespace

bool RayDistance(const ShapeLookup& lookup, const double* phi_z, const double* o, double phi_o, const double* u,
                 double* distance, double* c, double* g_c) {
  const double min_step = 0.5 * lookup.grid().voxel_size;
  const double sign = phi_o < 0.0 ? -1.0 : 1.0;  // inside: towards the camera
  const double direction[3] = {sign * u[0], sign * u[1], sign * u[2]};
  auto same_side = [&](double v) { return SameSide(sign, v); };
  // Sphere tracing: |phi| bounds the distance to the surface.
  double lo = 0.0, phi_lo = phi_o, hi = 0.0, phi_hi = phi_o;
  const double limit = kMaxRayRatio * std::abs(phi_o);
  for (int k = 0; k < kMaxMarchSteps && same_side(phi_hi) && hi <= limit; ++k) {
    lo = hi;
    phi_lo = phi_hi;
    hi = lo + std::max(std::abs(phi_lo), min_step);
    PointOnRay(o, direction, hi, c);
    phi_hi = lookup.EvaluateDense(phi_z, c, nullptr, nullptr);
    if (!std::isfinite(phi_hi)) return false;
  }
  if (same_side(phi_hi)) return false;
  double v;
  const double d = RefineCrossing(lookup, phi_z, o, direction, lo, hi, phi_lo, phi_hi, c, g_c, &v);
  if (d > limit) return false;
  // A crossing at a grazing angle (or none after all) counts as a miss.
  if (!(g_c[0] * u[0] + g_c[1] * u[1] + g_c[2] * u[2] < -kMinRaySlope)) return false;
  *distance = d;
  return true;
}

bool FirstCrossing(const ShapeLookup& lookup, const double* phi_z, const double* o_cam, const double* u,
                   double* lambda, double* c, double* g_c, double* phi_min, bool refine_miss, double max_lambda) {
  const GridSpec& grid = lookup.grid();
  auto finish_miss = [&](double l) {
    *lambda = l;
    PointOnRay(o_cam, u, l, c);
    *phi_min = lookup.EvaluateDense(phi_z, c, g_c, nullptr);
    return false;
  };
  double enter, leave;
  if (!GridBoxSpan(grid, o_cam, u, &enter, &leave)) {
    // The ray passes the grid box: its closest approach to the box centre.
    const Eigen::Vector3d centre = 0.5 * (grid.MinCorner() + grid.MaxCorner());
    double l = 0.0;
    for (int a = 0; a < 3; ++a) l += (centre[a] - o_cam[a]) * u[a];
    return finish_miss(std::max(l, 0.0));
  }
  // Sphere tracing from the entry: |phi| bounds the distance to the surface.
  const double min_step = 0.5 * grid.voxel_size;
  double ls[kMaxTraceSteps + 1], vs[kMaxTraceSteps + 1];
  int count = 0;
  double l = enter;
  for (;;) {
    double p[3];
    PointOnRay(o_cam, u, l, p);
    const double v = lookup.EvaluateDense(phi_z, p, nullptr, nullptr);
    if (!std::isfinite(v)) {
      *phi_min = v;
      return false;
    }
    ls[count] = l;
    vs[count] = v;
    ++count;
    if (v < 0.0) break;
    if (l >= leave || count > kMaxTraceSteps) break;
    if (l > max_lambda) return false;  // positive beyond max_lambda: any crossing lies beyond it
    l = std::min(l + std::max(v, min_step), leave);
  }
  if (vs[count - 1] < 0.0 && count >= 2) {
    // Crossing bracketed in [ls[count-2], ls[count-1]].
    *lambda = RefineCrossing(lookup, phi_z, o_cam, u, ls[count - 2], ls[count - 1], vs[count - 2], vs[count - 1],
                             c, g_c, phi_min);
    return true;
  }
  if (vs[count - 1] < 0.0) return finish_miss(ls[0]);  // inside at the box entry (a shape touching the box)
  if (!refine_miss) return false;
  // Miss: the smallest sampled phi, refined in the neighbouring samples' interval.
  int best = 0;
  for (int k = 1; k < count; ++k) {
    if (vs[k] < vs[best]) best = k;
  }
  const double a = ls[std::max(best - 1, 0)], b = ls[std::min(best + 1, count - 1)];
  return finish_miss(ClosestApproach(lookup, phi_z, o_cam, u, a, b, ls[best], vs[best]));
}

namespace {

// The march slots: kMarchSlots rays sample in lockstep, one sample each per
// round (their lookups overlap), a ray that stops handing its slot to the
// next waiting ray so that the slots stay full until the queue runs dry.
// Their points are kept per axis (slot s at x[s], y[s], z[s]) and evaluated
// several at a time (SampleSlots).
constexpr int kMarchSlots = 8;

// v[s] = phi at slot s's point, s in [0, num_slots): four at a time when
// `four` (DenseValuePair::HasEvaluate4), then two, then one.
inline void SampleSlots(const ShapeLookup& lookup, const ShapeLookup::DenseValuePair& pair, bool four,
                        const double* phi_z, const double* x, const double* y, const double* z, int num_slots,
                        double* v) {
  int s = 0;
  if (four) {
    for (; s + 4 <= num_slots; s += 4) pair.Evaluate4(x + s, y + s, z + s, v + s);
  }
  for (; s + 2 <= num_slots; s += 2) pair.Evaluate(x + s, y + s, z + s, v + s);
  if (s < num_slots) {
    const double p[3] = {x[s], y[s], z[s]};
    v[s] = lookup.EvaluateDenseValue(phi_z, p);
  }
}

// The ray in slot s stops: the next waiting ray of queue[*next..queued)
// takes the slot (load(s, ray); its first sample comes in the next round),
// else (the queue dry) the last slot's state moves into slot s
// (move(s, last)).
template <typename Load, typename Move>
inline void HandOverSlot(int s, const int* queue, int queued, int* next, int* num_slots, Load load, Move move) {
  if (*next < queued) {
    load(s, queue[(*next)++]);
    return;
  }
  --*num_slots;
  move(s, *num_slots);
}

}  // namespace

void RayDistances(const ShapeLookup& lookup, const double* phi_z, RayDistanceQuery* rays, int n) {
  SAMP_CHECK(n >= 0 && n <= kRayBatch) << "RayDistances: " << n << " rays, at most " << kRayBatch;
  const double min_step = 0.5 * lookup.grid().voxel_size;
  struct March {
    double sign, direction[3], lo, phi_lo, hi, phi_hi, limit;
    int steps;
    bool failed;
  } m[kRayBatch];
  // The rays that take a step, in order.
  int queue[kRayBatch], queued = 0;
  for (int r = 0; r < n; ++r) {
    March& a = m[r];
    RayDistanceQuery& q = rays[r];
    a.sign = q.phi_o < 0.0 ? -1.0 : 1.0;  // inside: towards the camera
    for (int k = 0; k < 3; ++k) a.direction[k] = a.sign * q.u[k];
    a.lo = a.hi = 0.0;
    a.phi_lo = a.phi_hi = q.phi_o;
    a.limit = kMaxRayRatio * std::abs(q.phi_o);
    a.steps = 0;
    a.failed = false;
    queue[queued] = r;
    queued += SameSide(a.sign, a.phi_hi) & (a.hi <= a.limit);
  }
  // Sphere tracing (RayDistance's loop) in the march slots.
  int slot_ray[kMarchSlots], num_slots = 0, next = 0;
  double x[kMarchSlots], y[kMarchSlots], z[kMarchSlots], v[kMarchSlots];
  auto load = [&](int s, int r) { slot_ray[s] = r; };
  auto move = [&](int to, int from) { slot_ray[to] = slot_ray[from]; };
  while (num_slots < kMarchSlots && next < queued) load(num_slots++, queue[next++]);
  const ShapeLookup::DenseValuePair pair(lookup, phi_z);
  const bool four = ShapeLookup::DenseValuePair::HasEvaluate4();
  while (num_slots > 0) {
    for (int s = 0; s < num_slots; ++s) {
      March& a = m[slot_ray[s]];
      const double* o = rays[slot_ray[s]].o;
      a.lo = a.hi;
      a.phi_lo = a.phi_hi;
      a.hi = a.lo + std::max(std::abs(a.phi_lo), min_step);
      x[s] = o[0] + a.hi * a.direction[0];
      y[s] = o[1] + a.hi * a.direction[1];
      z[s] = o[2] + a.hi * a.direction[2];
    }
    SampleSlots(lookup, pair, four, phi_z, x, y, z, num_slots, v);
    // Every slot's sample, and whether its ray stops, without a branch on it
    // (the tests joined by &): whether a ray goes on is what the predictor
    // cannot know.
    uint32_t stops = 0;
    for (int s = 0; s < num_slots; ++s) {
      March& a = m[slot_ray[s]];
      const double value = v[s];
      a.phi_hi = value;
      ++a.steps;
      const bool finite = std::isfinite(value);
      a.failed = !finite;
      const bool go_on = finite & (a.steps < kMaxMarchSteps) & SameSide(a.sign, value) & (a.hi <= a.limit);
      stops |= uint32_t(!go_on) << s;
    }
    HandOverStopped(stops, [&](int s) { HandOverSlot(s, queue, queued, &next, &num_slots, load, move); });
  }
  // The bracketed crossings.
  Refinement jobs[kRayBatch];
  int job_ray[kRayBatch], num_jobs = 0;
  for (int r = 0; r < n; ++r) {
    const March& a = m[r];
    rays[r].found = false;
    // Written for every ray, kept (counted) for the bracketed ones.
    jobs[num_jobs] = Bracket(rays[r].o, a.direction, a.lo, a.hi, a.phi_lo, a.phi_hi);
    job_ray[num_jobs] = r;
    num_jobs += !(a.failed | SameSide(a.sign, a.phi_hi));
  }
  RefineCrossings(lookup, pair, jobs, num_jobs);
  for (int k = 0; k < num_jobs; ++k) {
    const Refinement& j = jobs[k];
    RayDistanceQuery& q = rays[job_ray[k]];
    for (int a = 0; a < 3; ++a) {
      q.c[a] = j.c[a];
      q.g_c[a] = j.g_c[a];
    }
    q.cell = j.cell;
    q.in_cell = j.in_cell;
    q.distance = j.t;
    const double slope = q.g_c[0] * q.u[0] + q.g_c[1] * q.u[1] + q.g_c[2] * q.u[2];
    q.found = !(j.t > m[job_ray[k]].limit) & (slope < -kMinRaySlope);
  }
}

void FirstCrossings(const ShapeLookup& lookup, const double* phi_z, const double* o_cam, FirstCrossingQuery* rays,
                    int n) {
  SAMP_CHECK(n >= 0 && n <= kRayBatch) << "FirstCrossings: " << n << " rays, at most " << kRayBatch;
  const double min_step = 0.5 * lookup.grid().voxel_size;
  // Each ray's last two samples when its trace stopped, the last one negative
  // after at least two samples: the bracket of its crossing.
  struct Trace {
    double last_l = 0.0, last_v = 0.0, prev_l = 0.0, prev_v = 0.0;
    bool bracketed = false;
  } t[kRayBatch];
  // The rays that enter the grid box, in order, with the span inside it.
  int queue[kRayBatch], queued = 0;
  double enter[kRayBatch], leave[kRayBatch];
  for (int r = 0; r < n; ++r) {
    // A ray passing the grid box misses (FirstCrossing's closest approach is
    // not needed without refine_miss).
    if (GridBoxSpan(lookup.grid(), o_cam, rays[r].u, &enter[r], &leave[r])) queue[queued++] = r;
  }
  // Sphere tracing from the box entry (FirstCrossing's loop, stopping after
  // the first sample beyond max_lambda) in the march slots, whose state is
  // kept per slot (the ray in slot s: its next sample at l[s], its box exit,
  // max_lambda and direction, its last two samples and their count).
  struct Slots {
    int ray[kMarchSlots], count[kMarchSlots];
    double l[kMarchSlots], leave[kMarchSlots], max_lambda[kMarchSlots], u[3][kMarchSlots];
    double last_l[kMarchSlots], last_v[kMarchSlots], prev_l[kMarchSlots], prev_v[kMarchSlots];
  } slots;
  int num_slots = 0, next = 0;
  auto load = [&](int s, int r) {
    slots.ray[s] = r;
    slots.count[s] = 0;
    slots.l[s] = enter[r];
    slots.leave[s] = leave[r];
    slots.max_lambda[s] = rays[r].max_lambda;
    for (int a = 0; a < 3; ++a) slots.u[a][s] = rays[r].u[a];
    slots.last_l[s] = slots.last_v[s] = slots.prev_l[s] = slots.prev_v[s] = 0.0;
  };
  auto move = [&](int to, int from) {
    slots.ray[to] = slots.ray[from];
    slots.count[to] = slots.count[from];
    slots.l[to] = slots.l[from];
    slots.leave[to] = slots.leave[from];
    slots.max_lambda[to] = slots.max_lambda[from];
    for (int a = 0; a < 3; ++a) slots.u[a][to] = slots.u[a][from];
    slots.last_l[to] = slots.last_l[from];
    slots.last_v[to] = slots.last_v[from];
    slots.prev_l[to] = slots.prev_l[from];
    slots.prev_v[to] = slots.prev_v[from];
  };
  double x[kMarchSlots], y[kMarchSlots], z[kMarchSlots], v[kMarchSlots];
  while (num_slots < kMarchSlots && next < queued) load(num_slots++, queue[next++]);
  const ShapeLookup::DenseValuePair pair(lookup, phi_z);
  const bool four = ShapeLookup::DenseValuePair::HasEvaluate4();
  while (num_slots > 0) {
    for (int s = 0; s < num_slots; ++s) {
      x[s] = o_cam[0] + slots.l[s] * slots.u[0][s];
      y[s] = o_cam[1] + slots.l[s] * slots.u[1][s];
      z[s] = o_cam[2] + slots.l[s] * slots.u[2][s];
    }
    SampleSlots(lookup, pair, four, phi_z, x, y, z, num_slots, v);
    // Every slot's sample, and whether its trace stops, without a branch on
    // it (the tests joined by &); every trace steps (a stopping one's next l
    // is not read).
    uint32_t stops = 0;
    for (int s = 0; s < num_slots; ++s) {
      const double value = v[s];
      // The last two samples (read only from a bracketed trace, whose
      // samples are all finite).
      slots.prev_l[s] = slots.last_l[s];
      slots.prev_v[s] = slots.last_v[s];
      slots.last_l[s] = slots.l[s];
      slots.last_v[s] = value;
      ++slots.count[s];
      const bool finite = std::isfinite(value);
      const bool go_on = finite & !(value < 0.0) & !(slots.l[s] >= slots.leave[s]) &
                         !(slots.count[s] > kMaxTraceSteps) & !(slots.l[s] > slots.max_lambda[s]);
      stops |= uint32_t(!go_on) << s;
      slots.l[s] = std::min(slots.l[s] + std::max(value, min_step), slots.leave[s]);
    }
    HandOverStopped(stops, [&](int s) {
      // Inside at the box entry (one sample): a miss without refine_miss.
      const double value = slots.last_v[s];
      const bool bracketed = std::isfinite(value) & (value < 0.0) & (slots.count[s] >= 2);
      // The trace's result, then the slot's hand-over.
      Trace& done = t[slots.ray[s]];
      done.bracketed = bracketed;
      done.last_l = slots.last_l[s];
      done.last_v = slots.last_v[s];
      done.prev_l = slots.prev_l[s];
      done.prev_v = slots.prev_v[s];
      HandOverSlot(s, queue, queued, &next, &num_slots, load, move);
    });
  }
  // The bracketed crossings.
  Refinement jobs[kRayBatch];
  int job_ray[kRayBatch], num_jobs = 0;
  for (int r = 0; r < n; ++r) {
    const Trace& a = t[r];
    rays[r].hit = a.bracketed;
    // Written for every ray, kept (counted) for the bracketed ones.
    jobs[num_jobs] = Bracket(o_cam, rays[r].u, a.prev_l, a.last_l, a.prev_v, a.last_v);
    job_ray[num_jobs] = r;
    num_jobs += a.bracketed;
  }
  RefineCrossings(lookup, pair, jobs, num_jobs);
  for (int k = 0; k < num_jobs; ++k) {
    const Refinement& j = jobs[k];
    FirstCrossingQuery& q = rays[job_ray[k]];
    q.lambda = j.t;
    for (int a = 0; a < 3; ++a) {
      q.c[a] = j.c[a];
      q.g_c[a] = j.g_c[a];
    }
    q.cell = j.cell;
    q.in_cell = j.in_cell;
  }
}

}  // namespace samp
