#pragma once
// A screen the eye looks at: a flat rectangle in the world, with points on
// it in millimetres from its top-left corner. Gaze targets and gaze
// estimates live here.

#include <optional>
#include <vector>

#include "purkinje/models/geometry.h"

namespace purkinje {

// A point on a screen, mm from its top-left corner: x along the rows, y
// down the columns.
struct ScreenPoint {
  double x_mm = 0, y_mm = 0;
};

struct Screen {
  Point3 top_left;                            // world mm
  UnitVector3 right = UnitVector3::unit_x();  // along the rows
  UnitVector3 down = UnitVector3::unit_y();   // down the columns, perpendicular to right
  double width_mm = 0, height_mm = 0;

  // From the centre and size, the rows along `right` and the columns
  // along `down`. Throws std::invalid_argument for sizes not > 0 or
  // directions not perpendicular (within 1e-6).
  static Screen centered(const Point3& center, double width_mm, double height_mm, const UnitVector3& right,
                         const UnitVector3& down);

  Point3 at(const ScreenPoint& p) const;
  Point3 center() const { return at({width_mm / 2, height_mm / 2}); }
  // Where the ray from `origin` along `direction` meets the screen's plane
  // (beyond its edges too); nullopt when it runs parallel to the plane or
  // away from it.
  std::optional<ScreenPoint> hit(const Point3& origin, const Vector3& direction) const;
  // The centres of a columns x rows grid of equal cells over the screen,
  // row by row. Throws std::invalid_argument for fewer than one of either.
  std::vector<ScreenPoint> grid(int columns, int rows) const;
};

}  // namespace purkinje
