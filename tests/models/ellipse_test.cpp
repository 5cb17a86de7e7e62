#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "purkinje/models/truth.h"
#include "reference_data.h"

namespace purkinje {
namespace {

constexpr double pi = std::numbers::pi;

// Points at parameters t on the ellipse (centre, semi-axes a along `angle`
// and b across it): c + a cos t e1 + b sin t e2.
std::vector<Pixel> points_on(const Ellipse& e, int count, double first_t = 0.1,
                             double arc = 2 * pi) {
  std::vector<Pixel> points;
  const double c = std::cos(e.angle_rad), s = std::sin(e.angle_rad);
  for (int k = 0; k < count; ++k) {
    const double t = first_t + arc * k / (arc == 2 * pi ? count : count - 1);
    const double along = e.semi_axis_1_px * std::cos(t), across = e.semi_axis_2_px * std::sin(t);
    points.push_back({e.center.u + along * c - across * s, e.center.v + along * s + across * c});
  }
  return points;
}

// Difference of two axis orientations, which are defined modulo pi.
double axis_angle_difference(double a, double b) { return std::abs(std::remainder(a - b, pi)); }

// Distance from the centre to the ellipse's edge in the direction phi; it
// does not depend on how the axes are ordered or their angles wrapped.
double radius_toward(double a, double b, double angle, double phi) {
  const double c = std::cos(phi - angle), s = std::sin(phi - angle);
  return 1 / std::sqrt(c * c / (a * a) + s * s / (b * b));
}

void expect_recovers(const Ellipse& truth, const std::vector<Pixel>& points, double tolerance) {
  const std::optional<Ellipse> fit = fit_ellipse(points);
  ASSERT_TRUE(fit.has_value());
  EXPECT_NEAR(fit->center.u, truth.center.u, tolerance);
  EXPECT_NEAR(fit->center.v, truth.center.v, tolerance);
  EXPECT_NEAR(fit->semi_axis_1_px, truth.semi_axis_1_px, tolerance);
  EXPECT_NEAR(fit->semi_axis_2_px, truth.semi_axis_2_px, tolerance);
  if (truth.semi_axis_1_px != truth.semi_axis_2_px) {
    EXPECT_LT(axis_angle_difference(fit->angle_rad, truth.angle_rad), tolerance);
  }
  EXPECT_GT(fit->angle_rad, -pi / 2);
  EXPECT_LE(fit->angle_rad, pi / 2);
}

TEST(FitEllipse, RecoversExactEllipsesFarFromTheOrigin) {
  // Semi-axis 1 is the major one.
  const std::vector<Ellipse> ellipses{
      {{1000, 800}, 30, 20, 0.3},
      {{1279.5, 1023.5}, 45, 12, -1.2},
      {{2500.25, 12.75}, 28, 27.5, 1.4},
      {{-350, 4000}, 300, 299.99, -0.7},
      {{10, -5}, 5, 1, pi / 2},
      {{640, 480}, 33, 18, 0},
  };
  for (const Ellipse& truth : ellipses) {
    SCOPED_TRACE(::testing::Message() << "centre (" << truth.center.u << ", " << truth.center.v
                                    << "), axes " << truth.semi_axis_1_px << ", "
                                    << truth.semi_axis_2_px);
    expect_recovers(truth, points_on(truth, 36), 1e-9);
    expect_recovers(truth, points_on(truth, 6, 0.4), 1e-9);
  }
}

TEST(FitEllipse, RecoversAnEllipseFromAShortArc) {
  const Ellipse truth{{812.5, 611.25}, 36, 21, 0.9};
  // Eight points over a third of the ellipse.
  expect_recovers(truth, points_on(truth, 8, 0.3, 2 * pi / 3), 1e-9);
}

TEST(FitEllipse, RecoversNearlyDegenerateThinEllipses) {
  for (double thickness : {1.0, 0.1, 0.01}) {
    SCOPED_TRACE(thickness);
    const Ellipse truth{{1100, 900}, 40, thickness, -0.45};
    expect_recovers(truth, points_on(truth, 36), 1e-9);
  }
}

TEST(FitEllipse, GivesACircleEqualSemiAxes) {
  const Ellipse circle{{1500.5, 700.5}, 27.5, 27.5, 0};
  const std::optional<Ellipse> fit = fit_ellipse(points_on(circle, 36));
  ASSERT_TRUE(fit.has_value());
  EXPECT_NEAR(fit->center.u, 1500.5, 1e-9);
  EXPECT_NEAR(fit->center.v, 700.5, 1e-9);
  EXPECT_NEAR(fit->semi_axis_1_px, 27.5, 1e-9);
  EXPECT_NEAR(fit->semi_axis_2_px, 27.5, 1e-9);
  EXPECT_TRUE(std::isfinite(fit->angle_rad));
}

TEST(FitEllipse, OrdersTheMajorAxisFirstAndWrapsItsAngle) {
  // Given with the minor axis first: the fit reports the major one first,
  // perpendicular, with the angle wrapped into (-pi/2, pi/2].
  const Ellipse minor_first{{400, 300}, 10, 25, 1.2};
  const std::optional<Ellipse> fit = fit_ellipse(points_on(minor_first, 20));
  ASSERT_TRUE(fit.has_value());
  EXPECT_NEAR(fit->semi_axis_1_px, 25, 1e-9);
  EXPECT_NEAR(fit->semi_axis_2_px, 10, 1e-9);
  EXPECT_NEAR(fit->angle_rad, 1.2 - pi / 2, 1e-9);
}

TEST(FitEllipse, NeedsSixPoints) {
  const Ellipse truth{{100, 100}, 20, 10, 0.2};
  EXPECT_FALSE(fit_ellipse(points_on(truth, 5)).has_value());
  EXPECT_FALSE(fit_ellipse({}).has_value());
  EXPECT_TRUE(fit_ellipse(points_on(truth, 6)).has_value());
}

TEST(FitEllipse, RejectsCollinearAndRepeatedPoints) {
  std::vector<Pixel> line;
  for (int k = 0; k < 10; ++k) line.push_back({100 + 3.0 * k, 200 - 2.0 * k});
  EXPECT_FALSE(fit_ellipse(line).has_value());

  std::vector<Pixel> same(8, Pixel{50, 60});
  EXPECT_FALSE(fit_ellipse(same).has_value());

  // Six points but only three distinct ones: a whole family of conics fits.
  const std::vector<Pixel> three{{0, 0}, {10, 0}, {0, 10}, {0, 0}, {10, 0}, {0, 10}};
  EXPECT_FALSE(fit_ellipse(three).has_value());
}

TEST(FitEllipse, RejectsNonFinitePoints) {
  std::vector<Pixel> points = points_on({{100, 100}, 20, 10, 0.2}, 10);
  points[3].u = std::nan("");
  EXPECT_FALSE(fit_ellipse(points).has_value());
}

TEST(FitEllipse, MatchesTheEtSimulPupilEllipses) {
  // Refracted pupil-border images from et_simul (tests/data/reference):
  // fitting them must reproduce its Halir-Flusser ellipse. Its semi-axis 1
  // is along theta but not necessarily the major one, so compare as sets.
  std::map<std::string, std::vector<Pixel>> border;
  for (const testing::CsvRow& row : testing::read_reference("pupil_border.csv")) {
    border[row.str("case_id")].push_back({row.num("u_px"), row.num("v_px")});
  }
  std::map<std::string, testing::CsvRow> cases;
  for (const testing::CsvRow& row : testing::read_reference("glints_and_pupil.csv")) {
    cases.emplace(row.str("case_id"), row);
  }
  ASSERT_GE(cases.size(), 6u);
  for (const auto& [id, row] : cases) {
    SCOPED_TRACE(id);
    ASSERT_EQ(border[id].size(), static_cast<size_t>(row.num("pupil_border_npts_used")));
    const std::optional<Ellipse> fit = fit_ellipse(border[id]);
    ASSERT_TRUE(fit.has_value());
    EXPECT_NEAR(fit->center.u, row.num("pupil_ellipse_u_px"), 1e-6);
    EXPECT_NEAR(fit->center.v, row.num("pupil_ellipse_v_px"), 1e-6);

    const double a = row.num("pupil_ellipse_semiaxis1_px");
    const double b = row.num("pupil_ellipse_semiaxis2_px");
    const double theta = row.num("pupil_ellipse_theta_rad");
    EXPECT_NEAR(fit->semi_axis_1_px, std::max(a, b), 1e-6);
    EXPECT_NEAR(fit->semi_axis_2_px, std::min(a, b), 1e-6);
    // The orientation is only defined when the axes differ noticeably.
    if (std::abs(a - b) > 1e-3) {
      const double reference_major_angle = a >= b ? theta : theta + pi / 2;
      EXPECT_LT(axis_angle_difference(fit->angle_rad, reference_major_angle), 1e-6);
    }
    for (double phi = 0; phi < pi; phi += pi / 12) {
      EXPECT_NEAR(radius_toward(fit->semi_axis_1_px, fit->semi_axis_2_px, fit->angle_rad, phi),
                  radius_toward(a, b, theta, phi), 1e-6)
          << "toward " << phi;
    }
  }
}

}  // namespace
}  // namespace purkinje
