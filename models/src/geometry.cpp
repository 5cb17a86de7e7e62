#include "purkinje/models/geometry.h"

#include <sstream>
#include <stdexcept>

namespace purkinje {

void UnitVector3::throw_not_normalizable(const Vector3& v) {
  std::ostringstream msg;
  msg << "cannot normalize vector (" << v.x << ", " << v.y << ", " << v.z << ") of norm " << v.norm();
  throw std::invalid_argument(msg.str());
}

UnitVector3 UnitVector3::from(const Vector3& v) {
  const double n = v.norm();
  if (!(std::abs(n - 1.0) <= 1e-9)) {
    std::ostringstream msg;
    msg.precision(17);
    msg << "not a unit vector: (" << v.x << ", " << v.y << ", " << v.z << ") has norm " << n;
    throw std::invalid_argument(msg.str());
  }
  return UnitVector3(v);
}

double angle_between(const Vector3& a, const Vector3& b) {
  return std::atan2(cross(a, b).norm(), dot(a, b));
}

}  // namespace purkinje
