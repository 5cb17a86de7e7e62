#include "purkinje/models/rotation.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace purkinje {

Vector3 rotate(const Vector3& v, const UnitVector3& k, double radians) {
  // Rodrigues: v cos + (k x v) sin + k (k.v)(1 - cos).
  const double c = std::cos(radians), s = std::sin(radians);
  return v * c + cross(k, v) * s + k.vector() * (dot(k, v) * (1.0 - c));
}

UnitVector3 rotate(const UnitVector3& v, const UnitVector3& around_axis, double radians) {
  // A rotation preserves the norm; renormalize only to remove rounding.
  return UnitVector3::normalize(rotate(v.vector(), around_axis, radians));
}

Rotation Rotation::from_axis_angle(const UnitVector3& axis, double radians) {
  Rotation r;
  const Vector3 ex = rotate(Vector3{1, 0, 0}, axis, radians);
  const Vector3 ey = rotate(Vector3{0, 1, 0}, axis, radians);
  const Vector3 ez = rotate(Vector3{0, 0, 1}, axis, radians);
  r.m_ = {ex.x, ey.x, ez.x, ex.y, ey.y, ez.y, ex.z, ey.z, ez.z};
  return r;
}

Rotation Rotation::from_columns(const UnitVector3& x, const UnitVector3& y, const UnitVector3& z) {
  const double tol = 1e-9;
  if (std::abs(dot(x, y)) > tol || std::abs(dot(y, z)) > tol || std::abs(dot(x, z)) > tol ||
      (cross(x, y) - z.vector()).norm() > tol) {
    throw std::invalid_argument("Rotation::from_columns: axes are not orthonormal and right-handed");
  }
  Rotation r;
  r.m_ = {x.x(), y.x(), z.x(), x.y(), y.y(), z.y(), x.z(), y.z(), z.z()};
  return r;
}

Rotation Rotation::from_rotation_vector(const Vector3& w) {
  const double angle = w.norm();
  if (angle == 0.0) return Rotation{};
  return from_axis_angle(UnitVector3::normalize(w), angle);
}

Rotation Rotation::operator*(const Rotation& o) const {
  Rotation r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      r.m_[3 * i + j] =
          m_[3 * i] * o.m_[j] + m_[3 * i + 1] * o.m_[3 + j] + m_[3 * i + 2] * o.m_[6 + j];
  return r;
}

Rotation Rotation::inverse() const {
  Rotation r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m_[3 * i + j] = m_[3 * j + i];
  return r;
}

Vector3 Rotation::rotation_vector() const {
  // Through a quaternion: robust at angles near 0 and pi, unlike the trace formula.
  const glm::dmat3 m(m_[0], m_[3], m_[6], m_[1], m_[4], m_[7], m_[2], m_[5], m_[8]);
  glm::dquat q = glm::quat_cast(m);
  if (q.w < 0) q = -q;
  const double s = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z);
  if (s == 0.0) return {0, 0, 0};
  const double angle = 2.0 * std::atan2(s, q.w);
  return Vector3{q.x, q.y, q.z} * (angle / s);
}

UnitVector3 Rotation::column(int c) const {
  return UnitVector3::from_normalized_unchecked({m_[c], m_[3 + c], m_[6 + c]});
}

Pose Pose::inverse() const {
  const Rotation ri = r_.inverse();
  return {ri, -(ri * t_)};
}

}  // namespace purkinje
