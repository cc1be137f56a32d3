#include "dpc/control/control_problem.h"

namespace dpc {

void BuildTaskJacobian(const Target& target, const ChainKinematics& k, const Vector3& e1,
                       const Vector3& e2, TaskJacobian* task_jacobian) {
  const int n = static_cast<int>(k.generators.cols());
  if (target.is_point()) {
    task_jacobian->resize(2, n);
    task_jacobian->row(0).noalias() = e2.transpose() * k.generators;
    task_jacobian->row(1).noalias() = -e1.transpose() * k.generators;
  } else {
    task_jacobian->resize(1, n);
    const Vector3 axis = k.s_out.cross(target.normal());
    task_jacobian->row(0).noalias() = axis.transpose() * k.generators;
  }
}

void UpdateControlProblem(ControlProblem* problem) {
  problem->chain->Evaluate(*problem->pose, problem->s_in, &problem->kinematics);
  const ChainKinematics& k = problem->kinematics;
  problem->s_out_for_error =
      problem->loop_mode == LoopMode::kModel ? k.s_out : problem->s_out_measured;
  TangentBasis(k.s_out, &problem->tangent_e1, &problem->tangent_e2);
  const Target& target = *problem->target;
  BuildTaskJacobian(target, k, problem->tangent_e1, problem->tangent_e2,
                    &problem->task_jacobian);
  if (target.is_point()) {
    const Vector3 error = target.point() - problem->s_out_for_error;
    problem->task_error.resize(2);
    problem->task_error << problem->tangent_e1.dot(error), problem->tangent_e2.dot(error);
  } else {
    problem->task_error.resize(1);
    problem->task_error[0] = target.offset() - target.normal().dot(problem->s_out_for_error);
  }
}

}  // namespace dpc
