#include "dpc/control/fused_gradient_projection.h"

namespace dpc {

std::optional<FusedUpdatePlan> PlanFusedUpdate(const WaveplateChain& chain, const Target& target,
                                               const ControllerConfig& config) {
  const bool law_fits = config.method == ControlMethod::kGradientProjection ||
                        config.method == ControlMethod::kThresholdedGradientProjection ||
                        config.method == ControlMethod::kPseudoInverse;
  // The options beyond the paper run on the general path (the fused update stays the paper's).
  const bool paper_options = !config.prediction && !config.singularity_damping &&
                             !config.curvature_correction &&
                             config.nullspace_criterion == NullspaceCriterion::kMinimumNorm;
  const int stages = chain.stage_count();
  if (!law_fits || !paper_options || !target.is_point() || (stages != 3 && stages != 4) ||
      chain.control_count() != stages || chain.has_ranges()) {
    return std::nullopt;
  }
  FusedUpdatePlan plan;
  plan.stages = stages;
  for (int i = 0; i < stages; ++i) {
    const WaveplateStage& stage = chain.stages()[i];
    if (stage.kind() != WaveplateStage::Kind::kFixedAxis ||
        ClassifyAxis(stage.axis()) == ElementalAxis::kGeneral) {
      return std::nullopt;
    }
    const ControlMap& map = stage.controls()[0].map;
    if (map.kind() != ControlMap::Kind::kLinear) return std::nullopt;
    plan.axis[i] = ClassifyAxis(stage.axis());
    plan.rad_per_unit[i] = map.linear_rad_per_unit();
    plan.offset_rad[i] = map.AngleRad(0.0);
  }
  plan.step = config.step;
  plan.nullspace_step =
      config.method == ControlMethod::kPseudoInverse ? 0.0 : config.nullspace_step;
  if (config.method == ControlMethod::kThresholdedGradientProjection) {
    plan.threshold = config.threshold;
  }
  plan.singular_value_tolerance = config.singular_value_tolerance;
  plan.loop = config.loop;
  plan.target_point = target.point();
  return plan;
}

namespace {

template <typename Axes>
class FusedControlStepFor final : public FusedControlStep {
 public:
  static constexpr int N = Axes::kStages;

  FusedControlStepFor(const FusedUpdatePlan& plan, const Axes& axes) : update_(plan, axes) {}

  void SetCommand(const ControlVector& phi) override {
    for (int e = 0; e < N; ++e) pose_.phi[e] = phi[e];
    update_.ExactPose(&pose_);
  }

  void SetPose(const ChainPose& pose) override {
    for (int e = 0; e < N; ++e) {
      pose_.phi[e] = pose.phi[e];
      pose_.cos[e] = pose.cos[e];
      pose_.sin[e] = pose.sin[e];
    }
    pose_.incremental_steps = pose.incremental_steps;
  }

  FusedUpdateResult Update(const StokesVector& s_in, const StokesVector& s_out_measured,
                           ControlVector* delta_phi) override {
    delta_phi->resize(N);
    return update_.Update(s_in, s_out_measured, &pose_, delta_phi->data());
  }

 private:
  FusedGradientProjection<Axes> update_;
  ElementalPose<N> pose_;
};

}  // namespace

std::unique_ptr<FusedControlStep> FusedControlStep::Make(const FusedUpdatePlan& plan) {
  return DispatchStageAxes(plan.axis, plan.stages,
                           [&](const auto& axes) -> std::unique_ptr<FusedControlStep> {
                             using Axes = std::decay_t<decltype(axes)>;
                             return std::make_unique<FusedControlStepFor<Axes>>(plan, axes);
                           });
}

}  // namespace dpc
