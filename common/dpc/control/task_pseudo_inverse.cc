#include "dpc/control/task_pseudo_inverse.h"

#include <cassert>
#include <cmath>
#include <utility>

namespace dpc {

void TaskPseudoInverse::Compute(const TaskJacobian& a) {
  assert(a.rows() == 1 || a.rows() == 2);
  rows_ = static_cast<int>(a.rows());
  inverse_sigma_squared_[0] = inverse_sigma_squared_[1] = 0.0;
  if (rows_ == 1) {
    b_[0] = a.row(0).transpose();
    const double g = b_[0].squaredNorm();
    sigma_[0] = std::sqrt(g);
    sigma_[1] = 0.0;
    u_.setIdentity();
    rank_ = g > 0.0 ? 1 : 0;
    if (rank_) inverse_sigma_squared_[0] = 1.0 / g;
    return;
  }
  const double g11 = a.row(0).squaredNorm();
  const double g22 = a.row(1).squaredNorm();
  const double g12 = a.row(0).dot(a.row(1));
  // Jacobi rotation zeroing the off-diagonal of G (Golub & Van Loan, sym. Schur 2 × 2).
  double c = 1.0, s = 0.0;
  if (g12 != 0.0) {
    const double tau = (g22 - g11) / (2.0 * g12);
    const double t = std::copysign(1.0, tau) / (std::abs(tau) + std::sqrt(1.0 + tau * tau));
    c = 1.0 / std::sqrt(1.0 + t * t);
    s = c * t;
  }
  u_ << c, s, -s, c;  // u1 = (c, −s), u2 = (s, c)
  b_[0].noalias() = c * a.row(0).transpose() - s * a.row(1).transpose();
  b_[1].noalias() = s * a.row(0).transpose() + c * a.row(1).transpose();
  double n0 = b_[0].squaredNorm(), n1 = b_[1].squaredNorm();
  if (n1 > n0) {
    std::swap(b_[0], b_[1]);
    std::swap(n0, n1);
    u_.col(0).swap(u_.col(1));
  }
  sigma_[0] = std::sqrt(n0);
  if (!(n0 > 0.0)) {
    sigma_[1] = 0.0;
    rank_ = 0;
    return;
  }
  // Re-orthogonalize b2 against b1 (removes the round-off of the rotation).
  b_[1] -= (b_[0].dot(b_[1]) / n0) * b_[0];
  n1 = b_[1].squaredNorm();
  sigma_[1] = std::sqrt(n1);
  inverse_sigma_squared_[0] = 1.0 / n0;
  if (sigma_[1] > relative_tolerance_ * sigma_[0]) {
    rank_ = 2;
    inverse_sigma_squared_[1] = 1.0 / n1;
  } else {
    rank_ = 1;
  }
}

void TaskPseudoInverse::Solve(const TaskVector& e, ControlVector* x) const {
  if (rows_ == 1) {
    x->noalias() = b_[0] * (e[0] * inverse_sigma_squared_[0]);
    return;
  }
  const double y0 = (u_(0, 0) * e[0] + u_(1, 0) * e[1]) * inverse_sigma_squared_[0];
  const double y1 = (u_(0, 1) * e[0] + u_(1, 1) * e[1]) * inverse_sigma_squared_[1];
  x->noalias() = b_[0] * y0 + b_[1] * y1;
}

void TaskPseudoInverse::NullSpaceProjection(const ControlVector& v, ControlVector* out) const {
  const double y0 = b_[0].dot(v) * inverse_sigma_squared_[0];
  if (rows_ == 1) {
    out->noalias() = v - b_[0] * y0;
    return;
  }
  const double y1 = b_[1].dot(v) * inverse_sigma_squared_[1];
  out->noalias() = v - b_[0] * y0 - b_[1] * y1;
}

}  // namespace dpc
