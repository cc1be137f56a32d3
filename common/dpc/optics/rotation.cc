#include "dpc/optics/rotation.h"

#include <cmath>
#include <stdexcept>

namespace dpc {

Vector3 ElementalAxisVector(ElementalAxis axis) {
  switch (axis) {
    case ElementalAxis::kS1: return Vector3::UnitX();
    case ElementalAxis::kS2: return Vector3::UnitY();
    case ElementalAxis::kS3: return Vector3::UnitZ();
    case ElementalAxis::kGeneral: break;
  }
  throw std::invalid_argument("ElementalAxisVector: not an elemental axis");
}

ElementalAxis ClassifyAxis(const Vector3& axis) {
  if (axis == Vector3::UnitX()) return ElementalAxis::kS1;
  if (axis == Vector3::UnitY()) return ElementalAxis::kS2;
  if (axis == Vector3::UnitZ()) return ElementalAxis::kS3;
  return ElementalAxis::kGeneral;
}

Matrix3 CrossProductMatrix(const Vector3& r) {
  Matrix3 m;
  m << 0.0, -r.z(), r.y(),  //
      r.z(), 0.0, -r.x(),   //
      -r.y(), r.x(), 0.0;
  return m;
}

Matrix3 RotationAboutAxis(const Vector3& axis, double cos_angle, double sin_angle) {
  const Matrix3 k = CrossProductMatrix(axis);
  return Matrix3::Identity() + sin_angle * k + (1.0 - cos_angle) * (k * k);
}

Matrix3 RotationAboutAxis(const Vector3& axis, double angle_rad) {
  return RotationAboutAxis(axis, std::cos(angle_rad), std::sin(angle_rad));
}

Matrix3 R1(double angle_rad) {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  Matrix3 m;
  m << 1.0, 0.0, 0.0,  //
      0.0, c, -s,      //
      0.0, s, c;
  return m;
}

Matrix3 R2(double angle_rad) {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  Matrix3 m;
  m << c, 0.0, s,    //
      0.0, 1.0, 0.0,  //
      -s, 0.0, c;
  return m;
}

Matrix3 R3(double angle_rad) {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  Matrix3 m;
  m << c, -s, 0.0,  //
      s, c, 0.0,    //
      0.0, 0.0, 1.0;
  return m;
}

}  // namespace dpc
