#include "dpc/control/task_pseudo_inverse.h"

#include "dpc/optics/count_dispatch.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace dpc {
namespace {

inline double Dot(const double* x, const double* y, int n) {
  double sum = 0.0;
  for (int i = 0; i < n; ++i) sum += x[i] * y[i];
  return sum;
}

}  // namespace

void TaskPseudoInverse::Compute(const TaskJacobian& a) { Factorize<false>(a, 0.0, 0.0); }

void TaskPseudoInverse::ComputeDamped(const TaskJacobian& a, double max_damping,
                                      double threshold) {
  Factorize<true>(a, max_damping * max_damping, threshold * threshold);
}

template <bool kDamped>
void TaskPseudoInverse::Factorize(const TaskJacobian& a, double max_damping_squared,
                                  double threshold_squared) {
  assert(a.rows() == 1 || a.rows() == 2);
  rows_ = static_cast<int>(a.rows());
  n_ = static_cast<int>(a.cols());
  damping_squared_ = 0.0;
  const double* r0 = a.data();  // row-major: rows are contiguous
  solve_[0][0] = solve_[0][1] = solve_[1][0] = solve_[1][1] = 0.0;
  project_[0][0] = project_[0][1] = project_[1][0] = project_[1][1] = 0.0;
  DispatchCount(n_, [&](auto fixed) {
    const int n = FixedOr(fixed, n_);
    if (rows_ == 1) {
      double g = 0.0;
      for (int i = 0; i < n; ++i) {
        b_[0][i] = r0[i];
        g += r0[i] * r0[i];
      }
      singular_values_ = SingularValues::FromGram(g);
      rank_ = g > 0.0 ? 1 : 0;
      if constexpr (kDamped) {
        if (g < threshold_squared) {
          damping_squared_ = max_damping_squared * (1.0 - g / threshold_squared);
        }
        const double denominator = g + damping_squared_;
        if (denominator > 0.0) solve_[0][0] = project_[0][0] = 1.0 / denominator;
      } else {
        if (rank_) solve_[0][0] = project_[0][0] = 1.0 / g;
      }
      return;
    }
    const double* r1 = r0 + n_;
    double g11 = 0.0, g22 = 0.0, g12 = 0.0;
    for (int i = 0; i < n; ++i) {
      g11 += r0[i] * r0[i];
      g22 += r1[i] * r1[i];
      g12 += r0[i] * r1[i];
    }
    const double trace = g11 + g22;
    const double det = g11 * g22 - g12 * g12;
    if (!(det > kWellConditioned * trace * trace)) {
      // The Jacobi path measures σ_min accurately; it damps there.
      ComputeJacobi(r0, r1, g11, g22, g12, max_damping_squared, threshold_squared);
      return;
    }
    rank_ = 2;
    for (int i = 0; i < n; ++i) {
      b_[0][i] = r0[i];
      b_[1][i] = r1[i];
    }
    double d11 = g11, d22 = g22, inverse_det;
    if constexpr (kDamped) {  // σ_min² = λ2 of G (SingularValues::min_squared); (G + λ²I)⁻¹
      const double root = std::sqrt((g11 - g22) * (g11 - g22) + 4.0 * g12 * g12);
      const double sigma_min_squared = 2.0 * det / (trace + root);
      if (sigma_min_squared < threshold_squared) {
        damping_squared_ = max_damping_squared * (1.0 - sigma_min_squared / threshold_squared);
      }
      d11 += damping_squared_;
      d22 += damping_squared_;
      inverse_det = 1.0 / (d11 * d22 - g12 * g12);
    } else {
      inverse_det = 1.0 / det;
    }
    solve_[0][0] = project_[0][0] = d22 * inverse_det;
    solve_[1][1] = project_[1][1] = d11 * inverse_det;
    solve_[0][1] = solve_[1][0] = project_[0][1] = project_[1][0] = -g12 * inverse_det;
    singular_values_ = SingularValues::FromGram(g11, g22, g12, det);
  });
}

void TaskPseudoInverse::ComputeJacobi(const double* r0, const double* r1, double g11,
                                      double g22, double g12, double max_damping_squared,
                                      double threshold_squared) {
  const int n = n_;
  // Jacobi rotation zeroing the off-diagonal of G (Golub & Van Loan, 2 × 2 symmetric Schur).
  double c = 1.0, s = 0.0;
  if (g12 != 0.0) {
    const double tau = (g22 - g11) / (2.0 * g12);
    const double t = std::copysign(1.0, tau) / (std::abs(tau) + std::sqrt(1.0 + tau * tau));
    c = 1.0 / std::sqrt(1.0 + t * t);
    s = c * t;
  }
  // Rotated rows b1 = c·r0 − s·r1, b2 = s·r0 + c·r1, the larger first.
  const double n1 = c * c * g11 - 2.0 * c * s * g12 + s * s * g22;
  const double n2 = s * s * g11 + 2.0 * c * s * g12 + c * c * g22;
  const double u_a[2] = {c, -s}, u_b[2] = {s, c};
  const double* u0 = n2 > n1 ? u_b : u_a;
  const double* u1 = n2 > n1 ? u_a : u_b;
  for (int i = 0; i < n; ++i) {
    b_[0][i] = u0[0] * r0[i] + u0[1] * r1[i];
    b_[1][i] = u1[0] * r0[i] + u1[1] * r1[i];
  }
  const double norm0 = Dot(b_[0], b_[0], n);
  if (!(norm0 > 0.0)) {
    singular_values_ = SingularValues::Exact(0.0, 0.0);
    rank_ = 0;
    return;
  }
  // Re-orthogonalize b2 against b1 (removes the round-off of the rotation).
  const double projection = Dot(b_[0], b_[1], n) / norm0;
  for (int i = 0; i < n; ++i) b_[1][i] -= projection * b_[0][i];
  const double norm1 = Dot(b_[1], b_[1], n);
  const double sigma0 = std::sqrt(norm0), sigma1 = std::sqrt(norm1);
  singular_values_ = SingularValues::Exact(sigma0, sigma1);
  const bool full_rank = sigma1 > relative_tolerance_ * sigma0;
  rank_ = full_rank ? 2 : 1;
  // Damping (ComputeDamped only): λ² from σ_min = σ1 here.
  const double lambda_squared =
      norm1 < threshold_squared ? max_damping_squared * (1.0 - norm1 / threshold_squared) : 0.0;
  damping_squared_ = lambda_squared;
  const double inverse0 = 1.0 / (norm0 + lambda_squared);
  const double inverse1 =
      full_rank || lambda_squared > 0.0 ? 1.0 / (norm1 + lambda_squared) : 0.0;
  solve_[0][0] = inverse0 * u0[0];
  solve_[0][1] = inverse0 * u0[1];
  solve_[1][0] = inverse1 * u1[0];
  solve_[1][1] = inverse1 * u1[1];
  project_[0][0] = inverse0;
  project_[1][1] = inverse1;
}

void TaskPseudoInverse::Solve(const TaskVector& e, ControlVector* x) const {
  const int n = n_;
  x->resize(n);
  double* out = x->data();
  if (rows_ == 1) {
    const double y0 = solve_[0][0] * e[0];
    for (int i = 0; i < n; ++i) out[i] = b_[0][i] * y0;
    return;
  }
  const double y0 = solve_[0][0] * e[0] + solve_[0][1] * e[1];
  const double y1 = solve_[1][0] * e[0] + solve_[1][1] * e[1];
  for (int i = 0; i < n; ++i) out[i] = b_[0][i] * y0 + b_[1][i] * y1;
}

void TaskPseudoInverse::NullSpaceProjection(const ControlVector& v, ControlVector* out) const {
  const int n = n_;
  const double* in = v.data();
  out->resize(n);
  double* result = out->data();
  if (rows_ == 1) {
    const double y0 = project_[0][0] * Dot(b_[0], in, n);
    for (int i = 0; i < n; ++i) result[i] = in[i] - b_[0][i] * y0;
    return;
  }
  const double z0 = Dot(b_[0], in, n), z1 = Dot(b_[1], in, n);
  const double y0 = project_[0][0] * z0 + project_[0][1] * z1;
  const double y1 = project_[1][0] * z0 + project_[1][1] * z1;
  for (int i = 0; i < n; ++i) result[i] = in[i] - b_[0][i] * y0 - b_[1][i] * y1;
}

void TaskPseudoInverse::GradientProjectionStep(const TaskVector& e, const ControlVector& phi,
                                               double step, double nullspace_step,
                                               ControlVector* out) const {
  out->resize(n_);
  DispatchCount(n_, [&](auto fixed) {
    const int n = FixedOr(fixed, n_);
    const double* v = phi.data();
    double* result = out->data();
    const double* b0 = b_[0];
    const double* b1 = b_[1];
    double z0 = 0.0, z1 = 0.0;
    for (int i = 0; i < n; ++i) {
      z0 += b0[i] * v[i];
      z1 += b1[i] * v[i];
    }
    const double e0 = e[0], e1 = rows_ == 2 ? e[1] : 0.0;
    if (rows_ == 1) z1 = 0.0;
    const double y0 = step * (solve_[0][0] * e0 + solve_[0][1] * e1) +
                      nullspace_step * (project_[0][0] * z0 + project_[0][1] * z1);
    const double y1 = rows_ == 2 ? step * (solve_[1][0] * e0 + solve_[1][1] * e1) +
                                       nullspace_step * (project_[1][0] * z0 + project_[1][1] * z1)
                                 : 0.0;
    for (int i = 0; i < n; ++i) result[i] = b0[i] * y0 + b1[i] * y1 - nullspace_step * v[i];
  });
}

}  // namespace dpc
