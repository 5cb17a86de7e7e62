// Screens: points on them, rays meeting them, grids over them, by hand.

#include "purkinje/models/screen.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace purkinje {
namespace {

TEST(Screen, PlacesAndHitsPointsByHand) {
  const Screen screen{{-100, -50, 0}, UnitVector3::unit_x(), UnitVector3::unit_y(), 200, 100};
  const Point3 p = screen.at({30, 20});
  EXPECT_EQ(p, (Point3{-70, -30, 0}));
  // From (0, 0, 600) toward (-70, -30, 0).
  const std::optional<ScreenPoint> hit = screen.hit({0, 0, 600}, Vector3{-70, -30, -600});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->x_mm, 30, 1e-12);
  EXPECT_NEAR(hit->y_mm, 20, 1e-12);
  EXPECT_FALSE(screen.hit({0, 0, 600}, Vector3{0, 0, 1}));  // looking away
  EXPECT_FALSE(screen.hit({0, 0, 600}, Vector3{1, 0, 0}));  // along the plane
  const std::vector<ScreenPoint> grid = screen.grid(2, 2);
  ASSERT_EQ(grid.size(), 4u);
  EXPECT_DOUBLE_EQ(grid[1].x_mm, 150);
  EXPECT_DOUBLE_EQ(grid[2].y_mm, 75);
  EXPECT_THROW(screen.grid(0, 3), std::invalid_argument);
}

TEST(Screen, IsBuiltFromItsCentreAndRefusesBadShapes) {
  const Screen s = Screen::centered({10, 20, 30}, 40, 10, UnitVector3::unit_x(), UnitVector3::unit_y());
  EXPECT_EQ(s.top_left, (Point3{-10, 15, 30}));
  EXPECT_EQ(s.center(), (Point3{10, 20, 30}));
  EXPECT_THROW(Screen::centered({}, 0, 10, UnitVector3::unit_x(), UnitVector3::unit_y()), std::invalid_argument);
  EXPECT_THROW(Screen::centered({}, 5, 10, UnitVector3::unit_x(), UnitVector3::unit_x()), std::invalid_argument);
}

}  // namespace
}  // namespace purkinje
