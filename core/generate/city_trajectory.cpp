// city: a 2D random walk along the streets of a Manhattan grid, like M3500 and city10000.
#include <algorithm>
#include <cmath>
#include <limits>

#include "generate/geometry.hpp"
#include "generate/trajectory.hpp"

namespace tessera {
namespace {

constexpr long kBlock = 3;  // poses (metres) between intersections
constexpr std::size_t kNotVisited = std::numeric_limits<std::size_t>::max();

// Directions as unit steps, counter-clockwise from +x.
constexpr long kDx[4] = {1, 0, -1, 0};
constexpr long kDy[4] = {0, 1, 0, -1};

struct Walker {
  long x = 0, y = 0;  // position in metres on the street grid
  int dir = 0;        // index into kDx/kDy
};

// Street-grid size: about three visits per street cell (2 * side^2 * kBlock cells).
long intersections_per_side(std::size_t n) {
  return std::max<long>(2, std::lround(std::sqrt(double(n) / (6.0 * kBlock))));
}

// At an intersection: straight with probability 1/2, else left or right; never a U-turn
// and never off the grid (a corner always leaves one turn open).
int choose_direction(const Walker& w, long extent, RandomStream& random) {
  const int straight = w.dir, left = (w.dir + 1) % 4, right = (w.dir + 3) % 4;
  const double u = random.uniform();
  const int preferred = u < 0.5 ? straight : (u < 0.75 ? left : right);
  for (int dir : {preferred, straight, left, right}) {
    const long nx = w.x + kBlock * kDx[dir], ny = w.y + kBlock * kDy[dir];
    if (nx >= 0 && ny >= 0 && nx <= extent && ny <= extent) return dir;
  }
  return left;  // unreachable on a grid of at least 2 x 2 intersections
}

std::vector<Walker> walk_streets(std::size_t n, long extent, RandomStream& random) {
  std::vector<Walker> path(n);
  Walker w;
  for (std::size_t k = 0; k < n; ++k) {
    if (w.x % kBlock == 0 && w.y % kBlock == 0) w.dir = choose_direction(w, extent, random);
    path[k] = w;
    w.x += kDx[w.dir];
    w.y += kDy[w.dir];
  }
  return path;
}

}  // namespace

Trajectory make_city_trajectory(std::size_t n, RandomStream& random) {
  const long extent = (intersections_per_side(n) - 1) * kBlock;  // metres per side
  const std::vector<Walker> path = walk_streets(n, extent, random);

  Trajectory traj;
  traj.d = 2;
  traj.poses.reserve(n);
  for (const Walker& w : path) {
    Eigen::VectorXd t(2);
    t << double(w.x), double(w.y);
    traj.poses.push_back({planar_rotation(0.5 * kPi * w.dir), t});
  }

  // First and latest visit of every place, in a flat array (the map is small and dense).
  const std::size_t width = std::size_t(extent) + 1;
  std::vector<std::size_t> first(width * width, kNotVisited), latest(width * width, kNotVisited);
  traj.closure_candidates.reserve(2 * n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t cell = std::size_t(path[k].y) * width + std::size_t(path[k].x);
    if (first[cell] == kNotVisited) {
      first[cell] = k;
    } else {
      traj.closure_candidates.emplace_back(latest[cell], k);
      traj.closure_candidates.emplace_back(first[cell], k);
    }
    latest[cell] = k;
  }
  normalise_candidates(traj.closure_candidates, n);
  return traj;
}

}  // namespace tessera
