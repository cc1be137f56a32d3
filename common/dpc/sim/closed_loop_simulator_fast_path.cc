// The simulator's fast path: the general loop (closed_loop_simulator.cc) fused into one
// fixed-size loop body for the paper's class of configurations (see PlanFastPath): 3 or 4
// fixed-axis stages on S1/S2/S3 with θ = k·φ + θ0 and no ranges, a point target, gradient
// projection (gp, gpt) or the pseudo-inverse, either loop mode.
//
// Per sample it computes exactly what the general loop computes, with the same formulas:
//   pose        θ = kφ + θ0, sines and cosines by angle addition from the previous command
//               (exact every WaveplateChain::kMaxIncrementalSteps updates) — ComputePoseFrom
//   kinematics  forward pass: M = B_m, Ω′_e = k_e · (row of B_(e−1) on the stage's axis) —
//               WaveplateChain::Evaluate
//   task        T = [e2ᵀΩ′; −e1ᵀΩ′] at the tangent basis of the measured S_in,
//               e = Eᵀ(MᵀS* − MᵀS_out) — UpdateControlProblem
//   law         Δφ = Tᵀ(μ K e + μ_N K T φ) − μ_N φ with K = (TTᵀ)⁻¹ when det(TTᵀ) > 1e-6·tr²,
//               else the general TaskPseudoInverse (one-sided Jacobi) —
//               TaskPseudoInverse::GradientProjectionStep, GradientProjectionLaw,
//               PseudoInverseLaw
//   integrator φ += Δφ unless Δφ is not finite — ControlIntegrator
// It shares the input generator, the polarimeters, the statistics and the near-singular
// fallback with the general loop. Only round-off separates the two loops' trajectories.

#include <cmath>

#include "dpc/control/task_pseudo_inverse.h"
#include "dpc/sim/closed_loop_simulator.h"
#include "dpc/sim/delay_line.h"
#include "dpc/sim/simulation_run.h"

namespace dpc {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr double kWellConditioned = 1e-6;  // as TaskPseudoInverse

template <int N>
struct FastPose {
  double cos[N], sin[N], angle_rad[N], phi[N];
  int incremental_steps = 0;
};

// (u, v) ← (c·u − s·v, s·u + c·v).
inline void Turn(double& u, double& v, double c, double s) {
  const double t = u;
  u = c * t - s * v;
  v = s * t + c * v;
}

}  // namespace

template <int N>
SimulationResult ClosedLoopSimulator::RunFastPath(SimulationObserver* observer,
                                                  int64_t decimation) {
  const FastPathPlan& plan = *fast_path_;
  const double dt_s = 1.0 / scenario_.simulation.sample_rate_hz;
  const Target& target = *target_;
  const bool model_loop = scenario_.controller.loop == LoopMode::kModel;

  SimulationRun run(scenario_, target, N, total_samples_, observer, decimation);
  TaskPseudoInverse fallback(plan.singular_value_tolerance);
  TaskJacobian fallback_task(2, N);
  TaskVector fallback_error(2);
  ControlVector fallback_phi(N), fallback_delta(N);

  // The pose of control vector φ, exactly.
  const auto exact_pose = [&plan](const double* phi, FastPose<N>* pose) {
    for (int e = 0; e < N; ++e) {
      pose->phi[e] = phi[e];
      pose->angle_rad[e] = plan.rad_per_unit[e] * phi[e] + plan.offset_rad[e];
      SinCos(pose->angle_rad[e], &pose->sin[e], &pose->cos[e]);
    }
    pose->incremental_steps = 0;
  };

  // The delay line of poses, as in the general loop.
  double phi[N];
  for (int e = 0; e < N; ++e) phi[e] = initial_phi_[e];
  FastPose<N> initial_pose;
  exact_pose(phi, &initial_pose);
  DelayLine<FastPose<N>> line(delay_samples_, initial_pose);

  const StokesVector target_point = target.point();
  const int64_t block = std::min<int64_t>(delay_samples_, kMaxBlock);
  std::vector<StokesVector> in_measured(static_cast<size_t>(block));
  std::vector<StokesVector> out_measured(static_cast<size_t>(block));
  ControlVector observed_phi(N);

  int64_t block_start_slot = 0, k = 0;
  while (k < total_samples_) {
    const int64_t count = std::min(block, total_samples_ - k);
    // Phase 1: input, plant, measurement, statistics of the true output.
    int64_t slot = block_start_slot;
    for (int64_t i = 0; i < count; ++i, slot = line.Next(slot)) {
      const int64_t sample = k + i;
      const double t_s = static_cast<double>(sample) * dt_s;
      const StokesVector& s_in = run.input.Next();
      const FastPose<N>& applied = line.at(slot);
      double x = s_in[0], y = s_in[1], z = s_in[2];
      for (int e = 0; e < N; ++e) RotateElemental(plan.axis[e], applied.cos[e], applied.sin[e], x, y, z);
      const StokesVector s_out(x, y, z);
      if (sample >= activation_sample_) {
        run.statistics.AddSample(t_s, s_out, applied.phi);
        in_measured[static_cast<size_t>(i)] = run.input_polarimeter.Measure(s_in);
        out_measured[static_cast<size_t>(i)] = run.output_polarimeter.Measure(s_out);
      }
      if (run.TakesSample()) {
        for (int e = 0; e < N; ++e) observed_phi[e] = applied.phi[e];
        run.observer().OnSample(SampleView{sample, t_s, s_in, s_out, observed_phi,
                                           target.DistanceRad(s_out) * kRadToDeg});
      }
    }
    // Phase 2: the controller, sample by sample.
    slot = block_start_slot;
    for (int64_t i = 0; i < count; ++i, slot = line.Next(slot)) {
      const int64_t sample = k + i;
      bool issued = false;
      if (sample >= activation_sample_) {
        const FastPose<N>& current = line.latest();
        const StokesVector& s_in = in_measured[static_cast<size_t>(i)];
        // Kinematics in the input frame: B_e = M_e ⋯ M_1 (b_rc), Ω′_e (w[e]).
        double b00 = 1, b01 = 0, b02 = 0, b10 = 0, b11 = 1, b12 = 0, b20 = 0, b21 = 0, b22 = 1;
        double wx[N], wy[N], wz[N];  // Ω′, one array per component (vectorizes over stages)
        for (int e = 0; e < N; ++e) {
          const double c = current.cos[e], s = current.sin[e], f = plan.rad_per_unit[e];
          switch (plan.axis[e]) {
            case ElementalAxis::kS1:
              wx[e] = f * b00, wy[e] = f * b01, wz[e] = f * b02;
              Turn(b10, b20, c, s), Turn(b11, b21, c, s), Turn(b12, b22, c, s);
              break;
            case ElementalAxis::kS2:
              wx[e] = f * b10, wy[e] = f * b11, wz[e] = f * b12;
              Turn(b20, b00, c, s), Turn(b21, b01, c, s), Turn(b22, b02, c, s);
              break;
            default:  // kS3 (the plan holds elemental axes only)
              wx[e] = f * b20, wy[e] = f * b21, wz[e] = f * b22;
              Turn(b00, b10, c, s), Turn(b01, b11, c, s), Turn(b02, b12, c, s);
              break;
          }
        }
        // Task: tangent basis at S_in, T rows, error e = Eᵀ(MᵀS* − MᵀS_out).
        Vector3 e1, e2;
        TangentBasis(s_in, &e1, &e2);
        double t0[N], t1[N];
        for (int e = 0; e < N; ++e) {
          t0[e] = e2[0] * wx[e] + e2[1] * wy[e] + e2[2] * wz[e];
          t1[e] = -(e1[0] * wx[e] + e1[1] * wy[e] + e1[2] * wz[e]);
        }
        const double px = target_point[0], py = target_point[1], pz = target_point[2];
        double ex = b00 * px + b10 * py + b20 * pz;  // MᵀS*
        double ey = b01 * px + b11 * py + b21 * pz;
        double ez = b02 * px + b12 * py + b22 * pz;
        if (model_loop) {  // MᵀS_out = S_in for the model output
          ex -= s_in[0], ey -= s_in[1], ez -= s_in[2];
        } else {
          const StokesVector& m = out_measured[static_cast<size_t>(i)];
          ex -= b00 * m[0] + b10 * m[1] + b20 * m[2];
          ey -= b01 * m[0] + b11 * m[1] + b21 * m[2];
          ez -= b02 * m[0] + b12 * m[1] + b22 * m[2];
        }
        const double err0 = e1[0] * ex + e1[1] * ey + e1[2] * ez;
        const double err1 = e2[0] * ex + e2[1] * ey + e2[2] * ez;
        // Law: gradient projection (μ_N = 0 for pinv; gpt gates the null-space term).
        bool nullspace_active = plan.nullspace_step > 0.0;
        if (nullspace_active && plan.threshold) {
          double largest = 0.0;
          for (int e = 0; e < N; ++e) largest = std::max(largest, std::abs(current.phi[e]));
          nullspace_active = largest > *plan.threshold;
        }
        const double mu = plan.step, mu_null = nullspace_active ? plan.nullspace_step : 0.0;
        double g11 = 0, g22 = 0, g12 = 0;
        for (int e = 0; e < N; ++e) {
          g11 += t0[e] * t0[e];
          g22 += t1[e] * t1[e];
          g12 += t0[e] * t1[e];
        }
        const double trace = g11 + g22, det = g11 * g22 - g12 * g12;
        double delta[N];
        int rank = 2;
        SingularValues singular_values;
        if (det > kWellConditioned * trace * trace) {
          double z0 = 0, z1 = 0;
          for (int e = 0; e < N; ++e) {
            z0 += t0[e] * current.phi[e];
            z1 += t1[e] * current.phi[e];
          }
          const double inverse_det = 1.0 / det;
          const double k00 = g22 * inverse_det, k11 = g11 * inverse_det, k01 = -g12 * inverse_det;
          const double y0 = mu * (k00 * err0 + k01 * err1) + mu_null * (k00 * z0 + k01 * z1);
          const double y1 = mu * (k01 * err0 + k11 * err1) + mu_null * (k01 * z0 + k11 * z1);
          for (int e = 0; e < N; ++e) delta[e] = t0[e] * y0 + t1[e] * y1 - mu_null * current.phi[e];
          singular_values = SingularValues::FromGram(g11, g22, g12, det);
        } else {  // near a singularity: the general one-sided Jacobi pseudo-inverse
          for (int e = 0; e < N; ++e) {
            fallback_task(0, e) = t0[e];
            fallback_task(1, e) = t1[e];
            fallback_phi[e] = current.phi[e];
          }
          fallback_error << err0, err1;
          fallback.Compute(fallback_task);
          fallback.GradientProjectionStep(fallback_error, fallback_phi, mu, mu_null,
                                          &fallback_delta);
          for (int e = 0; e < N; ++e) delta[e] = fallback_delta[e];
          rank = fallback.rank();
          singular_values = fallback.singular_values();
        }
        bool finite = true;
        for (int e = 0; e < N; ++e) finite = finite && std::isfinite(delta[e]);
        run.statistics.AddUpdate(nullspace_active, !finite, finite && rank < 2, false,
                                 singular_values);
        if (finite) {
          for (int e = 0; e < N; ++e) phi[e] = current.phi[e] + delta[e];
          // The new command's pose, by angle addition (ComputePoseFrom).
          FastPose<N>& next = line.issue(slot);
          const FastPose<N>& previous = current;  // may be `next` when D = 1
          if (previous.incremental_steps >= WaveplateChain::kMaxIncrementalSteps) {
            exact_pose(phi, &next);
          } else {
            const int steps = previous.incremental_steps + 1;
            for (int e = 0; e < N; ++e) {
              const double angle = plan.rad_per_unit[e] * phi[e] + plan.offset_rad[e];
              const double c = previous.cos[e], s = previous.sin[e];
              double sd, cd;
              SinCos(angle - previous.angle_rad[e], &sd, &cd);
              next.phi[e] = phi[e];
              next.angle_rad[e] = angle;
              next.cos[e] = c * cd - s * sd;
              next.sin[e] = s * cd + c * sd;
            }
            next.incremental_steps = steps;
          }
          issued = true;
        }
      }
      line.Close(slot, issued);
    }
    block_start_slot = slot;
    k += count;
    if (!run.EndBlock(k)) break;
  }
  ControlVector final_phi(N);
  for (int e = 0; e < N; ++e) final_phi[e] = line.latest().phi[e];
  return run.Finish(k, 0, final_phi);
}

template SimulationResult ClosedLoopSimulator::RunFastPath<3>(SimulationObserver*, int64_t);
template SimulationResult ClosedLoopSimulator::RunFastPath<4>(SimulationObserver*, int64_t);

}  // namespace dpc
