#pragma once
// Internal: the gauge of the Newton refinement's problem at rank d, and the step's projection
// off it.
//
// A global rigid motion (X -> O X for O in SO(d), every translation plus one vector) leaves f
// unchanged, so the tangent vectors it generates, V = [Omega_k X ; e_k in every translation],
// d(d+1)/2 of them, carry no decrease: <g, V> = 0 and f is constant along them exactly (the
// rigid retraction moves every pose by the same rigid motion, distributed/rigid_retraction.hpp).
// The quadratic model is not: away from a critical point <V, Hess f V> is of the order of
// |g| |V|^2, which a step with a large gauge part (the lever arm of a global turn is the map's
// extent) counts as a decrease f cannot give. The refinement's CG with the grounded interface
// solves (interface_solve.hpp) takes steps that hold one pose fixed, so they carry the gauge
// motion that keeps that pose in place; the step tried is its part orthogonal to V, with the
// model's terms corrected from the sums V^T s and V^T H s, which its CG carries by recurrence
// (parking-garage at N = 5: 5 Newton steps with the gauge part left in, 4 without, the same f;
// docs/newton-refine.md, "Gauge").
//
// With NewtonRefineOptions::project_gauge the CG instead works on the vectors orthogonal to V
// (each iteration's z and H z projected off it), so its steps carry no gauge part at all.
//
// Each agent holds the columns on its own poses and its neighbours' (from X and Xn), so H V is
// a local product; the k x k sums V^T V and V^T H V are summed once per point.

#include <Eigen/Core>
#include <vector>

namespace tessera {

class GaugeSpace {
 public:
  /// The basis at a rank-d point: X the block's poses (d x (d+1) m), Xn the neighbours'.
  GaugeSpace(int d, const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn);
  /// d(d+1)/2: rotations first (the generators of so(d)), then translations.
  int size() const { return static_cast<int>(own_.size()); }
  /// Column k on the own poses and on the neighbours' copies.
  const Eigen::MatrixXd& own(int k) const { return own_[static_cast<std::size_t>(k)]; }
  const Eigen::MatrixXd& neighbours(int k) const {
    return neighbours_[static_cast<std::size_t>(k)];
  }
  /// The block's share of V^T v (size() numbers) into out.
  void dot(const Eigen::MatrixXd& v, double* out) const;
  /// v -= V c on the own poses.
  void subtract(const Eigen::VectorXd& c, Eigen::MatrixXd& v) const;

 private:
  std::vector<Eigen::MatrixXd> own_, neighbours_;
};

}  // namespace tessera
