#include "dpc/optics/control_map.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace dpc {
namespace {

void RequireFinite(double v, const std::string& what) {
  if (!std::isfinite(v)) throw std::invalid_argument(fmt::format("{} is not finite ({})", what, v));
}

}  // namespace

ControlMap ControlMap::Linear(double rad_per_unit, double offset_rad) {
  RequireFinite(rad_per_unit, "linear map rad_per_unit");
  RequireFinite(offset_rad, "linear map offset_rad");
  if (rad_per_unit == 0.0) {
    throw std::invalid_argument("linear map rad_per_unit is 0: the control would do nothing");
  }
  ControlMap map;
  map.kind_ = Kind::kLinear;
  map.linear_rad_per_unit_ = rad_per_unit;
  map.linear_offset_rad_ = offset_rad;
  return map;
}

ControlMap ControlMap::Polynomial(std::vector<double> coefficients_rad) {
  if (coefficients_rad.empty()) {
    throw std::invalid_argument("polynomial map has no coefficients");
  }
  if (coefficients_rad.size() > static_cast<size_t>(kMaxPolynomialCoefficients)) {
    throw std::invalid_argument(
        fmt::format("polynomial map has {} coefficients; at most {} (degree {}) are accepted",
                    coefficients_rad.size(), kMaxPolynomialCoefficients,
                    kMaxPolynomialCoefficients - 1));
  }
  bool has_slope = false;
  for (size_t j = 0; j < coefficients_rad.size(); ++j) {
    RequireFinite(coefficients_rad[j], fmt::format("polynomial map coefficient [{}]", j));
    if (j > 0 && coefficients_rad[j] != 0.0) has_slope = true;
  }
  if (!has_slope) {
    throw std::invalid_argument(
        "polynomial map is constant (every coefficient of degree >= 1 is 0)");
  }
  ControlMap map;
  map.kind_ = Kind::kPolynomial;
  map.coefficients_rad_ = std::move(coefficients_rad);
  return map;
}

ControlMap ControlMap::Table(std::vector<double> control, std::vector<double> angle_rad) {
  if (control.size() != angle_rad.size()) {
    throw std::invalid_argument(
        fmt::format("lookup table has {} control values but {} angles; they must pair up",
                    control.size(), angle_rad.size()));
  }
  if (control.size() < 2) {
    throw std::invalid_argument(
        fmt::format("lookup table has {} point(s); at least 2 are needed", control.size()));
  }
  if (control.size() > static_cast<size_t>(kMaxTablePoints)) {
    throw std::invalid_argument(fmt::format(
        "lookup table has {} points; at most {} are accepted", control.size(), kMaxTablePoints));
  }
  for (size_t j = 0; j < control.size(); ++j) {
    RequireFinite(control[j], fmt::format("lookup table control[{}]", j));
    RequireFinite(angle_rad[j], fmt::format("lookup table angle_rad[{}]", j));
  }
  double min_spacing = INFINITY;
  for (size_t j = 1; j < control.size(); ++j) {
    if (!(control[j] > control[j - 1])) {
      throw std::invalid_argument(fmt::format(
          "lookup table control is not strictly increasing: control[{}] = {} follows "
          "control[{}] = {}",
          j, control[j], j - 1, control[j - 1]));
    }
    min_spacing = std::min(min_spacing, control[j] - control[j - 1]);
  }
  const bool increasing = angle_rad[1] > angle_rad[0];
  for (size_t j = 1; j < angle_rad.size(); ++j) {
    const bool ok = increasing ? angle_rad[j] > angle_rad[j - 1] : angle_rad[j] < angle_rad[j - 1];
    if (!ok) {
      throw std::invalid_argument(fmt::format(
          "lookup table angle_rad is not strictly monotonic: angle_rad[{}] = {} after "
          "angle_rad[{}] = {} (the table {} before)",
          j, angle_rad[j], j - 1, angle_rad[j - 1], increasing ? "increases" : "decreases"));
    }
  }
  ControlMap map;
  map.kind_ = Kind::kTable;
  map.table_control_ = std::move(control);
  map.table_angle_rad_ = std::move(angle_rad);
  map.table_difference_step_ = 1e-6 * min_spacing;
  return map;
}

double ControlMap::TableAngle(double control) const {
  const auto& x = table_control_;
  const auto& y = table_angle_rad_;
  // Segment j spans [x[j], x[j+1]]; beyond the ends the first/last segment is extended.
  size_t j;
  if (control <= x.front()) {
    j = 0;
  } else if (control >= x.back()) {
    j = x.size() - 2;
  } else {
    j = static_cast<size_t>(std::upper_bound(x.begin(), x.end(), control) - x.begin()) - 1;
  }
  const double t = (control - x[j]) / (x[j + 1] - x[j]);
  return y[j] + t * (y[j + 1] - y[j]);
}

double ControlMap::AngleRad(double control) const {
  switch (kind_) {
    case Kind::kLinear:
      return linear_rad_per_unit_ * control + linear_offset_rad_;
    case Kind::kPolynomial: {
      double value = 0.0;
      for (auto it = coefficients_rad_.rbegin(); it != coefficients_rad_.rend(); ++it) {
        value = value * control + *it;
      }
      return value;
    }
    case Kind::kTable:
      return TableAngle(control);
  }
  return NAN;
}

double ControlMap::DerivativeRadPerUnit(double control) const {
  switch (kind_) {
    case Kind::kLinear:
      return linear_rad_per_unit_;
    case Kind::kPolynomial: {
      double value = 0.0;
      for (size_t j = coefficients_rad_.size() - 1; j >= 1; --j) {
        value = value * control + static_cast<double>(j) * coefficients_rad_[j];
      }
      return value;
    }
    case Kind::kTable: {
      const double h = table_difference_step_;
      return (TableAngle(control + h) - TableAngle(control - h)) / (2.0 * h);
    }
  }
  return NAN;
}

std::optional<double> ControlMap::ControlForAngle(double angle_rad, double lo, double hi) const {
  if (!(lo <= hi) || !std::isfinite(angle_rad)) return std::nullopt;
  if (kind_ == Kind::kLinear) {
    const double control = (angle_rad - linear_offset_rad_) / linear_rad_per_unit_;
    if (control < lo || control > hi) return std::nullopt;
    return control;
  }
  // Bisection; valid when θ is monotonic over [lo, hi], which is checked on a grid first.
  constexpr int kGrid = 64;
  const double a0 = AngleRad(lo), a1 = AngleRad(hi);
  const bool increasing = a1 > a0;
  double previous = a0;
  for (int i = 1; i <= kGrid; ++i) {
    const double value = AngleRad(lo + (hi - lo) * i / kGrid);
    if (increasing ? value < previous : value > previous) return std::nullopt;
    previous = value;
  }
  if (increasing ? (angle_rad < a0 || angle_rad > a1) : (angle_rad > a0 || angle_rad < a1)) {
    return std::nullopt;
  }
  double left = lo, right = hi;
  for (int i = 0; i < 200 && right - left > 1e-15 * std::max(1.0, std::abs(left)); ++i) {
    const double mid = 0.5 * (left + right);
    const bool below = increasing ? AngleRad(mid) < angle_rad : AngleRad(mid) > angle_rad;
    (below ? left : right) = mid;
  }
  return 0.5 * (left + right);
}

std::optional<std::pair<double, double>> ControlMap::TableSpan() const {
  if (kind_ != Kind::kTable) return std::nullopt;
  return std::make_pair(table_control_.front(), table_control_.back());
}

std::string ControlMap::Describe() const {
  switch (kind_) {
    case Kind::kLinear:
      return linear_offset_rad_ == 0.0
                 ? fmt::format("linear {:.6g} rad/unit", linear_rad_per_unit_)
                 : fmt::format("linear {:.6g} rad/unit + {:.6g} rad", linear_rad_per_unit_,
                               linear_offset_rad_);
    case Kind::kPolynomial:
      return fmt::format("polynomial degree {}", coefficients_rad_.size() - 1);
    case Kind::kTable:
      return fmt::format("table {} points", table_control_.size());
  }
  return "?";
}

}  // namespace dpc
