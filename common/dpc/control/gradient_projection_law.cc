#include "dpc/control/gradient_projection_law.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace dpc {
namespace {

// 0·x is 0 for finite x and NaN for NaN or ±Inf: one branch for the whole vector.
bool AllFinite(const ControlVector& v) {
  double sum = 0.0;
  for (int i = 0; i < v.size(); ++i) sum += 0.0 * v[i];
  return sum == 0.0;
}

}  // namespace

GradientProjectionLaw::GradientProjectionLaw(double step, double nullspace_step,
                                             std::optional<double> threshold,
                                             double singular_value_tolerance)
    : GradientProjectionLaw(step, nullspace_step,
                            GradientProjectionOptions{threshold, singular_value_tolerance}) {}

GradientProjectionLaw::GradientProjectionLaw(double step, double nullspace_step,
                                             const GradientProjectionOptions& options)
    : step_(step),
      nullspace_step_(nullspace_step),
      threshold_(options.threshold),
      max_damping_(options.max_damping),
      damping_threshold_(options.damping_threshold),
      range_aware_(options.range_aware),
      curvature_correction_(options.curvature_correction),
      has_options_(options.max_damping != 0.0 || options.range_aware ||
                   options.curvature_correction),
      pseudo_inverse_(options.singular_value_tolerance) {
  if (!std::isfinite(step) || !(step > 0.0)) {
    throw std::invalid_argument(fmt::format("gradient projection step must be > 0 (got {})", step));
  }
  if (!std::isfinite(nullspace_step) || nullspace_step < 0.0) {
    throw std::invalid_argument(
        fmt::format("gradient projection null-space step must be >= 0 (got {})", nullspace_step));
  }
  if (threshold_ && (!std::isfinite(*threshold_) || *threshold_ < 0.0)) {
    throw std::invalid_argument(
        fmt::format("gradient projection threshold must be >= 0 (got {})", *threshold_));
  }
  if (!std::isfinite(max_damping_) || max_damping_ < 0.0) {
    throw std::invalid_argument(
        fmt::format("gradient projection damping must be >= 0 (got {})", max_damping_));
  }
  if (!std::isfinite(damping_threshold_) || !(damping_threshold_ > 0.0)) {
    throw std::invalid_argument(fmt::format(
        "gradient projection damping threshold must be > 0 (got {})", damping_threshold_));
  }
}

inline bool GradientProjectionLaw::NullspaceActive(const ControlVector& phi) const {
  if (!(nullspace_step_ > 0.0)) return false;
  if (!threshold_) return true;
  double largest = 0.0;
  for (int i = 0; i < phi.size(); ++i) largest = std::max(largest, std::abs(phi[i]));
  return largest > *threshold_;
}

void GradientProjectionLaw::Factorize(const TaskJacobian& task) {
  if (max_damping_ > 0.0) {
    pseudo_inverse_.ComputeDamped(task, max_damping_, damping_threshold_);
  } else {
    pseudo_inverse_.Compute(task);
  }
}

void GradientProjectionLaw::RangeGradient(const ControlProblem& problem) {
  const ControlVector& phi = problem.phi();
  const int n = static_cast<int>(phi.size());
  const std::vector<double>& lo = problem.chain->range_min();
  const std::vector<double>& hi = problem.chain->range_max();
  gradient_.resize(n);
  for (int i = 0; i < n; ++i) {
    const double low = lo[static_cast<size_t>(i)], high = hi[static_cast<size_t>(i)];
    if (!std::isfinite(low) || !std::isfinite(high)) {
      gradient_[i] = phi[i];
      continue;
    }
    const double half = 0.5 * (high - low);
    const double x = (phi[i] - 0.5 * (high + low)) / half;
    const double x2 = x * x;
    const double g = x + x * x2 * x2 * x2;
    // In φ's unit (h·x = φ − c): the pull near the centre is the paper's whatever the unit.
    gradient_[i] = half * std::clamp(g, -kMaxRangeGradient, kMaxRangeGradient);
  }
}

ControlStatus GradientProjectionLaw::ComputeUpdate(const ControlProblem& problem,
                                                   ControlVector* delta_phi) {
  if (has_options_) return ComputeUpdateWithOptions(problem, delta_phi);
  // The paper's law.
  pseudo_inverse_.Compute(problem.task_jacobian);
  diagnostics_.rank = pseudo_inverse_.rank();
  diagnostics_.singular_values = pseudo_inverse_.singular_values();

  const ControlVector& phi = problem.phi();
  const int n = static_cast<int>(phi.size());
  const bool active = NullspaceActive(phi);
  diagnostics_.nullspace_active = active;
  pseudo_inverse_.GradientProjectionStep(problem.task_error, phi, step_,
                                         active ? nullspace_step_ : 0.0, delta_phi);
  // 0·x is 0 for finite x and NaN for NaN or ±Inf: one branch for the whole vector.
  double sum = 0.0;
  for (int i = 0; i < n; ++i) sum += 0.0 * (*delta_phi)[i];
  if (sum != 0.0) {
    delta_phi->setZero();
    return ControlStatus::kNotFinite;
  }
  const bool full_rank = pseudo_inverse_.rank() == problem.task_jacobian.rows();
  return full_rank ? ControlStatus::kOk : ControlStatus::kRankDeficient;
}

ControlStatus GradientProjectionLaw::ComputeUpdateWithOptions(const ControlProblem& problem,
                                                              ControlVector* delta_phi) {
  const ControlVector& phi = problem.phi();
  const bool active = NullspaceActive(phi);
  diagnostics_.nullspace_active = active;
  const double nullspace_step = active ? nullspace_step_ : 0.0;
  Factorize(problem.task_jacobian);
  if (range_aware_) RangeGradient(problem);
  pseudo_inverse_.GradientProjectionStep(problem.task_error, range_aware_ ? gradient_ : phi,
                                         step_, nullspace_step, delta_phi);
  diagnostics_.rank = pseudo_inverse_.rank();
  diagnostics_.singular_values = pseudo_inverse_.singular_values();
  const bool full_rank = pseudo_inverse_.rank() == problem.task_jacobian.rows();
  saturated_count_ = 0;
  if (curvature_correction_ && AllFinite(*delta_phi)) CorrectCurvature(problem, delta_phi);
  if (range_aware_ && problem.chain->has_ranges() && AllFinite(*delta_phi)) {
    SaturateAndResolve(problem, nullspace_step, delta_phi);
  }
  if (!AllFinite(*delta_phi)) {
    delta_phi->setZero();
    return ControlStatus::kNotFinite;
  }
  return full_rank ? ControlStatus::kOk : ControlStatus::kRankDeficient;
}

void GradientProjectionLaw::CorrectCurvature(const ControlProblem& problem,
                                             ControlVector* delta_phi) {
  const WaveplateChain& chain = *problem.chain;
  const ChainKinematics& k = problem.kinematics;
  const TaskJacobian& task = problem.task_jacobian;
  const int n = static_cast<int>(delta_phi->size());
  next_phi_ = problem.phi() + *delta_phi;
  chain.ComputePoseFrom(*problem.pose, next_phi_, &next_pose_);
  const Target& target = *problem.target;
  residual_.resize(task.rows());
  // r = TΔφ (the linear model's decrease of e) − (e(φ) − e(φ + Δφ)) (the model's).
  if (target.is_point()) {
    // e_i(φ) = e_iᵀMᵀS* − e_iᵀS_in: the decrease is (M e_i − M′e_i)·S*.
    const Vector3& e1 = problem.tangent_e1;
    const Vector3& e2 = problem.tangent_e2;
    const StokesVector& point = target.point();
    const double decrease0 = (k.mueller * e1 - chain.Output(next_pose_, e1)).dot(point);
    const double decrease1 = (k.mueller * e2 - chain.Output(next_pose_, e2)).dot(point);
    residual_[0] = task.row(0).dot(delta_phi->head(n)) - decrease0;
    residual_[1] = task.row(1).dot(delta_phi->head(n)) - decrease1;
  } else {
    // e = c − n·M S_in: the decrease is n·(M′S_in − M S_in).
    const double decrease =
        target.normal().dot(chain.Output(next_pose_, problem.s_in) - k.s_out);
    residual_[0] = task.row(0).dot(delta_phi->head(n)) - decrease;
  }
  // Always damped: near a singularity an undamped correction would be as large as 1/σ_min.
  if (max_damping_ == 0.0) {
    pseudo_inverse_.ComputeDamped(task, kDefaultMaxDamping, kDefaultDampingThreshold);
  }
  pseudo_inverse_.Solve(residual_, &correction_);
  *delta_phi += correction_;
}

void GradientProjectionLaw::SaturateAndResolve(const ControlProblem& problem,
                                               double nullspace_step, ControlVector* delta_phi) {
  const ControlVector& phi = problem.phi();
  const int n = static_cast<int>(phi.size());
  const std::vector<double>& lo = problem.chain->range_min();
  const std::vector<double>& hi = problem.chain->range_max();
  for (int i = 0; i < n; ++i) saturated_[i] = false;
  fixed_delta_.setZero(n);
  const TaskJacobian& task = problem.task_jacobian;
  const int rows = static_cast<int>(task.rows());
  const double max_damping = max_damping_ > 0.0 ? max_damping_ : kDefaultMaxDamping;
  const double threshold = max_damping_ > 0.0 ? damping_threshold_ : kDefaultDampingThreshold;
  for (int round = 0; round < n; ++round) {
    bool new_saturation = false;
    for (int i = 0; i < n; ++i) {
      if (saturated_[i]) continue;
      const double next = phi[i] + (*delta_phi)[i];
      const double low = lo[static_cast<size_t>(i)], high = hi[static_cast<size_t>(i)];
      if (next > high || next < low) {
        saturated_[i] = true;
        ++saturated_count_;
        // A control already outside (never, unless φ started there) moves to its limit.
        fixed_delta_[i] = (next > high ? high : low) - phi[i];
        new_saturation = true;
      }
    }
    if (!new_saturation) return;
    // The task with the fixed controls' columns zeroed; their effect moved to the error side.
    masked_task_ = task;
    masked_gradient_ = range_aware_ && gradient_.size() == n ? gradient_ : phi;
    shifted_error_ = problem.task_error;
    for (int i = 0; i < n; ++i) {
      if (!saturated_[i]) continue;
      for (int r = 0; r < rows; ++r) {
        shifted_error_[r] -= task(r, i) * fixed_delta_[i] / step_;
        masked_task_(r, i) = 0.0;
      }
      masked_gradient_[i] = 0.0;
    }
    pseudo_inverse_.ComputeDamped(masked_task_, max_damping, threshold);
    pseudo_inverse_.GradientProjectionStep(shifted_error_, masked_gradient_, step_,
                                           nullspace_step, delta_phi);
    for (int i = 0; i < n; ++i) {
      if (saturated_[i]) (*delta_phi)[i] = fixed_delta_[i];
    }
    if (!AllFinite(*delta_phi)) return;
  }
}

}  // namespace dpc
