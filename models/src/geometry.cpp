#include "purkinje/models/geometry.h"
#include "purkinje/models/check.h"

#include <sstream>
#include <stdexcept>

namespace purkinje {

void UnitVector3::throw_not_normalizable(const Vector3& v) {
  using check::format_number;
  throw std::invalid_argument("cannot normalize vector (" + format_number(v.x) + ", " + format_number(v.y) + ", " +
                              format_number(v.z) + ") of norm " + format_number(v.norm()));
}

UnitVector3 UnitVector3::from(const Vector3& v) {
  const double n = v.norm();
  if (!(std::abs(n - 1.0) <= 1e-9)) {
    using check::format_number;
    throw std::invalid_argument("not a unit vector: (" + format_number(v.x) + ", " + format_number(v.y) + ", " +
                                format_number(v.z) + ") has norm " + format_number(n));
  }
  return UnitVector3(v);
}

double angle_between(const Vector3& a, const Vector3& b) {
  return std::atan2(cross(a, b).norm(), dot(a, b));
}

}  // namespace purkinje
