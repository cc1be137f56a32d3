#include "dpc/control/input_predictor.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "dpc/optics/rotation.h"

namespace dpc {
namespace {

/// Relative ridge ε/tr A of the fit.
constexpr double kRelativeRidge = 1e-9;

}  // namespace

InputPredictor::InputPredictor(double window_samples, double nominal_sample_period_s,
                               int refresh_samples)
    : window_samples_(window_samples),
      nominal_sample_period_s_(nominal_sample_period_s),
      refresh_samples_(refresh_samples) {
  if (refresh_samples < 1) {
    throw std::invalid_argument(fmt::format(
        "input predictor refresh interval must be >= 1 sample (got {})", refresh_samples));
  }
  if (!std::isfinite(window_samples) || !(window_samples > 0.0)) {
    throw std::invalid_argument(
        fmt::format("input predictor window must be > 0 samples (got {})", window_samples));
  }
  if (!std::isfinite(nominal_sample_period_s) || !(nominal_sample_period_s > 0.0)) {
    throw std::invalid_argument(fmt::format(
        "input predictor sample period must be > 0 s (got {})", nominal_sample_period_s));
  }
  uniform_forget_ = std::exp(-1.0 / window_samples);
  Reset();
}

void InputPredictor::Reset() {
  a_xx_ = a_yy_ = a_zz_ = a_xy_ = a_xz_ = a_yz_ = 0.0;
  b_.setZero();
  latest_ = StokesVector::UnitX();
  latest_t_s_ = 0.0;
  samples_ = 0;
  cached_horizon_samples_ = -1.0;
  since_refresh_ = 0;
}

bool InputPredictor::ObserveAt(const StokesVector& s, double t_s) {
  if (!std::isfinite(t_s) || (samples_ > 0 && !(t_s > latest_t_s_))) return false;
  StokesVector unit;
  if (!NormalizeStokes(s, &unit)) return false;
  if (samples_ > 0) AddInterval(unit, (t_s - latest_t_s_) / nominal_sample_period_s_);
  latest_ = unit;
  latest_t_s_ = t_s;
  ++samples_;
  ++since_refresh_;
  return true;
}

Vector3 InputPredictor::RotationPerSample() const {
  const double ridge = kRelativeRidge * (a_xx_ + a_yy_ + a_zz_);
  const double xx = a_xx_ + ridge, yy = a_yy_ + ridge, zz = a_zz_ + ridge;
  const double xy = a_xy_, xz = a_xz_, yz = a_yz_;
  // Cofactors of the symmetric matrix; w = adj(A)·b / det A.
  const double c_xx = yy * zz - yz * yz, c_yy = xx * zz - xz * xz, c_zz = xx * yy - xy * xy;
  const double c_xy = xz * yz - xy * zz, c_xz = xy * yz - xz * yy, c_yz = xy * xz - xx * yz;
  const double det = xx * c_xx + xy * c_xy + xz * c_xz;
  if (!(det > 0.0) || !std::isfinite(det)) return Vector3::Zero();
  const double inverse_det = 1.0 / det;
  const Vector3 w((c_xx * b_[0] + c_xy * b_[1] + c_xz * b_[2]) * inverse_det,
                  (c_xy * b_[0] + c_yy * b_[1] + c_yz * b_[2]) * inverse_det,
                  (c_xz * b_[0] + c_yz * b_[1] + c_zz * b_[2]) * inverse_det);
  const double norm = w.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return Vector3::Zero();
  // |w| = 2 tan(θ/2) per nominal period.
  return w * (2.0 * std::atan(0.5 * norm) / norm);
}

void InputPredictor::Refresh(double horizon_samples) const {
  cached_horizon_samples_ = horizon_samples;
  since_refresh_ = 0;
  cached_rotation_.setIdentity();
  const Vector3 rotation = RotationPerSample();
  const double rate = rotation.norm();
  const double angle = rate * horizon_samples;
  if (!(angle > 0.0) || !std::isfinite(angle)) return;
  double s, c;
  SinCos(angle, &s, &c);
  cached_rotation_ = RotationAboutAxis(rotation / rate, c, s);
}

}  // namespace dpc
