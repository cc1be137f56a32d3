#pragma once
// Delay compensation: the controller aims at the input SOP it predicts for the moment its
// command acts, not at the one it just measured, and follows the prediction's motion at once.
//
// A command computed from the sample at t_k acts from t_k + D (the loop delay). The
// InputPredictor (input_predictor.h) gives P_k = Ŝ(t_k + h), horizon h = D. The laws see P_k as
// their input SOP (ControlProblem::s_in): the model output, the task Jacobian and the task error
// e_k are all evaluated there, so every law and target works unchanged.
//
// Lead. The laws integrate with step μ < 1 (φ[k+1] = φ[k] + μ·J⁺e…, paper eqs. 6, 10): against
// an aim that moves every sample such an integrator settles (1 − μ)/μ samples behind it. The
// part of the error that is new this sample, the motion of the prediction
//
//   m_k = −A·(P_k − P_(k−1))      (A: e's linear map of S_in: Eᵀ for a point, (Mᵀn)ᵀ for a set)
//
// is therefore added to the task error with the lead L = (1 − μ)/μ:
//
//   e_k ← e_k + L·m_k,   so that the step is μ·e_k + (1 − μ)·m_k
//
// With a constant motion m the linearized error after the update, (1 − μ)(e − m), settles at 0:
// the command equals the latest prediction, and a kick seen at t_k is followed in one update
// (gain μ(1 + L) = 1) instead of over 1/μ. Every term is of the size of one sample's motion, so
// the linearization holds at high rates (a lead by extrapolating the aim point L samples ahead
// would not: its chord leaves the SOP's orbit by ~(Lθ)²). The price: the measurement noise that
// reaches P_k is followed at gain 1 too (the predictor's fit averages over its window).
//
// Model loop only (in the measured loop the error comes from the delayed output polarimeter).
// Real-time: Predict, PredictAt and AddLead do not allocate.

#include "dpc/control/control_problem.h"
#include "dpc/control/input_predictor.h"

namespace dpc {

class DelayCompensator {
 public:
  /// `window_samples`: the predictor's memory (InputPredictor). `lead_samples` L ≥ 0.
  /// `nominal_sample_period_s` > 0 (PredictAt). Throws std::invalid_argument for bad values.
  DelayCompensator(double window_samples, double lead_samples,
                   double nominal_sample_period_s = 1.0);

  /// Not real-time. Forgets the history (e.g. when control restarts).
  void Reset();

  /// Real-time. Observes the sample that follows the previous one by one nominal period and
  /// returns P_k, the SOP predicted `horizon_samples` later: the control problem's s_in. A
  /// sample the predictor rejects (not finite) leaves the history as it was.
  const StokesVector& Predict(const StokesVector& s_in_measured, double horizon_samples);

  /// Real-time. The same for a sample taken at t_s (seconds) and a horizon in seconds (the
  /// measured latency from the sample's time to the command's effect).
  const StokesVector& PredictAt(const StokesVector& s_in_measured, double t_s, double horizon_s);

  /// Real-time. After UpdateControlProblem(problem) with problem->s_in = the latest prediction:
  /// adds L·m_k to problem->task_error (see the file comment).
  void AddLead(ControlProblem* problem) const;

  const InputPredictor& predictor() const { return predictor_; }
  double lead_samples() const { return lead_samples_; }

 private:
  const StokesVector& Keep(const StokesVector& prediction);

  InputPredictor predictor_;
  double lead_samples_;
  bool have_previous_ = false;
  StokesVector previous_ = StokesVector::UnitX();  ///< P_(k−1)
  StokesVector current_ = StokesVector::UnitX();   ///< P_k
};

/// The lead that removes the velocity lag of an integrator with step μ ∈ (0, 1]: (1 − μ)/μ
/// (0 for μ ≥ 1).
double IntegratorLagSamples(double step);

// ---- Real-time paths, inline: they run on every sample.

inline const StokesVector& DelayCompensator::Predict(const StokesVector& s_in_measured,
                                                     double horizon_samples) {
  predictor_.Observe(s_in_measured);
  return Keep(predictor_.PredictSamples(horizon_samples));
}

inline const StokesVector& DelayCompensator::Keep(const StokesVector& prediction) {
  previous_ = have_previous_ ? current_ : prediction;
  have_previous_ = true;
  current_ = prediction;
  return current_;
}

inline void DelayCompensator::AddLead(ControlProblem* problem) const {
  if (lead_samples_ == 0.0) return;
  TaskVector change;
  TaskErrorChangeOfInput(*problem, current_ - previous_, &change);
  // Element by element (the same products and sums as the vector expression): GCC 12 warns that
  // Eigen's 512-bit path, dead for a vector of at most 3, would read past it (-Warray-bounds).
  for (Eigen::Index i = 0; i < change.size(); ++i) problem->task_error[i] += lead_samples_ * change[i];
}

}  // namespace dpc
