#include "calibration.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace dpc::tools {

Matrix3 FitRotation(const std::vector<StokesVector>& from, const std::vector<StokesVector>& to, double* spread) {
  if (from.size() != to.size() || from.size() < 2) {
    throw std::invalid_argument("a rotation is fitted from at least 2 pairs of vectors");
  }
  Matrix3 covariance = Matrix3::Zero();
  for (size_t k = 0; k < from.size(); ++k) covariance += to[k] * from[k].transpose();
  const Eigen::JacobiSVD<Matrix3> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Vector3 sigma = svd.singularValues();
  if (spread != nullptr) *spread = sigma[0] > 0 ? sigma[1] / sigma[0] : 0.0;
  // The proper rotation: flip the weakest direction if U·Vᵀ is a reflection.
  Matrix3 d = Matrix3::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

std::optional<Vector3> RotationAxis(const Matrix3& rotation, double min_angle_rad) {
  const Vector3 vee(rotation(2, 1) - rotation(1, 2), rotation(0, 2) - rotation(2, 0), rotation(1, 0) - rotation(0, 1));
  const double sine = vee.norm() / 2, cosine = (rotation.trace() - 1) / 2;
  const double angle = std::atan2(sine, cosine);
  if (angle < min_angle_rad || angle > M_PI - min_angle_rad) return std::nullopt;
  return Vector3(vee / vee.norm());
}

double SignedAngleAbout(const Matrix3& rotation, const Vector3& axis) {
  const Vector3 vee(rotation(2, 1) - rotation(1, 2), rotation(0, 2) - rotation(2, 0), rotation(1, 0) - rotation(0, 1));
  return std::atan2(axis.dot(vee) / 2, (rotation.trace() - 1) / 2);
}

void Unwrap(std::vector<double>* angles_rad) {
  for (size_t k = 1; k < angles_rad->size(); ++k) {
    double& a = (*angles_rad)[k];
    const double previous = (*angles_rad)[k - 1];
    a -= 2 * M_PI * std::round((a - previous) / (2 * M_PI));
  }
}

ScaledPolynomial FitPolynomial(const std::vector<double>& x, const std::vector<double>& y, int degree) {
  const size_t n = x.size(), m = static_cast<size_t>(degree) + 1;
  if (y.size() != n || degree < 0 || n < m) throw std::invalid_argument("too few points for the polynomial");
  ScaledPolynomial p;
  double lo = x[0], hi = x[0];
  for (const double v : x) lo = std::min(lo, v), hi = std::max(hi, v);
  p.centre = (lo + hi) / 2;
  p.half = hi > lo ? (hi - lo) / 2 : 1.0;
  Eigen::MatrixXd a(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(m));
  Eigen::VectorXd b(static_cast<Eigen::Index>(n));
  for (size_t k = 0; k < n; ++k) {
    const double u = (x[k] - p.centre) / p.half;
    double power = 1.0;
    for (size_t j = 0; j < m; ++j, power *= u) a(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j)) = power;
    b[static_cast<Eigen::Index>(k)] = y[k];
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(b);
  p.coefficients.assign(c.data(), c.data() + c.size());
  return p;
}

double ScaledPolynomial::operator()(double x) const {
  const double u = (x - centre) / half;
  double value = 0.0;
  for (size_t j = coefficients.size(); j-- > 0;) value = value * u + coefficients[j];
  return value;
}

double ScaledPolynomial::Derivative(double x) const {
  const double u = (x - centre) / half;
  double value = 0.0;
  for (size_t j = coefficients.size(); j-- > 1;) value = value * u + static_cast<double>(j) * coefficients[j];
  return value / half;
}

}  // namespace dpc::tools
