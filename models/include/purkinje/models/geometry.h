#pragma once
// Strong geometric types in double precision. Points, vectors and unit
// vectors are distinct types so that, e.g., Point - Point is a Vector and a
// direction can never silently hold a non-unit vector. Storage is three
// plain doubles: GLM is used inside models' .cpp files only, so it never
// leaks into other components' headers.

#include <cmath>
#include <optional>

namespace purkinje {

struct Vector3 {
  double x = 0, y = 0, z = 0;

  constexpr Vector3() = default;
  constexpr Vector3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}

  constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vector3 operator-() const { return {-x, -y, -z}; }
  constexpr Vector3 operator+(const Vector3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  constexpr Vector3 operator-(const Vector3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  constexpr Vector3 operator*(double s) const { return {x * s, y * s, z * s}; }
  constexpr Vector3 operator/(double s) const { return {x / s, y / s, z / s}; }
  constexpr Vector3& operator+=(const Vector3& o) { x += o.x; y += o.y; z += o.z; return *this; }
  constexpr Vector3& operator-=(const Vector3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  constexpr Vector3& operator*=(double s) { x *= s; y *= s; z *= s; return *this; }
  constexpr bool operator==(const Vector3&) const = default;

  constexpr double squared_norm() const { return x * x + y * y + z * z; }
  double norm() const { return std::sqrt(squared_norm()); }
  bool is_finite() const { return std::isfinite(x) && std::isfinite(y) && std::isfinite(z); }
};

constexpr Vector3 operator*(double s, const Vector3& v) { return v * s; }
constexpr double dot(const Vector3& a, const Vector3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vector3 cross(const Vector3& a, const Vector3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

struct Point3 {
  double x = 0, y = 0, z = 0;

  constexpr Point3() = default;
  constexpr Point3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}

  constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vector3 operator-(const Point3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  constexpr Point3 operator+(const Vector3& v) const { return {x + v.x, y + v.y, z + v.z}; }
  constexpr Point3 operator-(const Vector3& v) const { return {x - v.x, y - v.y, z - v.z}; }
  constexpr Point3& operator+=(const Vector3& v) { x += v.x; y += v.y; z += v.z; return *this; }
  constexpr bool operator==(const Point3&) const = default;

  // The vector from the origin; for code that needs coordinates as a vector.
  constexpr Vector3 from_origin() const { return {x, y, z}; }
  static constexpr Point3 origin() { return {0, 0, 0}; }
  bool is_finite() const { return std::isfinite(x) && std::isfinite(y) && std::isfinite(z); }
};

inline double distance(const Point3& a, const Point3& b) { return (a - b).norm(); }

// A direction: always of unit length (to rounding). Constructed only through
// named factories so that an unnormalized vector cannot slip in.
class UnitVector3 {
 public:
  // Normalizes v; nullopt when v is zero or not finite.
  static std::optional<UnitVector3> try_normalize(const Vector3& v);
  // Normalizes v; throws std::invalid_argument naming the norm when v is
  // zero or not finite.
  static UnitVector3 normalize(const Vector3& v);
  // Accepts v only when |v| is 1 within 1e-9; throws with the norm otherwise.
  static UnitVector3 from(const Vector3& v);
  // For callers that have just normalized v themselves (hot paths).
  static UnitVector3 from_normalized_unchecked(const Vector3& v) { return UnitVector3(v); }

  static constexpr UnitVector3 unit_x() { return UnitVector3({1, 0, 0}); }
  static constexpr UnitVector3 unit_y() { return UnitVector3({0, 1, 0}); }
  static constexpr UnitVector3 unit_z() { return UnitVector3({0, 0, 1}); }

  constexpr const Vector3& vector() const { return v_; }
  constexpr operator const Vector3&() const { return v_; }  // NOLINT: a unit vector is a vector
  constexpr double x() const { return v_.x; }
  constexpr double y() const { return v_.y; }
  constexpr double z() const { return v_.z; }
  constexpr UnitVector3 operator-() const { return UnitVector3(-v_); }
  constexpr Vector3 operator*(double s) const { return v_ * s; }
  constexpr bool operator==(const UnitVector3&) const = default;

 private:
  constexpr explicit UnitVector3(const Vector3& v) : v_(v) {}
  // Out of line and cold: the normalizers sit on every ray's path.
  [[noreturn]] static void throw_not_normalizable(const Vector3& v);
  Vector3 v_;
};

inline std::optional<UnitVector3> UnitVector3::try_normalize(const Vector3& v) {
  const double n = v.norm();
  if (!(n > 0.0) || !std::isfinite(n)) return std::nullopt;
  return UnitVector3(v / n);
}

inline UnitVector3 UnitVector3::normalize(const Vector3& v) {
  const double n = v.norm();
  if (!(n > 0.0) || !std::isfinite(n)) throw_not_normalizable(v);
  return UnitVector3(v / n);
}

constexpr Vector3 operator*(double s, const UnitVector3& u) { return u.vector() * s; }

// Angle between two directions in radians, accurate near 0 and pi (atan2
// form, unlike acos of a dot product).
double angle_between(const Vector3& a, const Vector3& b);

// Two directions that complete n to a right-handed orthonormal frame
// (a, b, n): a along n x (1, 0, 0), or n x (0, 1, 0) where n lies within
// 26 deg of the x axis (where the first cross product would lose digits).
struct Perpendiculars {
  UnitVector3 a, b;
};
inline Perpendiculars perpendiculars(const UnitVector3& n) {
  Vector3 a = std::abs(n.x()) < 0.9 ? cross(n, Vector3{1, 0, 0}) : cross(n, Vector3{0, 1, 0});
  a = a * (1.0 / a.norm());
  return {UnitVector3::from_normalized_unchecked(a), UnitVector3::from_normalized_unchecked(cross(n, a))};
}

}  // namespace purkinje
