#pragma once
// Rotations (axis-angle at the interface, a 3x3 matrix inside) and rigid
// poses named destination-from-source: camera_from_world * world_from_eye
// gives camera_from_eye, and a mismatched product reads wrong.

#include <array>

#include "purkinje/models/geometry.h"

namespace purkinje {

// Rotates v by `radians` around `around_axis`, right-handed (Rodrigues).
Vector3 rotate(const Vector3& v, const UnitVector3& around_axis, double radians);
UnitVector3 rotate(const UnitVector3& v, const UnitVector3& around_axis, double radians);

class Rotation {
 public:
  Rotation() = default;  // identity
  static Rotation from_axis_angle(const UnitVector3& axis, double radians);
  // The rotation whose matrix has these columns, i.e. maps the unit x, y, z
  // to the given axes. The axes must be orthonormal and right-handed
  // (checked to 1e-9; throws std::invalid_argument otherwise).
  static Rotation from_columns(const UnitVector3& x_axis, const UnitVector3& y_axis,
                               const UnitVector3& z_axis);
  // Rotation by a rotation vector (axis times angle in radians), as OpenCV's rvec.
  static Rotation from_rotation_vector(const Vector3& axis_times_radians);

  // Inline: on every ray's path.
  Vector3 operator*(const Vector3& v) const {
    return {m_[0] * v.x + m_[1] * v.y + m_[2] * v.z, m_[3] * v.x + m_[4] * v.y + m_[5] * v.z,
            m_[6] * v.x + m_[7] * v.y + m_[8] * v.z};
  }
  UnitVector3 operator*(const UnitVector3& v) const {
    return UnitVector3::from_normalized_unchecked((*this) * v.vector());
  }
  Rotation operator*(const Rotation& other) const;
  Rotation inverse() const;
  // Axis times angle in radians, angle in [0, pi].
  Vector3 rotation_vector() const;
  // Row-major matrix entries.
  double operator()(int row, int col) const { return m_[3 * row + col]; }
  UnitVector3 column(int c) const;

 private:
  std::array<double, 9> m_{1, 0, 0, 0, 1, 0, 0, 0, 1};
};

// A rigid transform. Name variables destination_from_source.
class Pose {
 public:
  Pose() = default;
  Pose(const Rotation& rotation, const Vector3& translation) : r_(rotation), t_(translation) {}

  Point3 operator*(const Point3& p) const { return Point3::origin() + r_ * p.from_origin() + t_; }
  Vector3 operator*(const Vector3& v) const { return r_ * v; }
  UnitVector3 operator*(const UnitVector3& v) const { return r_ * v; }
  Pose operator*(const Pose& other) const { return {r_ * other.r_, r_ * other.t_ + t_}; }
  Pose inverse() const;

  const Rotation& rotation() const { return r_; }
  const Vector3& translation() const { return t_; }

 private:
  Rotation r_;
  Vector3 t_;
};

}  // namespace purkinje
