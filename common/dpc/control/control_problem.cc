#include "dpc/control/control_problem.h"

#include "dpc/optics/count_dispatch.h"

namespace dpc {

void BuildTaskJacobian(const Target& target, const ChainKinematics& k, const StokesVector& s_in,
                       const Vector3& e1, const Vector3& e2, TaskJacobian* task_jacobian) {
  const int n = static_cast<int>(k.input_generators.cols());
  const double* g = k.input_generators.data();  // Ω′, column-major 3 × n
  // Local copies: the stores below could alias them for the compiler.
  double p0, p1, p2, q0 = 0, q1 = 0, q2 = 0;
  int rows;
  if (target.is_point()) {  // T = [e2ᵀΩ′; −e1ᵀΩ′]
    rows = 2;
    p0 = e2[0], p1 = e2[1], p2 = e2[2];
    q0 = -e1[0], q1 = -e1[1], q2 = -e1[2];
  } else {  // nᵀJ = (S_in × Mᵀn)ᵀΩ′
    rows = 1;
    const Vector3 axis = s_in.cross(k.mueller.transpose() * target.normal());
    p0 = axis[0], p1 = axis[1], p2 = axis[2];
  }
  task_jacobian->resize(rows, n);
  double* row0 = task_jacobian->data();
  double* row1 = row0 + n;
  DispatchCount(n, [&](auto fixed) {
    const int count = FixedOr(fixed, n);
    for (int c = 0; c < count; ++c) {
      const double* w = g + 3 * c;
      row0[c] = p0 * w[0] + p1 * w[1] + p2 * w[2];
      if (rows == 2) row1[c] = q0 * w[0] + q1 * w[1] + q2 * w[2];
    }
  });
}

void UpdateControlProblem(ControlProblem* problem) {
  const StokesVector& s_in = problem->s_in;
  // The basis at S_in first: it does not wait for the chain.
  TangentBasis(s_in, &problem->tangent_e1, &problem->tangent_e2);
  problem->chain->Evaluate(*problem->pose, s_in, &problem->kinematics, problem->need_jacobian);
  const ChainKinematics& k = problem->kinematics;
  const bool model = problem->loop_mode == LoopMode::kModel;
  problem->s_out_for_error = model ? k.s_out : problem->s_out_measured;
  const Target& target = *problem->target;
  BuildTaskJacobian(target, k, s_in, problem->tangent_e1, problem->tangent_e2,
                    &problem->task_jacobian);
  if (target.is_point()) {
    // e = Eᵀ Mᵀ(S* − S_out); MᵀS_out is S_in itself for the model output.
    const Matrix3& m = k.mueller;
    const Vector3 target_in = m.transpose() * target.point();
    const Vector3 output_in = model ? Vector3(s_in) : Vector3(m.transpose() * problem->s_out_measured);
    const Vector3 error = target_in - output_in;
    problem->task_error.resize(2);
    problem->task_error << problem->tangent_e1.dot(error), problem->tangent_e2.dot(error);
  } else {
    problem->task_error.resize(1);
    problem->task_error[0] = target.offset() - target.normal().dot(problem->s_out_for_error);
  }
}

}  // namespace dpc
