// The exact optics against independent reference values (et_simul 1.01,
// confirmed by a 50-digit derivation): glints, refracted pupil-border
// points, the refracted pupil centre and the fitted pupil ellipse.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "purkinje/models/truth.h"
#include "reference_data.h"

namespace purkinje {
namespace {

using testing::CsvRow;
using testing::read_reference;

constexpr double kPi = 3.14159265358979323846;

struct ReferenceCase {
  Scene scene;
};

// The reference world: camera frame = world frame, one cornea sphere with
// a single refracting surface, pupil and limbus in one plane.
Scene scene_from(const CsvRow& row, const std::vector<CsvRow>& lights) {
  Scene s;
  Intrinsics in;
  in.fx = row.num("fx_px");
  in.fy = row.num("fy_px");
  in.cx = row.num("cx_px");
  in.cy = row.num("cy_px");
  in.width = static_cast<int>(row.num("width_px"));
  in.height = static_cast<int>(row.num("height_px"));
  s.cameras.emplace_back("reference", in, Distortion{}, Pose{});

  EyeModel m;
  const double R = row.num("cornea_radius_mm");
  const double cap = row.num("cap_min_dot_mm");
  m.anterior_cornea = {R, 0.0};
  m.aqueous_index = row.num("n_inside");
  m.limbus_radius_mm = std::sqrt(R * R - cap * cap);
  m.iris_radius_mm = m.limbus_radius_mm;
  m.iris_depth_mm = R - row.num("pupil_offset_mm");
  m.pupil_radius_mm = row.num("pupil_radius_mm");
  const Point3 c{row.num("cornea_center_x_mm"), row.num("cornea_center_y_mm"),
                 row.num("cornea_center_z_mm")};
  const UnitVector3 o =
      UnitVector3::normalize({row.num("axis_o_x"), row.num("axis_o_y"), row.num("axis_o_z")});
  s.eyes.push_back(Eye::with_cornea_center(m, c, o));
  for (const CsvRow& l : lights) {
    Illuminator ill;
    ill.position = {l.num("light_x_mm"), l.num("light_y_mm"), l.num("light_z_mm")};
    s.illuminators.push_back(ill);
  }
  return s;
}

std::map<std::string, std::vector<CsvRow>> rows_by_case(const std::vector<CsvRow>& rows) {
  std::map<std::string, std::vector<CsvRow>> out;
  for (const CsvRow& r : rows) out[r.str("case_id")].push_back(r);
  return out;
}

class Reference : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    glints_ = new std::map<std::string, std::vector<CsvRow>>(
        rows_by_case(read_reference("glints_and_pupil.csv")));
    border_ = new std::map<std::string, std::vector<CsvRow>>(
        rows_by_case(read_reference("pupil_border.csv")));
  }
  static void TearDownTestSuite() {
    delete glints_;
    delete border_;
  }
  static std::map<std::string, std::vector<CsvRow>>* glints_;
  static std::map<std::string, std::vector<CsvRow>>* border_;
};
std::map<std::string, std::vector<CsvRow>>* Reference::glints_ = nullptr;
std::map<std::string, std::vector<CsvRow>>* Reference::border_ = nullptr;

TEST_F(Reference, HasSixCasesOfTwoLightsAndThirtySixBorderPoints) {
  ASSERT_EQ(glints_->size(), 6u);
  for (const auto& [id, rows] : *glints_) {
    EXPECT_EQ(rows.size(), 2u) << id;
    EXPECT_EQ(border_->at(id).size(), 36u) << id;
  }
}

TEST_F(Reference, GlintsMatchWithinMicroPixels) {
  double max_px = 0, max_mm = 0;
  for (const auto& [id, rows] : *glints_) {
    const Scene scene = scene_from(rows[0], rows);
    const SceneTruth truth = compute_truth(scene);
    ASSERT_EQ(truth.views.size(), 1u);
    for (size_t l = 0; l < rows.size(); ++l) {
      SCOPED_TRACE(id + " light " + std::to_string(l + 1));
      const CsvRow& r = rows[l];
      const GlintTruth& g = truth.views[0].glints[l];
      EXPECT_EQ(g.status, PathStatus::ok);
      EXPECT_EQ(g.reflection.on_cap, r.num("glint_on_cap") == 1);
      EXPECT_NEAR(g.pixel.u, r.num("glint_u_px"), 1e-6);
      EXPECT_NEAR(g.pixel.v, r.num("glint_v_px"), 1e-6);
      EXPECT_NEAR(g.reflection.point.x, r.num("glint_x_mm"), 1e-8);
      EXPECT_NEAR(g.reflection.point.y, r.num("glint_y_mm"), 1e-8);
      EXPECT_NEAR(g.reflection.point.z, r.num("glint_z_mm"), 1e-8);
      EXPECT_NEAR(g.reflection.incidence_rad * 180 / kPi, r.num("glint_incidence_deg"), 1e-9);
      max_px = std::max({max_px, std::abs(g.pixel.u - r.num("glint_u_px")),
                         std::abs(g.pixel.v - r.num("glint_v_px"))});
      max_mm = std::max(max_mm, distance(g.reflection.point, {r.num("glint_x_mm"), r.num("glint_y_mm"),
                                                              r.num("glint_z_mm")}));
    }
  }
  std::printf("glints vs reference: max %.2g px, %.2g mm\n", max_px, max_mm);
}

TEST_F(Reference, RefractedPupilBorderMatchesWithinMicroPixels) {
  double max_px = 0, max_mm = 0;
  for (const auto& [id, rows] : *glints_) {
    SCOPED_TRACE(id);
    const Scene scene = scene_from(rows[0], rows);
    const SceneTruth truth = compute_truth(scene);
    const PupilTruth& pupil = truth.views[0].pupil;
    const std::vector<CsvRow>& border = border_->at(id);
    ASSERT_EQ(pupil.border.size(), border.size());
    for (size_t k = 0; k < border.size(); ++k) {
      SCOPED_TRACE("border point " + std::to_string(k));
      const CsvRow& b = border[k];
      const PupilBorderPointTruth& p = pupil.border[k];
      EXPECT_NEAR(p.border_point.x, b.num("border_x_mm"), 1e-8);
      EXPECT_NEAR(p.border_point.y, b.num("border_y_mm"), 1e-8);
      EXPECT_NEAR(p.border_point.z, b.num("border_z_mm"), 1e-8);
      EXPECT_EQ(p.status, PathStatus::ok);
      EXPECT_NEAR(p.refraction.anterior_point.x, b.num("refr_surface_x_mm"), 1e-8);
      EXPECT_NEAR(p.refraction.anterior_point.y, b.num("refr_surface_y_mm"), 1e-8);
      EXPECT_NEAR(p.refraction.anterior_point.z, b.num("refr_surface_z_mm"), 1e-8);
      EXPECT_NEAR(p.pixel.u, b.num("u_px"), 1e-6);
      EXPECT_NEAR(p.pixel.v, b.num("v_px"), 1e-6);
      max_px = std::max({max_px, std::abs(p.pixel.u - b.num("u_px")),
                         std::abs(p.pixel.v - b.num("v_px"))});
      max_mm = std::max(max_mm, distance(p.refraction.anterior_point,
                                         {b.num("refr_surface_x_mm"), b.num("refr_surface_y_mm"),
                                          b.num("refr_surface_z_mm")}));
    }
  }
  std::printf("pupil border vs reference: max %.2g px, %.2g mm\n", max_px, max_mm);
}

TEST_F(Reference, PupilCentresMatch) {
  double max_centre = 0;
  for (const auto& [id, rows] : *glints_) {
    SCOPED_TRACE(id);
    const CsvRow& r = rows[0];
    const SceneTruth truth = compute_truth(scene_from(r, rows));
    const PupilTruth& pupil = truth.views[0].pupil;
    EXPECT_EQ(pupil.refracted_center_status, PathStatus::ok);
    EXPECT_NEAR(pupil.refracted_center.u, r.num("pc_refr_u_px"), 1e-6);
    EXPECT_NEAR(pupil.refracted_center.v, r.num("pc_refr_v_px"), 1e-6);
    EXPECT_NEAR(pupil.refracted_center_path.anterior_point.x, r.num("pc_refr_surface_x_mm"), 1e-8);
    EXPECT_NEAR(pupil.refracted_center_path.anterior_point.y, r.num("pc_refr_surface_y_mm"), 1e-8);
    EXPECT_NEAR(pupil.refracted_center_path.anterior_point.z, r.num("pc_refr_surface_z_mm"), 1e-8);
    EXPECT_NEAR(pupil.unrefracted_center.pixel.u, r.num("pc_norefr_u_px"), 1e-6);
    EXPECT_NEAR(pupil.unrefracted_center.pixel.v, r.num("pc_norefr_v_px"), 1e-6);
    ASSERT_TRUE(pupil.ellipse_valid);
    EXPECT_NEAR(pupil.ellipse.center.u, r.num("pupil_ellipse_u_px"), 1e-5);
    EXPECT_NEAR(pupil.ellipse.center.v, r.num("pupil_ellipse_v_px"), 1e-5);
    max_centre = std::max({max_centre, std::abs(pupil.ellipse.center.u - r.num("pupil_ellipse_u_px")),
                           std::abs(pupil.ellipse.center.v - r.num("pupil_ellipse_v_px"))});
    // Semi-axes in either order (the reference's order follows its angle).
    const double a = pupil.ellipse.semi_axis_1_px, b = pupil.ellipse.semi_axis_2_px;
    const double ra = r.num("pupil_ellipse_semiaxis1_px"), rb = r.num("pupil_ellipse_semiaxis2_px");
    EXPECT_NEAR(std::max(a, b), std::max(ra, rb), 1e-5);
    EXPECT_NEAR(std::min(a, b), std::min(ra, rb), 1e-5);
  }
  std::printf("pupil ellipse centres vs reference: max %.2g px\n", max_centre);
}

}  // namespace
}  // namespace purkinje
