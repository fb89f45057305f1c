#pragma once
// The product manifold M = (St(r,d) x R^r)^n of lifted poses used by the rank-restricted
// (Burer–Monteiro) relaxation. A point is an r x (d+1)n matrix X = [Y_1 p_1 | ... | Y_n p_n]:
// pose i occupies columns (d+1)i .. (d+1)i+d, first the d Stiefel columns Y_i (Y_i^T Y_i = I),
// then the translation p_i. Tangent vectors have the same shape.

#include <Eigen/Core>
#include <cstddef>

namespace tessera {

class LiftedManifold {
 public:
  /// r >= d >= 2, n >= 1.
  LiftedManifold(int r, int d, std::size_t n);

  int rank() const { return r_; }
  int dim() const { return d_; }
  std::size_t num_poses() const { return n_; }
  Eigen::Index cols() const { return static_cast<Eigen::Index>((d_ + 1) * n_); }

  /// Nearest point of M (Frobenius): each Y_i replaced by its polar factor, p_i kept.
  /// This is Proj_M of the IRBCD paper.
  Eigen::MatrixXd project(const Eigen::MatrixXd& X) const;

  /// Orthogonal projection of an ambient V onto the tangent space at X:
  /// V_i - Y_i sym(Y_i^T V_i) on Stiefel blocks, translations unchanged.
  Eigen::MatrixXd tangent_project(const Eigen::MatrixXd& X, const Eigen::MatrixXd& V) const;
  /// The same, projecting V in its own storage (no copy of V; the same values).
  Eigen::MatrixXd tangent_project(const Eigen::MatrixXd& X, Eigen::MatrixXd&& V) const;

  /// Retraction R_X(V) = project(X + V) (the polar retraction).
  Eigen::MatrixXd retract(const Eigen::MatrixXd& X, const Eigen::MatrixXd& V) const;

  /// The curvature term of the Riemannian Hessian of f at X for tangent V:
  /// V_i sym(Y_i^T G_i) on Stiefel blocks (zero on translations), G = Euclidean gradient.
  Eigen::MatrixXd weingarten_term(const Eigen::MatrixXd& X, const Eigen::MatrixXd& G,
                                  const Eigen::MatrixXd& V) const;

  /// Largest deviation max_i ||Y_i^T Y_i - I||_F (0 on the manifold).
  double distance_from_manifold(const Eigen::MatrixXd& X) const;

 private:
  int r_;
  int d_;
  std::size_t n_;
};

/// Polar factor U V^T of an r x d matrix A = U S V^T (the nearest matrix with orthonormal columns).
Eigen::MatrixXd polar_factor(const Eigen::MatrixXd& A);

}  // namespace tessera
