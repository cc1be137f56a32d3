#include "dpc/optics/waveplate_chain.h"

#include "dpc/optics/count_dispatch.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace dpc {
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
  std::vector<bool> seen(controls_.size(), false);
  for (Element& el : elements_) {
    if (el.control >= 0 && !seen[el.control]) {
      el.first_of_control = true;
      seen[el.control] = true;
    }
  }
  for (const ControlChannel& channel : controls_) {
    all_linear_ = all_linear_ && channel.map.kind() == ControlMap::Kind::kLinear;
    linear_rad_per_unit_.push_back(channel.map.linear_rad_per_unit());
    linear_offset_rad_.push_back(channel.map.AngleRad(0.0));
    has_ranges_ = has_ranges_ || channel.range.has_value();
    range_min_.push_back(channel.range ? channel.range->min : -INFINITY);
    range_max_.push_back(channel.range ? channel.range->max : INFINITY);
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

void WaveplateChain::ComputeAngles(const ControlVector& phi, ChainPose* pose,
                                   double* theta) const {
  const int n = control_count();
  pose->phi.resize(n);
  pose->dtheta_dphi.resize(n);
  const bool same = &pose->phi == &phi;
  DispatchCount(n, [&](auto fixed) {
    const int count = FixedOr(fixed, n);
    const double* in = phi.data();
    double* out_phi = pose->phi.data();
    double* out_derivative = pose->dtheta_dphi.data();
    if (all_linear_) {
      const double* k = linear_rad_per_unit_.data();
      const double* offset = linear_offset_rad_.data();
      for (int c = 0; c < count; ++c) {
        const double value = in[c];
        theta[c] = k[c] * value + offset[c];
        out_derivative[c] = k[c];
        if (!same) out_phi[c] = value;
      }
      return;
    }
    for (int c = 0; c < count; ++c) {
      const double value = in[c];
      theta[c] = controls_[c].map.AngleRad(value);
      out_derivative[c] = controls_[c].map.DerivativeRadPerUnit(value);
      if (!same) out_phi[c] = value;
    }
  });
}

void WaveplateChain::ComputePose(const ControlVector& phi, ChainPose* pose) const {
  double theta[kMaxControls];
  ComputeAngles(phi, pose, theta);
  for (size_t e = 0; e < elements_.size(); ++e) {
    const Element& el = elements_[e];
    const double angle = el.control >= 0 ? el.sign * theta[el.control] : el.fixed_angle_rad;
    pose->angle_rad[e] = angle;
    SinCos(angle, &pose->sin[e], &pose->cos[e]);
  }
  pose->incremental_steps = 0;
}

void WaveplateChain::ComputePoseFrom(const ChainPose& previous, const ControlVector& phi,
                                     ChainPose* pose) const {
  if (previous.incremental_steps >= kMaxIncrementalSteps) {
    ComputePose(phi, pose);
    return;
  }
  const int steps = previous.incremental_steps + 1;
  double theta[kMaxControls];
  ComputeAngles(phi, pose, theta);
  DispatchCount(static_cast<int>(elements_.size()), [&](auto fixed) {
    const int count = FixedOr(fixed, static_cast<int>(elements_.size()));
    for (int e = 0; e < count; ++e) {  // element by element: `previous` may be `pose`
      const Element& el = elements_[e];
      const double angle = el.control >= 0 ? el.sign * theta[el.control] : el.fixed_angle_rad;
      const double c = previous.cos[e], s = previous.sin[e];
      double sd, cd;
      SinCos(angle - previous.angle_rad[e], &sd, &cd);  // the series for small steps
      pose->angle_rad[e] = angle;
      pose->cos[e] = c * cd - s * sd;
      pose->sin[e] = s * cd + c * sd;
    }
  });
  pose->incremental_steps = steps;
}

StokesVector WaveplateChain::Output(const ChainPose& pose, const StokesVector& s_in) const {
  return DispatchCount(static_cast<int>(elements_.size()), [&](auto fixed) {
    const int count = FixedOr(fixed, static_cast<int>(elements_.size()));
    // The state stays in registers: a switch per elemental axis instead of indexed components.
    double x = s_in[0], y = s_in[1], z = s_in[2];
    for (int e = 0; e < count; ++e) {
      const Element& el = elements_[e];
      const double c = pose.cos[e], s = pose.sin[e];
      if (el.elemental != ElementalAxis::kGeneral) {
        RotateElemental(el.elemental, c, s, x, y, z);
      } else {
        const Vector3 r = RotateVector(el.axis, c, s, Vector3(x, y, z));
        x = r[0];
        y = r[1];
        z = r[2];
      }
    }
    return StokesVector(x, y, z);
  });
}

namespace {

// (u, v) ← (c·u − s·v, s·u + c·v): one column of two rows mixed by a plane rotation.
inline void Turn(double& u, double& v, double c, double s) {
  const double t = u;
  u = c * t - s * v;
  v = s * t + c * v;
}

}  // namespace

void WaveplateChain::Evaluate(const ChainPose& pose, const StokesVector& s_in,
                              ChainKinematics* out, bool with_jacobian) const {
  const int n = control_count();
  const int elements = static_cast<int>(elements_.size());
  out->input_generators.resize(3, n);
  // Fixed-axis chains have one element per control: dispatch on both at once.
  DispatchCount(elements == n ? n : 0, [&](auto fixed) {
    const int count = FixedOr(fixed, n);
    const int element_count = FixedOr(fixed, elements);
    // Column-major, 3 × n. Every control drives at least one element; the first assigns its
    // column (no zeroing pass), later ones (adjustable-axis stages) add to it.
    double* g = out->input_generators.data();
    const double* derivative = pose.dtheta_dphi.data();
    // B_e = M_e ⋯ M_1 in named locals (b_rc: row r, column c) so that it stays in registers.
    double b00 = 1, b01 = 0, b02 = 0, b10 = 0, b11 = 1, b12 = 0, b20 = 0, b21 = 0, b22 = 1;
    const auto add_generator = [g, derivative](const Element& el, double x, double y, double z) {
      if (el.control < 0) return;
      const double f = el.sign * derivative[el.control];
      double* gc = g + 3 * el.control;
      if (el.first_of_control) {
        gc[0] = f * x;
        gc[1] = f * y;
        gc[2] = f * z;
      } else {
        gc[0] += f * x;
        gc[1] += f * y;
        gc[2] += f * z;
      }
    };
    for (int e = 0; e < element_count; ++e) {
      const Element& el = elements_[e];
      const double c = pose.cos[e], s = pose.sin[e];
      switch (el.elemental) {
        case ElementalAxis::kS1:  // Bᵀe1 = row 0; R1·B mixes rows 1, 2
          add_generator(el, b00, b01, b02);
          Turn(b10, b20, c, s);
          Turn(b11, b21, c, s);
          Turn(b12, b22, c, s);
          break;
        case ElementalAxis::kS2:  // Bᵀe2 = row 1; R2·B mixes rows 2, 0
          add_generator(el, b10, b11, b12);
          Turn(b20, b00, c, s);
          Turn(b21, b01, c, s);
          Turn(b22, b02, c, s);
          break;
        case ElementalAxis::kS3:  // Bᵀe3 = row 2; R3·B mixes rows 0, 1
          add_generator(el, b20, b21, b22);
          Turn(b00, b10, c, s);
          Turn(b01, b11, c, s);
          Turn(b02, b12, c, s);
          break;
        case ElementalAxis::kGeneral: {
          Matrix3 b;
          b << b00, b01, b02, b10, b11, b12, b20, b21, b22;
          const Vector3 w = b.transpose() * el.axis;
          add_generator(el, w[0], w[1], w[2]);
          b = RotationAboutAxis(el.axis, c, s) * b;
          b00 = b(0, 0), b01 = b(0, 1), b02 = b(0, 2);
          b10 = b(1, 0), b11 = b(1, 1), b12 = b(1, 2);
          b20 = b(2, 0), b21 = b(2, 1), b22 = b(2, 2);
          break;
        }
      }
    }
    out->mueller << b00, b01, b02, b10, b11, b12, b20, b21, b22;
    const double sx = s_in[0], sy = s_in[1], sz = s_in[2];
    const double x = b00 * sx + b01 * sy + b02 * sz;
    const double y = b10 * sx + b11 * sy + b12 * sz;
    const double z = b20 * sx + b21 * sy + b22 * sz;
    out->s_out = StokesVector(x, y, z);
    if (!with_jacobian) return;
    out->generators.resize(3, n);
    out->jacobian.resize(3, n);
    double* w = out->generators.data();
    double* j = out->jacobian.data();
    for (int col = 0; col < count; ++col) {  // Ω_c = M Ω′_c, J_c = Ω_c × S_out
      const double* v = g + 3 * col;
      double* wc = w + 3 * col;
      wc[0] = b00 * v[0] + b01 * v[1] + b02 * v[2];
      wc[1] = b10 * v[0] + b11 * v[1] + b12 * v[2];
      wc[2] = b20 * v[0] + b21 * v[1] + b22 * v[2];
      j[3 * col + 0] = wc[1] * z - wc[2] * y;
      j[3 * col + 1] = wc[2] * x - wc[0] * z;
      j[3 * col + 2] = wc[0] * y - wc[1] * x;
    }
  });
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
  if (!has_ranges_) return 0;
  return DispatchCount(control_count(), [&](auto fixed) {
    const int count = FixedOr(fixed, control_count());
    int clamped = 0;
    double* v = phi->data();
    for (int c = 0; c < count; ++c) {
      if (v[c] < range_min_[c]) {
        v[c] = range_min_[c];
        ++clamped;
      } else if (v[c] > range_max_[c]) {
        v[c] = range_max_[c];
        ++clamped;
      }
    }
    return clamped;
  });
}

std::string WaveplateChain::Describe() const {
  std::string text;
  for (const auto& stage : stages_) {
    if (!text.empty()) text += ' ';
    text += stage.Describe();
  }
  return text;
}

std::string WaveplateChain::PaperNotation() const {
  std::string text;
  for (auto stage = stages_.rbegin(); stage != stages_.rend(); ++stage) text += stage->Describe();
  return text;
}

}  // namespace dpc
