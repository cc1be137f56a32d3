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

InputPredictor::InputPredictor(double window_samples, double nominal_sample_period_s)
    : window_samples_(window_samples), nominal_sample_period_s_(nominal_sample_period_s) {
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
}

bool InputPredictor::Observe(const StokesVector& s) {
  const double norm = s.norm();
  if (!std::isfinite(norm) || !(norm > 0.0)) return false;
  const StokesVector unit = s / norm;
  if (samples_ > 0) AddInterval(unit, 1.0);
  latest_ = unit;
  latest_t_s_ += nominal_sample_period_s_;
  ++samples_;
  return true;
}

bool InputPredictor::ObserveAt(const StokesVector& s, double t_s) {
  const double norm = s.norm();
  if (!std::isfinite(norm) || !(norm > 0.0) || !std::isfinite(t_s)) return false;
  if (samples_ > 0 && !(t_s > latest_t_s_)) return false;
  const StokesVector unit = s / norm;
  if (samples_ > 0) AddInterval(unit, (t_s - latest_t_s_) / nominal_sample_period_s_);
  latest_ = unit;
  latest_t_s_ = t_s;
  ++samples_;
  return true;
}

void InputPredictor::AddInterval(const StokesVector& s, double tau) {
  const double f = tau == 1.0 ? uniform_forget_ : std::exp(-tau / window_samples_);
  const double g = 1.0 - f;
  const double half = 0.5 * tau;
  const double ax = half * (s[0] + latest_[0]), ay = half * (s[1] + latest_[1]),
               az = half * (s[2] + latest_[2]);
  const double yx = s[0] - latest_[0], yy = s[1] - latest_[1], yz = s[2] - latest_[2];
  const double a2 = ax * ax + ay * ay + az * az;
  a_xx_ = f * a_xx_ + g * (a2 - ax * ax);
  a_yy_ = f * a_yy_ + g * (a2 - ay * ay);
  a_zz_ = f * a_zz_ + g * (a2 - az * az);
  a_xy_ = f * a_xy_ - g * (ax * ay);
  a_xz_ = f * a_xz_ - g * (ax * az);
  a_yz_ = f * a_yz_ - g * (ay * az);
  b_[0] = f * b_[0] + g * (ay * yz - az * yy);
  b_[1] = f * b_[1] + g * (az * yx - ax * yz);
  b_[2] = f * b_[2] + g * (ax * yy - ay * yx);
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

StokesVector InputPredictor::PredictSamples(double horizon_samples) const {
  if (samples_ < 2 || !(horizon_samples > 0.0)) return latest_;
  const Vector3 rotation = RotationPerSample();
  const double rate = rotation.norm();
  const double angle = rate * horizon_samples;
  if (!(angle > 0.0) || !std::isfinite(angle)) return latest_;
  double s, c;
  SinCos(angle, &s, &c);
  return RotateVector(rotation / rate, c, s, latest_);
}

}  // namespace dpc
