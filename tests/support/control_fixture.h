#pragma once
// Shared test set-up for control-law tests: a chain, an input SOP, a φ, and the ControlProblem
// built from them, plus reference formulas computed the slow way (full 3-D J, Eigen SVD).

#include <Eigen/SVD>

#include <memory>
#include <optional>
#include <random>

#include "dpc/control/control_problem.h"
#include "dpc/optics/waveplate_chain.h"

namespace dpc::testing {

/// Moore–Penrose pseudo-inverse by JacobiSVD with Eigen's default threshold.
inline Eigen::MatrixXd SvdPseudoInverse(const Eigen::MatrixXd& a, double relative_tolerance = 1e-12) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& s = svd.singularValues();
  Eigen::VectorXd inv = Eigen::VectorXd::Zero(s.size());
  for (int i = 0; i < s.size(); ++i) {
    if (s[i] > relative_tolerance * s[0]) inv[i] = 1.0 / s[i];
  }
  return svd.matrixV() * inv.asDiagonal() * svd.matrixU().transpose();
}

class ControlFixture {
 public:
  explicit ControlFixture(const std::string& axes, uint64_t seed = 11)
      : chain_(WaveplateChain::FromAxes(axes)), rng_(seed) {}

  StokesVector RandomSop() {
    return StokesVector(normal_(rng_), normal_(rng_), normal_(rng_)).normalized();
  }
  ControlVector RandomPhi(double scale = 0.7) {
    ControlVector phi(chain_.control_count());
    for (int i = 0; i < phi.size(); ++i) phi[i] = scale * normal_(rng_);
    return phi;
  }

  /// Builds problem_ for φ, S_in and target (S_out measured = model unless given).
  ControlProblem& Build(const ControlVector& phi, const StokesVector& s_in, const Target& target,
                        LoopMode mode = LoopMode::kModel,
                        std::optional<StokesVector> s_out_measured = std::nullopt) {
    target_ = std::make_unique<Target>(target);
    chain_.ComputePose(phi, &pose_);
    problem_.chain = &chain_;
    problem_.target = target_.get();
    problem_.pose = &pose_;
    problem_.s_in = s_in;
    problem_.loop_mode = mode;
    problem_.s_out_measured = s_out_measured.value_or(chain_.Output(pose_, s_in));
    UpdateControlProblem(&problem_);
    return problem_;
  }

  /// The full task for the reference formulas: (J, S* − S) or (nᵀJ, c − n·S).
  Eigen::MatrixXd FullTaskJacobian() const {
    const Eigen::MatrixXd j = problem_.kinematics.jacobian;
    if (target_->is_point()) return j;
    return target_->normal().transpose() * j;
  }
  Eigen::VectorXd FullTaskError() const {
    if (target_->is_point()) return problem_.PointError();
    Eigen::VectorXd e(1);
    e[0] = target_->offset() - target_->normal().dot(problem_.s_out_for_error);
    return e;
  }

  const WaveplateChain& chain() const { return chain_; }
  ControlProblem& problem() { return problem_; }

 protected:
  WaveplateChain chain_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_;
  ChainPose pose_;
  ControlProblem problem_;
  std::unique_ptr<Target> target_;
};

}  // namespace dpc::testing
