#include "purkinje/models/screen.h"
#include "purkinje/models/check.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace purkinje {

Screen Screen::centered(const Point3& center, double width_mm, double height_mm, const UnitVector3& right,
                        const UnitVector3& down) {
  if (!(width_mm > 0 && height_mm > 0 && std::isfinite(width_mm) && std::isfinite(height_mm))) {
    throw std::invalid_argument("Screen: size " + check::format_number(width_mm) + " x " +
                                check::format_number(height_mm) + " mm: both must be > 0");
  }
  if (!(std::abs(dot(right, down)) < 1e-6)) {
    throw std::invalid_argument("Screen: right and down meet at " +
                                check::format_number(angle_between(right, down) * 180 / 3.14159265358979323846) +
                                " deg: they must be perpendicular");
  }
  return {center - (width_mm / 2) * right - (height_mm / 2) * down, right, down, width_mm, height_mm};
}

Point3 Screen::at(const ScreenPoint& p) const { return top_left + p.x_mm * right + p.y_mm * down; }

std::optional<ScreenPoint> Screen::hit(const Point3& origin, const Vector3& direction) const {
  const Vector3 normal = cross(right, down);
  const double along = dot(direction, normal);
  if (!(std::abs(along) > 1e-12 * direction.norm())) return std::nullopt;
  const double s = dot(top_left - origin, normal) / along;
  if (!(s > 0)) return std::nullopt;
  const Vector3 offset = (origin + s * direction) - top_left;
  return ScreenPoint{dot(offset, right), dot(offset, down)};
}

std::vector<ScreenPoint> Screen::grid(int columns, int rows) const {
  if (columns < 1 || rows < 1) {
    std::ostringstream out;
    out << "Screen::grid: " << columns << " x " << rows << ": needs at least one column and one row";
    throw std::invalid_argument(out.str());
  }
  std::vector<ScreenPoint> points;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      points.push_back({(c + 0.5) * width_mm / columns, (r + 0.5) * height_mm / rows});
    }
  }
  return points;
}

}  // namespace purkinje
