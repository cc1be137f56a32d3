#pragma once
// The extended Jacobian method (paper section III.C, eqs. 11–14; Chang 1987).
//
// Gradient projection only drifts towards min H = ½‖φ‖²; the extended Jacobian enforces the
// optimality condition "∇H = φ has no component in null(J)" as extra equations and solves
//
//   [      A      ] Δφ = [  μ   e  ]        g(φ) = (I − A⁺A) φ        (φ projected on null A)
//   [ Zᵀ ∂g/∂φ    ]      [ −μ_N Zᵀ g ]
//
// A is the task Jacobian (d × n), e the task error, Z (n × (n−d)) an orthonormal basis of
// null(A) at the current φ, so the system is square (n × n). Keeping ∂g/∂φ (the paper's
// eq. 12 with the second-order term) rather than dropping it (eq. 13) is what makes the
// solution converge to the constrained optimum; ∂g/∂φ is a central difference of g, which is a
// smooth function of φ (the projector A⁺A does not depend on the tangent basis).
//
// The paper notes that J_e is singular for a point target because J (3 × n) has rank ≤ 2. That
// holds for the 3-D formulation; on the reduced task (2 × n, full rank 2 away from
// singularities) the method applies to points as well. Its intended use is the 1-D target
// n·S = c (paper's "special cases"), where A = nᵀJ is 1 × n.
//
// Real-time but not cheap: 2n extra chain evaluations per update.

#include <Eigen/QR>

#include "dpc/control/control_law.h"
#include "dpc/control/task_pseudo_inverse.h"

namespace dpc {

class ExtendedJacobianLaw final : public ControlLaw {
 public:
  /// step μ > 0 and nullspace_step μ_N ≥ 0 (finite); difference_step h > 0. Throws otherwise.
  ExtendedJacobianLaw(double step, double nullspace_step, double singular_tolerance = 1e-10,
                      double difference_step = 1e-6);

  ControlStatus ComputeUpdate(const ControlProblem& problem, ControlVector* delta_phi) override;
  std::string_view name() const override { return "extended"; }
  bool needs_jacobian() const override { return false; }

 private:
  using SquareMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxControls,
                                     kMaxControls>;

  /// g(φ') = (I − A⁺A)φ' with A evaluated at φ' (same input SOP and target).
  void Constraint(const ControlProblem& problem, const ControlVector& phi, ControlVector* g);

  double step_;
  double nullspace_step_;
  double singular_tolerance_;
  double difference_step_;
  // Scratch, sized once.
  TaskPseudoInverse pseudo_inverse_;
  ChainPose pose_;
  ChainKinematics kinematics_;
  TaskJacobian task_jacobian_;
  ControlVector g_, g_plus_, g_minus_, shifted_;
  SquareMatrix dg_dphi_, extended_, null_basis_;
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxControls, 1> rhs_;
  Eigen::HouseholderQR<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxControls, 3>>
      transpose_qr_;
  Eigen::ColPivHouseholderQR<SquareMatrix> solver_;
};

}  // namespace dpc
