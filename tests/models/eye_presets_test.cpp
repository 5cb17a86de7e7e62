// The eye-model presets against values typed from the papers (not from
// eye_presets.cpp), and the geometric rules every preset must satisfy.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "purkinje/models/eye.h"

namespace purkinje {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

// Depth from the apex of x^2 + y^2 + (1 + Q) w^2 - 2 R w = 0 at radial
// distance r (the root nearer the apex).
double sag(double radius, double asphericity, double r) {
  const double k = 1.0 + asphericity;
  return (radius - std::sqrt(radius * radius - k * r * r)) / k;
}

// Navarro's dispersion formula (Navarro, Santamaria and Bescos, JOSA A 2(8)
// 1273-1281, 1985, eq. 4; coefficients as tabulated by Atchison and Smith,
// JOSA A 22(1) 29-37, 2005):
//   n(l) = a1(l) n** + a2(l) nF + a3(l) nC + a4(l) n*
//   ai(l) = A0 + A1 l^2 + P L + R L^2,  L = 1 / (l^2 - 0.1673^2),  l in um
// with n** at 365 nm, nF at 486.1 nm, nC at 656.3 nm and n* at 1014 nm.
double navarro_index(const std::array<double, 4>& n_nodes, double wavelength_nm) {
  constexpr double a[4][4] = {{0.66147196, -0.40352796, -0.28046790, 0.03385979},
                              {-4.20146383, 2.73508956, 1.50543784, -0.11593235},
                              {6.29834237, -4.69409935, -1.57508650, 0.10293038},
                              {-1.75835059, 2.36253794, 0.35011657, -0.02085782}};
  const double l = wavelength_nm / 1000.0;
  const double big_l = 1.0 / (l * l - 0.1673 * 0.1673);
  double n = 0;
  for (int i = 0; i < 4; ++i) {
    n += (a[i][0] + a[i][1] * l * l + a[i][2] * big_l + a[i][3] * big_l * big_l) * n_nodes[i];
  }
  return n;
}
// n**, nF, nC, n* for the cornea and the aqueous (Navarro et al. 1985).
constexpr std::array<double, 4> kNavarroCornea{1.3975, 1.3807, 1.37405, 1.3668};
constexpr std::array<double, 4> kNavarroAqueous{1.3593, 1.3422, 1.3354, 1.3278};

std::vector<EyeModel> all_presets() { return {keratometric_eye(), le_grand_eye(), navarro_eye()}; }

TEST(KeratometricEye, IsOneSphericalSurfaceWithTheKeratometricIndex) {
  const EyeModel m = keratometric_eye();
  EXPECT_EQ(m.name, "keratometric");
  EXPECT_DOUBLE_EQ(m.anterior_cornea.radius_mm, 7.8);
  EXPECT_TRUE(m.anterior_cornea.is_sphere());
  EXPECT_FALSE(m.posterior_cornea.has_value());
  // Keratometric index 1.3375: power = 337.5 / R(mm) dioptres.
  EXPECT_DOUBLE_EQ(m.aqueous_index, 1.3375);
  EXPECT_NEAR((m.aqueous_index - 1.0) / (m.anterior_cornea.radius_mm * 1e-3), 43.27, 0.01);
}

TEST(KeratometricEye, HasNoKappa) {
  const EyeModel m = keratometric_eye();
  EXPECT_EQ(m.kappa_horizontal_rad, 0.0);
  EXPECT_EQ(m.kappa_vertical_rad, 0.0);
}

// Le Grand's full theoretical eye (Le Grand and El Hage, Physiological
// Optics, Springer 1980): cornea 7.8 / 6.5 mm, 0.55 mm thick,
// n = 1.3771; aqueous 1.3374; anterior chamber 3.05 mm, so the lens (and
// the iris on it) at 3.60 mm.
TEST(LeGrandEye, MatchesTheFullTheoreticalEye) {
  const EyeModel m = le_grand_eye();
  EXPECT_EQ(m.name, "le_grand");
  EXPECT_DOUBLE_EQ(m.anterior_cornea.radius_mm, 7.8);
  EXPECT_TRUE(m.anterior_cornea.is_sphere());
  ASSERT_TRUE(m.posterior_cornea.has_value());
  EXPECT_DOUBLE_EQ(m.posterior_cornea->surface.radius_mm, 6.5);
  EXPECT_TRUE(m.posterior_cornea->surface.is_sphere());
  EXPECT_DOUBLE_EQ(m.posterior_cornea->thickness_mm, 0.55);
  EXPECT_DOUBLE_EQ(m.posterior_cornea->cornea_index, 1.3771);
  EXPECT_DOUBLE_EQ(m.aqueous_index, 1.3374);
  EXPECT_NEAR(m.iris_depth_mm, 0.55 + 3.05, 1e-12);
}

// Navarro et al. 1985, Table 1 (unaccommodated), repeated by Escudero-Sanz
// and Navarro, JOSA A 16(8) 1881-1891, 1999, Table 1: anterior cornea
// R 7.72 mm, Q -0.26; posterior R 6.50 mm, Q 0; thickness 0.55 mm;
// anterior chamber 3.05 mm.
TEST(NavarroEye, MatchesTheNavarroGeometry) {
  const EyeModel m = navarro_eye();
  EXPECT_EQ(m.name, "navarro");
  EXPECT_DOUBLE_EQ(m.anterior_cornea.radius_mm, 7.72);
  EXPECT_DOUBLE_EQ(m.anterior_cornea.asphericity, -0.26);
  ASSERT_TRUE(m.posterior_cornea.has_value());
  EXPECT_DOUBLE_EQ(m.posterior_cornea->surface.radius_mm, 6.50);
  EXPECT_TRUE(m.posterior_cornea->surface.is_sphere());
  EXPECT_DOUBLE_EQ(m.posterior_cornea->thickness_mm, 0.55);
  EXPECT_NEAR(m.iris_depth_mm, 0.55 + 3.05, 1e-12);
}

// Escudero-Sanz and Navarro 1999, Table 1 lists the indices the dispersion
// formula gives at four wavelengths; reproducing them checks the formula as
// typed here before it is trusted at 850 nm. The published aqueous index at
// 458 nm differs from the formula by 1.5e-4, hence the tolerance.
TEST(NavarroDispersion, ReproducesThePublishedIndices) {
  constexpr double kTolerance = 2e-4;
  EXPECT_NEAR(navarro_index(kNavarroCornea, 458.0), 1.3828, kTolerance);
  EXPECT_NEAR(navarro_index(kNavarroCornea, 543.0), 1.3777, kTolerance);
  EXPECT_NEAR(navarro_index(kNavarroCornea, 589.3), 1.3760, kTolerance);
  EXPECT_NEAR(navarro_index(kNavarroCornea, 632.8), 1.3747, kTolerance);
  EXPECT_NEAR(navarro_index(kNavarroAqueous, 458.0), 1.3445, kTolerance);
  EXPECT_NEAR(navarro_index(kNavarroAqueous, 543.0), 1.3391, kTolerance);
  EXPECT_NEAR(navarro_index(kNavarroAqueous, 589.3), 1.3374, kTolerance);
  EXPECT_NEAR(navarro_index(kNavarroAqueous, 632.8), 1.3360, kTolerance);
}

TEST(NavarroEye, UsesTheIndicesAt850Nanometres) {
  const EyeModel m = navarro_eye();
  ASSERT_TRUE(m.posterior_cornea.has_value());
  // Rounded to four decimals, as the paper's tables.
  EXPECT_NEAR(m.posterior_cornea->cornea_index, navarro_index(kNavarroCornea, 850.0), 6e-5);
  EXPECT_NEAR(m.aqueous_index, navarro_index(kNavarroAqueous, 850.0), 6e-5);
  // Normal dispersion: lower than the visible-light values.
  EXPECT_LT(m.posterior_cornea->cornea_index, 1.3760);
  EXPECT_LT(m.aqueous_index, 1.3374);
}

TEST(AnatomicalEyes, HaveTheTypicalKappa) {
  for (const EyeModel& m : {le_grand_eye(), navarro_eye()}) {
    SCOPED_TRACE(m.name);
    EXPECT_NEAR(m.kappa_horizontal_rad, 5.0 * kDegree, 1e-12);
    EXPECT_NEAR(m.kappa_vertical_rad, 1.5 * kDegree, 1e-12);
  }
}

TEST(EyePresets, ShareTheAnatomyOutsideTheCornea) {
  // White-to-white 11.8 mm; centre of rotation 13.5 mm behind the apex
  // (Fry and Hill 1962); a globe of about 24 mm.
  for (const EyeModel& m : all_presets()) {
    SCOPED_TRACE(m.name);
    EXPECT_DOUBLE_EQ(2.0 * m.limbus_radius_mm, 11.8);
    EXPECT_DOUBLE_EQ(m.rotation_center_depth_mm, 13.5);
    EXPECT_DOUBLE_EQ(2.0 * m.sclera_radius_mm, 24.0);
    EXPECT_DOUBLE_EQ(m.iris_depth_mm, 3.6);
    EXPECT_EQ(m.pupil_decentration_x_mm, 0.0);
    EXPECT_EQ(m.pupil_decentration_y_mm, 0.0);
  }
}

TEST(EyePresets, HaveTheLimbusWithinTheSurfacesReach) {
  // A conicoid with Q > -1 reaches at most R / sqrt(1 + Q) from the axis.
  for (const EyeModel& m : all_presets()) {
    SCOPED_TRACE(m.name);
    const Conicoid& s = m.anterior_cornea;
    EXPECT_LT(m.limbus_radius_mm, s.radius_mm / std::sqrt(1.0 + s.asphericity));
  }
}

TEST(EyePresets, OrderPupilIrisAndLimbus) {
  for (const EyeModel& m : all_presets()) {
    SCOPED_TRACE(m.name);
    EXPECT_GT(m.pupil_radius_mm, 0.0);
    EXPECT_LT(m.pupil_radius_mm, m.iris_radius_mm);
    EXPECT_LE(m.iris_radius_mm, m.limbus_radius_mm);
  }
}

TEST(EyePresets, KeepThePosteriorCorneaBehindTheAnteriorOverTheCap) {
  for (const EyeModel& m : all_presets()) {
    if (!m.posterior_cornea) continue;
    SCOPED_TRACE(m.name);
    const PosteriorCornea& p = *m.posterior_cornea;
    ASSERT_LT(m.limbus_radius_mm, p.surface.radius_mm / std::sqrt(1.0 + p.surface.asphericity));
    for (int i = 0; i <= 100; ++i) {
      const double r = m.limbus_radius_mm * i / 100.0;
      const double anterior = sag(m.anterior_cornea.radius_mm, m.anterior_cornea.asphericity, r);
      const double posterior = p.thickness_mm + sag(p.surface.radius_mm, p.surface.asphericity, r);
      EXPECT_GT(posterior, anterior) << "r = " << r;
    }
  }
}

TEST(EyePresets, KeepTheIrisInsideTheAqueous) {
  // The iris disc lies behind the innermost corneal surface: at the iris
  // depth that surface is farther from the axis than the iris border.
  for (const EyeModel& m : all_presets()) {
    SCOPED_TRACE(m.name);
    double radius = m.anterior_cornea.radius_mm, q = m.anterior_cornea.asphericity;
    double depth = m.iris_depth_mm;
    if (m.posterior_cornea) {
      radius = m.posterior_cornea->surface.radius_mm;
      q = m.posterior_cornea->surface.asphericity;
      depth -= m.posterior_cornea->thickness_mm;
      EXPECT_GT(depth, 0.0);
    }
    // x^2 + y^2 = 2 R w - (1 + Q) w^2 at depth w.
    const double inner_radius = std::sqrt(2.0 * radius * depth - (1.0 + q) * depth * depth);
    EXPECT_LT(m.iris_radius_mm, inner_radius);
  }
}

TEST(EyePresets, PutTheRotationCentreBehindTheIris) {
  for (const EyeModel& m : all_presets()) {
    SCOPED_TRACE(m.name);
    EXPECT_GT(m.rotation_center_depth_mm, m.iris_depth_mm);
    // The sclera sphere must reach in front of the limbus plane's radius,
    // or the globe would not close around the cornea.
    EXPECT_GT(m.sclera_radius_mm, m.limbus_radius_mm);
  }
}

TEST(EyeModelPreset, FindsEachPresetByName) {
  for (const std::string name : {"keratometric", "le_grand", "navarro"}) {
    const std::optional<EyeModel> m = eye_model_preset(name);
    ASSERT_TRUE(m.has_value()) << name;
    EXPECT_EQ(m->name, name);
  }
  EXPECT_DOUBLE_EQ(eye_model_preset("navarro")->anterior_cornea.asphericity, -0.26);
  EXPECT_TRUE(eye_model_preset("keratometric")->posterior_cornea == std::nullopt);
}

TEST(EyeModelPreset, ReturnsNothingForAnUnknownName) {
  EXPECT_FALSE(eye_model_preset("gullstrand").has_value());
  EXPECT_FALSE(eye_model_preset("").has_value());
  EXPECT_FALSE(eye_model_preset("Navarro").has_value());  // names are exact
}

}  // namespace
}  // namespace purkinje
