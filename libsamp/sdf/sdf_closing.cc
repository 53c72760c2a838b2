// The closing of the seen surface (sdf_stages.h, ClosingOutside; docs/sdf.md,
// "Sign: carving and closing") and the inside components of a sign.
#include <algorithm>
#include <cmath>

#include "libsamp/sdf/sdf_stages.h"

namespace samp {
namespace sdf_internal {
namespace {

// Calls visit(u) for each of the (up to six) face neighbours u of the voxel
// with linear index v, in the order -x, +x, -y, +y, -z, +z.
template <typename Visit>
void ForEachFaceNeighbour(const GridSpec& grid, int64_t v, Visit&& visit) {
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  const int64_t sy = nx, sz = int64_t(nx) * ny;
  const int i = int(v % nx), j = int((v / nx) % ny), k = int(v / sz);
  if (i > 0) visit(v - 1);
  if (i < nx - 1) visit(v + 1);
  if (j > 0) visit(v - sy);
  if (j < ny - 1) visit(v + sy);
  if (k > 0) visit(v - sz);
  if (k < nz - 1) visit(v + sz);
}

// O: the voxels farther than tau from the surface that a 6-connected flood
// fill reaches from the border voxels the carving calls outside; mark[v] = 1
// for each (buffers->mark). False when no border voxel seeds the fill.
bool FillFromBorder(const GridSpec& grid, const std::vector<float>& distance, const std::vector<uint8_t>& carved,
                    float tau, FloodBuffers* buffers) {
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  const size_t n = distance.size();
  std::vector<uint8_t>& fill = buffers->mark;
  fill.assign(n, 0);
  std::vector<int32_t>& queue = buffers->queue;
  queue.clear();
  queue.reserve(n / 4);
  auto seed = [&](int i, int j, int k) {
    const int64_t v = grid.Index(i, j, k);
    if (!fill[size_t(v)] && carved[size_t(v)] && distance[size_t(v)] > tau) {
      fill[size_t(v)] = 1;
      queue.push_back(int32_t(v));
    }
  };
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        if (i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1) seed(i, j, k);
      }
    }
  }
  if (queue.empty()) return false;
  for (size_t head = 0; head < queue.size(); ++head) {
    const int64_t v = queue[head];
    ForEachFaceNeighbour(grid, v, [&](int64_t u) {
      if (!fill[size_t(u)] && distance[size_t(u)] > tau) {
        fill[size_t(u)] = 1;
        queue.push_back(int32_t(u));
      }
    });
  }
  return true;
}

// Whether a voxel within tau of the surface lies in the open ball of radius
// d(o) around some voxel o of O (fill) within `reach` voxels of it.
class BallSearch {
 public:
  BallSearch(const GridSpec& grid, const std::vector<float>& distance, const std::vector<uint8_t>& fill,
             float radius_voxels)
      : grid_(grid), distance_(distance), fill_(fill), reach_(int(std::ceil(radius_voxels + 1.5f))) {
    const float h = float(grid.voxel_size);
    h2_ = h * h;
    // Neighbour offsets within the search radius, nearest first (an early hit is likely).
    for (int dk = -reach_; dk <= reach_; ++dk) {
      for (int dj = -reach_; dj <= reach_; ++dj) {
        for (int di = -reach_; di <= reach_; ++di) {
          const float r2 = float(di * di + dj * dj + dk * dk);
          if (r2 > 0.0f && r2 <= float(reach_ * reach_)) offsets_.push_back({di, dj, dk, r2});
        }
      }
    }
    std::stable_sort(offsets_.begin(), offsets_.end(),
                     [](const Offset& a, const Offset& b) { return a.squared_voxels < b.squared_voxels; });
    const int nx = grid.dims.x(), ny = grid.dims.y();
    steps_.resize(offsets_.size());  // linear index step of each offset
    for (size_t q = 0; q < offsets_.size(); ++q) {
      steps_[q] = offsets_[q].di + int64_t(nx) * (offsets_[q].dj + int64_t(ny) * offsets_[q].dk);
    }
  }

  // The voxel (i, j, k) with linear index v.
  bool InBall(int i, int j, int k, size_t v) const {
    const int nx = grid_.dims.x(), ny = grid_.dims.y(), nz = grid_.dims.z();
    // At least `reach` voxels from the border every offset stays in the
    // grid: linear index steps, no bounds checks (the same offsets in the
    // same order, so the same answer).
    const bool interior =
        i >= reach_ && j >= reach_ && k >= reach_ && i < nx - reach_ && j < ny - reach_ && k < nz - reach_;
    if (interior) {
      for (size_t q = 0; q < offsets_.size(); ++q) {
        const size_t u = size_t(int64_t(v) + steps_[q]);
        if (fill_[u] && offsets_[q].squared_voxels * h2_ < distance_[u] * distance_[u]) return true;
      }
      return false;
    }
    for (const Offset& o : offsets_) {
      const int oi = i + o.di, oj = j + o.dj, ok = k + o.dk;
      if (oi < 0 || oj < 0 || ok < 0 || oi >= nx || oj >= ny || ok >= nz) continue;
      const size_t u = size_t(grid_.Index(oi, oj, ok));
      if (fill_[u] && o.squared_voxels * h2_ < distance_[u] * distance_[u]) return true;
    }
    return false;
  }

 private:
  struct Offset {
    int di, dj, dk;
    float squared_voxels;
  };
  const GridSpec& grid_;
  const std::vector<float>& distance_;
  const std::vector<uint8_t>& fill_;
  const int reach_;
  float h2_ = 0.0f;
  std::vector<Offset> offsets_;
  std::vector<int64_t> steps_;
};

}  // namespace

bool ClosingOutside(const GridSpec& grid, const std::vector<float>& distance,
                    const std::vector<uint8_t>& carved, float radius_voxels,
                    FloodBuffers* buffers, std::vector<uint8_t>* closed_outside) {
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  const float h = float(grid.voxel_size);
  const float tau = radius_voxels * h;
  if (!FillFromBorder(grid, distance, carved, tau, buffers)) return false;
  const std::vector<uint8_t>& fill = buffers->mark;
  closed_outside->assign(distance.size(), 0);
  const BallSearch balls(grid, distance, fill, radius_voxels);
  const float on_surface = 1e-3f * h;
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const size_t v = size_t(grid.Index(i, j, k));
        if (fill[v]) {
          (*closed_outside)[v] = 1;
          continue;
        }
        const float d = distance[v];
        if (d > tau) continue;  // enclosed: inside
        if (!(d > on_surface)) {
          (*closed_outside)[v] = carved[v];  // on the surface
          continue;
        }
        if (balls.InBall(i, j, k, v)) (*closed_outside)[v] = 1;
      }
    }
  }
  return true;
}

void InsideComponents(const GridSpec& grid, const std::vector<uint8_t>& outside, FloodBuffers* buffers,
                      int* num_components, double* largest_share) {
  std::vector<uint8_t>& visited = buffers->mark;
  visited.assign(outside.size(), 0);
  std::vector<int32_t>& stack = buffers->queue;
  int64_t total = 0, largest = 0;
  *num_components = 0;
  for (size_t start = 0; start < outside.size(); ++start) {
    if (outside[start] || visited[start]) continue;
    ++*num_components;
    int64_t size = 0;
    visited[start] = 1;
    stack.assign(1, int32_t(start));
    while (!stack.empty()) {
      const int64_t v = stack.back();
      stack.pop_back();
      ++size;
      ForEachFaceNeighbour(grid, v, [&](int64_t u) {
        if (!outside[size_t(u)] && !visited[size_t(u)]) {
          visited[size_t(u)] = 1;
          stack.push_back(int32_t(u));
        }
      });
    }
    total += size;
    largest = std::max(largest, size);
  }
  *largest_share = total > 0 ? double(largest) / double(total) : 0.0;
}

}  // namespace sdf_internal
}  // namespace samp
