#include "dpc/optics/waveplate_chain.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace dpc {
namespace {

// v ← Rot(e, θ) v for an elemental axis (c = cos θ, s = sin θ).
inline void RotateElemental(ElementalAxis axis, double c, double s, Vector3* v) {
  const double x = v->x(), y = v->y(), z = v->z();
  switch (axis) {
    case ElementalAxis::kS1: *v = Vector3(x, c * y - s * z, s * y + c * z); return;
    case ElementalAxis::kS2: *v = Vector3(c * x + s * z, y, -s * x + c * z); return;
    case ElementalAxis::kS3: *v = Vector3(c * x - s * y, s * x + c * y, z); return;
    case ElementalAxis::kGeneral: return;
  }
}

// A ← A·Rot(e, θ) for an elemental axis: only two columns change.
inline void RightMultiplyElemental(ElementalAxis axis, double c, double s, Matrix3* a) {
  int i, j;  // Rot(e) mixes columns i, j as: col_i' = c col_i + s col_j, col_j' = c col_j − s col_i
  switch (axis) {
    case ElementalAxis::kS1: i = 1; j = 2; break;
    case ElementalAxis::kS2: i = 2; j = 0; break;
    case ElementalAxis::kS3: i = 0; j = 1; break;
    default: return;
  }
  const Vector3 ci = a->col(i), cj = a->col(j);
  a->col(i) = c * ci + s * cj;
  a->col(j) = c * cj - s * ci;
}

}  // namespace

WaveplateChain::WaveplateChain(std::vector<WaveplateStage> stages) : stages_(std::move(stages)) {
  if (stages_.empty()) {
    throw std::invalid_argument("a waveplate chain needs at least one stage (got 0)");
  }
  if (stages_.size() > static_cast<size_t>(kMaxStages)) {
    throw std::invalid_argument(fmt::format("a waveplate chain has at most {} stages (got {})",
                                            kMaxStages, stages_.size()));
  }
  for (size_t si = 0; si < stages_.size(); ++si) {
    const WaveplateStage& stage = stages_[si];
    const int first = static_cast<int>(controls_.size());
    stage_first_control_.push_back(first);
    for (size_t k = 0; k < stage.controls().size(); ++k) {
      ControlChannel channel = stage.controls()[k];
      if (channel.name.empty()) {
        const std::string base = stage.name().empty() ? fmt::format("phi_{}", si + 1) : stage.name();
        if (stage.kind() == WaveplateStage::Kind::kFixedAxis) {
          channel.name = base;
        } else {
          const bool is_retardance = k == 0 && stage.retardance().control.has_value();
          channel.name = fmt::format("{}.{}", base, is_retardance ? "retardance" : "orientation");
        }
      }
      controls_.push_back(std::move(channel));
    }
    if (stage.kind() == WaveplateStage::Kind::kFixedAxis) {
      elements_.push_back({stage.axis(), ClassifyAxis(stage.axis()), first, 1.0, 0.0});
    } else {
      // R3(ϕ) R1(θ) R3ᵀ(ϕ): the light meets R3(−ϕ), then R1(θ), then R3(ϕ).
      int next = first;
      const int theta_control = stage.retardance().control ? next++ : -1;
      const int phi_control = stage.orientation().control ? next++ : -1;
      const double fixed_theta = stage.retardance().fixed_angle_rad;
      const double fixed_phi = stage.orientation().fixed_angle_rad;
      const Vector3 e1 = Vector3::UnitX(), e3 = Vector3::UnitZ();
      elements_.push_back({e3, ElementalAxis::kS3, phi_control, -1.0, -fixed_phi});
      elements_.push_back({e1, ElementalAxis::kS1, theta_control, 1.0, fixed_theta});
      elements_.push_back({e3, ElementalAxis::kS3, phi_control, 1.0, fixed_phi});
    }
    stage_end_element_.push_back(static_cast<int>(elements_.size()));
  }
  if (controls_.size() > static_cast<size_t>(kMaxControls)) {
    throw std::invalid_argument(fmt::format("a waveplate chain has at most {} controls (got {})",
                                            kMaxControls, controls_.size()));
  }
}

WaveplateChain WaveplateChain::FromAxes(const std::string& axes, double rad_per_unit) {
  std::vector<WaveplateStage> stages;
  for (char ch : axes) {
    if (ch < '1' || ch > '3') {
      throw std::invalid_argument(fmt::format(
          "stage axes \"{}\": '{}' is not an axis; use 1, 2 or 3 for S1, S2, S3", axes, ch));
    }
    const auto axis = static_cast<ElementalAxis>(ch - '0');
    stages.push_back(WaveplateStage::FixedAxis(ElementalAxisVector(axis),
                                               ControlMap::Linear(rad_per_unit)));
  }
  return WaveplateChain(std::move(stages));
}

void WaveplateChain::ComputePose(const ControlVector& phi, ChainPose* pose) const {
  const int n = control_count();
  pose->phi = phi;
  pose->dtheta_dphi.resize(n);
  // θ per control first, so shared controls evaluate their map once.
  double theta[kMaxControls];
  for (int c = 0; c < n; ++c) {
    theta[c] = controls_[c].map.AngleRad(phi[c]);
    pose->dtheta_dphi[c] = controls_[c].map.DerivativeRadPerUnit(phi[c]);
  }
  for (size_t e = 0; e < elements_.size(); ++e) {
    const Element& el = elements_[e];
    const double angle = el.control >= 0 ? el.sign * theta[el.control] : el.fixed_angle_rad;
    pose->angle_rad[e] = angle;
    SinCos(angle, &pose->sin[e], &pose->cos[e]);
  }
}

StokesVector WaveplateChain::Output(const ChainPose& pose, const StokesVector& s_in) const {
  Vector3 s = s_in;
  for (size_t e = 0; e < elements_.size(); ++e) {
    const Element& el = elements_[e];
    if (el.elemental != ElementalAxis::kGeneral) {
      RotateElemental(el.elemental, pose.cos[e], pose.sin[e], &s);
    } else {
      s = RotateVector(el.axis, pose.cos[e], pose.sin[e], s);
    }
  }
  return s;
}

void WaveplateChain::Evaluate(const ChainPose& pose, const StokesVector& s_in,
                              ChainKinematics* out) const {
  const int n = control_count();
  out->generators.setZero(3, n);
  Matrix3 a = Matrix3::Identity();  // A_e = M_last ⋯ M_(e+1)
  for (int e = static_cast<int>(elements_.size()) - 1; e >= 0; --e) {
    const Element& el = elements_[e];
    if (el.elemental != ElementalAxis::kGeneral) {
      if (el.control >= 0) {
        const int column = static_cast<int>(el.elemental) - 1;
        out->generators.col(el.control) +=
            (el.sign * pose.dtheta_dphi[el.control]) * a.col(column);
      }
      RightMultiplyElemental(el.elemental, pose.cos[e], pose.sin[e], &a);
    } else {
      if (el.control >= 0) {
        out->generators.col(el.control) += (el.sign * pose.dtheta_dphi[el.control]) * (a * el.axis);
      }
      a = a * RotationAboutAxis(el.axis, pose.cos[e], pose.sin[e]);
    }
  }
  out->s_out = a * s_in;
  out->jacobian.resize(3, n);
  for (int c = 0; c < n; ++c) {
    out->jacobian.col(c) = out->generators.col(c).cross(out->s_out);
  }
}

Matrix3 WaveplateChain::MuellerMatrix(const ChainPose& pose) const {
  Matrix3 m = Matrix3::Identity();
  for (size_t e = 0; e < elements_.size(); ++e) {
    m = RotationAboutAxis(elements_[e].axis, pose.cos[e], pose.sin[e]) * m;
  }
  return m;
}

std::vector<StokesVector> WaveplateChain::StageStates(const ChainPose& pose,
                                                      const StokesVector& s_in) const {
  std::vector<StokesVector> states{s_in};
  Vector3 s = s_in;
  size_t e = 0;
  for (int end : stage_end_element_) {
    for (; e < static_cast<size_t>(end); ++e) {
      s = RotateVector(elements_[e].axis, pose.cos[e], pose.sin[e], s);
    }
    states.push_back(s);
  }
  return states;
}

StokesVector WaveplateChain::Output(const ControlVector& phi, const StokesVector& s_in) const {
  ChainPose pose;
  ComputePose(phi, &pose);
  return Output(pose, s_in);
}

Matrix3X WaveplateChain::Jacobian(const ControlVector& phi, const StokesVector& s_in) const {
  ChainPose pose;
  ComputePose(phi, &pose);
  ChainKinematics kinematics;
  Evaluate(pose, s_in, &kinematics);
  return kinematics.jacobian;
}

int WaveplateChain::ClampToRanges(ControlVector* phi) const {
  int clamped = 0;
  for (int c = 0; c < control_count(); ++c) {
    const auto& range = controls_[c].range;
    if (range && !range->Contains((*phi)[c])) {
      (*phi)[c] = range->Clamp((*phi)[c]);
      ++clamped;
    }
  }
  return clamped;
}

std::string WaveplateChain::Describe() const {
  std::string text;
  for (const auto& stage : stages_) {
    if (!text.empty()) text += ' ';
    text += stage.Describe();
  }
  return text;
}

}  // namespace dpc
