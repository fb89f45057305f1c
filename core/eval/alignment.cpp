#include <Eigen/Dense>
#include <string>
#include <tessera/eval/alignment.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

const char* align_mode_name(AlignMode mode) {
  switch (mode) {
    case AlignMode::kSim3:
      return "sim3";
    case AlignMode::kNone:
      return "none";
    case AlignMode::kSe3:
      break;
  }
  return "se3";
}

AlignMode parse_align_mode(const std::string& name) {
  if (name == "se3") return AlignMode::kSe3;
  if (name == "sim3") return AlignMode::kSim3;
  if (name == "none") return AlignMode::kNone;
  throw InputError("option --align: '" + name + "' is not one of se3, sim3, none");
}

Alignment umeyama_alignment(const Eigen::MatrixXd& from, const Eigen::MatrixXd& to,
                            AlignMode mode) {
  const Eigen::Index d = from.rows(), n = from.cols();
  Alignment a{Eigen::MatrixXd::Identity(d, d), Eigen::VectorXd::Zero(d), 1.0};
  if (mode == AlignMode::kNone || n == 0) return a;
  const Eigen::VectorXd mu_from = from.rowwise().mean(), mu_to = to.rowwise().mean();
  const Eigen::MatrixXd x = from.colwise() - mu_from, y = to.colwise() - mu_to;
  const Eigen::MatrixXd sigma = y * x.transpose() / static_cast<double>(n);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::VectorXd s = Eigen::VectorXd::Ones(d);
  // A reflection is no motion: flip the direction of the smallest singular value instead.
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) s(d - 1) = -1;
  a.R = svd.matrixU() * s.asDiagonal() * svd.matrixV().transpose();
  if (mode == AlignMode::kSim3) {
    const double var_from = x.squaredNorm() / static_cast<double>(n);
    if (var_from > 0) a.scale = svd.singularValues().dot(s) / var_from;
  }
  a.t = mu_to - a.scale * a.R * mu_from;
  return a;
}

}  // namespace tessera
