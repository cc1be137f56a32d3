#include "dpc/control/task_pseudo_inverse.h"

#include <cassert>
#include <cmath>

namespace dpc {

void TaskPseudoInverse::Compute(const TaskJacobian& a) {
  assert(a.rows() == 1 || a.rows() == 2);
  a_ = &a;
  rows_ = static_cast<int>(a.rows());
  const int n = static_cast<int>(a.cols());
  k_.setZero();
  if (rows_ == 1) {
    const double g = a.row(0).squaredNorm();
    sigma_max_ = sigma_min_ = std::sqrt(g);
    rank_ = g > 0.0 ? 1 : 0;
    if (rank_) k_(0, 0) = 1.0 / g;
    return;
  }
  const double g11 = a.row(0).squaredNorm();
  const double g22 = a.row(1).squaredNorm();
  const double g12 = a.row(0).dot(a.row(1));
  double det = 0.0;  // Cauchy–Binet
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const double minor = a(0, i) * a(1, j) - a(0, j) * a(1, i);
      det += minor * minor;
    }
  }
  const double half_trace = 0.5 * (g11 + g22);
  const double half_gap = std::sqrt(0.25 * (g11 - g22) * (g11 - g22) + g12 * g12);
  const double lambda1 = half_trace + half_gap;
  if (!(lambda1 > 0.0)) {
    rank_ = 0;
    sigma_max_ = sigma_min_ = 0.0;
    return;
  }
  const double lambda2 = det / lambda1;
  sigma_max_ = std::sqrt(lambda1);
  sigma_min_ = std::sqrt(lambda2);
  if (sigma_min_ > relative_tolerance_ * sigma_max_) {
    rank_ = 2;
    k_ << g22, -g12, -g12, g11;
    k_ /= det;
    return;
  }
  rank_ = 1;
  // Eigenvector of λ1: the larger of the two equivalent forms, for conditioning.
  Eigen::Vector2d u1(lambda1 - g22, g12), u2(g12, lambda1 - g11);
  Eigen::Vector2d u = u1.squaredNorm() >= u2.squaredNorm() ? u1 : u2;
  u.normalize();
  k_ = (u * u.transpose()) / lambda1;
}

void TaskPseudoInverse::Solve(const TaskVector& e, ControlVector* x) const {
  const TaskJacobian& a = *a_;
  if (rows_ == 1) {
    x->noalias() = a.row(0).transpose() * (k_(0, 0) * e[0]);
    return;
  }
  const Eigen::Vector2d y = k_ * Eigen::Vector2d(e[0], e[1]);
  x->noalias() = a.row(0).transpose() * y[0] + a.row(1).transpose() * y[1];
}

void TaskPseudoInverse::NullSpaceProjection(const ControlVector& v, ControlVector* out) const {
  const TaskJacobian& a = *a_;
  if (rows_ == 1) {
    const double y = k_(0, 0) * a.row(0).dot(v);
    out->noalias() = v - a.row(0).transpose() * y;
    return;
  }
  const Eigen::Vector2d av(a.row(0).dot(v), a.row(1).dot(v));
  const Eigen::Vector2d y = k_ * av;
  out->noalias() = v - a.row(0).transpose() * y[0] - a.row(1).transpose() * y[1];
}

}  // namespace dpc
