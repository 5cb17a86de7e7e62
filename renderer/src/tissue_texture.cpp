// The skin's and the sclera's procedural albedo (materials.h:
// skin_texture, sclera_texture), seeded by the eye's texture seed.
//
// In the near infrared the skin shows little detail: melanin absorbs a
// fraction of what it does in the visible, and light scattered under the
// surface for about a millimetre softens the shading of fine wrinkles and
// pores. What is left reads as low-contrast albedo (the "softened
// appearance"): a texture of the albedo, not of the normals, so that the
// fast mode's caches (which interpolate the irradiance, not the albedo)
// keep it, and both modes shade it alike. Conjunctival vessels absorb
// little at 850 nm (haemoglobin's absorption is some 50 times weaker than
// at 550 nm): faint thin lines running from the fornix toward the limbus.
//
// Every feature is a function of the point and seeded hashes of lattice
// points (counter_random.h's mixer): deterministic, stateless.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "materials.h"
#include "purkinje/models/counter_random.h"

namespace purkinje::renderer {
namespace {

// A lattice point's hash for one seed and one texture layer.
std::uint64_t lattice_hash(std::uint64_t seed, std::uint64_t layer, std::int64_t i, std::int64_t j) {
  return mix64(seed ^ (layer * 0xd6e8feb86659fd93ULL) ^ (static_cast<std::uint64_t>(i) * 0x9e3779b97f4a7c15ULL) ^
               (static_cast<std::uint64_t>(j) * 0xc2b2ae3d27d4eb4fULL));
}
double lattice_value(std::uint64_t seed, std::uint64_t layer, std::int64_t i, std::int64_t j) {  // [-1, 1)
  return static_cast<double>(lattice_hash(seed, layer, i, j) >> 11) * 0x1.0p-52 - 1.0;
}

double smooth(double t) { return t * t * (3.0 - 2.0 * t); }

// Value noise in [-1, 1], one cell per unit in u and v; with `period`
// > 0, periodic in u (an angle's turns times the period).
double value_noise(std::uint64_t seed, std::uint64_t layer, double u, double v, std::int64_t period = 0) {
  const double cu = std::floor(u), cv = std::floor(v);
  const double fu = smooth(u - cu), fv = smooth(v - cv);
  auto i = static_cast<std::int64_t>(cu), i1 = i + 1;
  if (period > 0) {
    i = ((i % period) + period) % period;
    i1 = i + 1 == period ? 0 : i + 1;
  }
  const auto j = static_cast<std::int64_t>(cv);
  const double a0 = lattice_value(seed, layer, i, j), a1 = lattice_value(seed, layer, i1, j);
  const double b0 = lattice_value(seed, layer, i, j + 1), b1 = lattice_value(seed, layer, i1, j + 1);
  const double a = a0 + (a1 - a0) * fu, b = b0 + (b1 - b0) * fu;
  return a + (b - a) * fv;
}

// A thin line where the noise crosses zero: 1 on it, 0 beyond `width`
// (in units of the noise's value, about its cells' width times 0.5).
double zero_line(double noise, double width) {
  const double t = std::abs(noise) / width;
  return t < 1 ? 1 - smooth(t) : 0.0;
}

enum Layer : std::uint64_t { kWrinkles = 101, kFineWrinkles, kWrinkleGate, kBlotches, kPores, kVessels, kFineVessels };

// Pores: at most one per 0.4 mm cell, 0.03 to 0.06 mm across its radius.
constexpr double kPoreCellMm = 0.4;
double pore(std::uint64_t seed, double x_mm, double y_mm) {
  const double u = x_mm / kPoreCellMm, v = y_mm / kPoreCellMm;
  const double cu = std::floor(u), cv = std::floor(v);
  const std::uint64_t h = lattice_hash(seed, kPores, static_cast<std::int64_t>(cu), static_cast<std::int64_t>(cv));
  const auto byte = [h](int k) { return static_cast<double>((h >> (8 * k)) & 0xff) * (1.0 / 255); };
  if (byte(0) > 0.7) return 0;  // a cell without a pore
  const double radius = (0.03 + 0.03 * byte(1)) / kPoreCellMm;
  const double du = u - cu - (0.2 + 0.6 * byte(2)), dv = v - cv - (0.2 + 0.6 * byte(3));
  const double r = std::sqrt(du * du + dv * dv) / radius;
  return r < 1 ? 1 - smooth(r) : 0.0;
}

// The textures' means, added back so that the mean albedo is the
// appearance's (the sclera's wherever its vessels fade in, so that the
// sclera by the limbus keeps its albedo): measured over 2000 seeds, the
// skin's over 60 x 40 mm, the vessels' lines where they are whole
// (tissue_texture_test.cpp, DISABLED_MeasureTheMeansTheConstantsCancel).
constexpr double kSkinMeanDarkening = 0.0439;
constexpr double kVesselMean = 0.1118;

double textured(double mean, double contrast, double texture) {
  const double a = mean * (1.0 + contrast * texture);
  return std::isfinite(a) ? std::clamp(a, 0.0, 1.0) : std::clamp(mean, 0.0, 1.0);
}

}  // namespace

double skin_texture(std::uint64_t seed, double x_mm, double y_mm) {
  // Lattice indices stay far inside int64.
  if (!(std::abs(x_mm) < 1e9 && std::abs(y_mm) < 1e9)) return 0;
  // Fine wrinkles run along the lids (head x): zero lines of noise cells
  // 5 mm long by 0.8 mm across, and finer ones half that, each fading in
  // and out along its length (a second noise, 3 mm cells, gates it) so
  // that they break into short creases; broad blotches of 5 mm; pores.
  const double gate = std::clamp(0.5 + value_noise(seed, kWrinkleGate, x_mm / 3.0, y_mm / 3.0), 0.0, 1.0);
  const double wrinkles = zero_line(value_noise(seed, kWrinkles, x_mm / 5.0, y_mm / 0.8), 0.1) +
                          0.6 * zero_line(value_noise(seed, kFineWrinkles, x_mm / 2.5, y_mm / 0.4), 0.1);
  const double blotches = value_noise(seed, kBlotches, x_mm / 5.0, y_mm / 5.0);
  return -0.6 * gate * wrinkles + 0.4 * blotches - 0.6 * pore(seed, x_mm, y_mm) + kSkinMeanDarkening;
}

double sclera_texture(std::uint64_t seed, double turn, double polar_rad, double seam_polar_rad) {
  // Vessels: zero lines of noise 60 cells per turn around the axis and
  // one per 0.25 rad (3 mm) from it, tortuous and mostly radial; finer
  // ones, fainter, twice as dense; both fade in from 0.05 rad (0.6 mm)
  // past the seam with the cornea over 0.35 rad.
  if (!(turn >= 0 && turn <= 1 && std::abs(polar_rad) < 10)) return 0;
  const double fade = smooth(std::clamp((polar_rad - seam_polar_rad - 0.05) / 0.35, 0.0, 1.0));
  if (fade == 0) return 0;
  const double u = turn * 60, v = polar_rad / 0.25;
  const double vessels = zero_line(value_noise(seed, kVessels, u, v, 60), 0.1);
  const double fine = zero_line(value_noise(seed, kFineVessels, 2 * u, 2 * v, 120), 0.08);
  return -fade * (vessels + 0.5 * fine - kVesselMean);
}

double textured_skin_albedo(const Eye& eye, const Point3& world) {
  const EyeAppearance& a = eye.appearance();
  if (a.skin_texture_contrast == 0) return a.skin_albedo;
  // Head frame: x across the face, y up (appearance.h).
  const Vector3 p = world - eye.rotation_center();
  const Vector3 up = a.head_up.vector() - a.head_forward.vector() * dot(a.head_up, a.head_forward);
  const Vector3 across = cross(up, a.head_forward.vector());
  const double x = dot(p, across) / across.norm(), y = dot(p, up) / up.norm();
  return textured(a.skin_albedo, a.skin_texture_contrast, skin_texture(mix64(a.iris_seed), x, y));
}

double textured_sclera_albedo(const Eye& eye, const Point3& world) {
  const EyeAppearance& a = eye.appearance();
  if (a.sclera_vessel_contrast == 0) return a.sclera_albedo;
  // About the sclera's centre (the centre of rotation), in the eye frame.
  const Vector3 d = eye.eye_from_world().rotation() * (world - eye.rotation_center());
  const double polar = std::atan2(std::hypot(d.x, d.y), d.z);
  double turn = std::atan2(d.y, d.x) * (0.5 / std::numbers::pi);
  if (turn < 0) turn += 1;
  // The seam's polar angle about the centre of rotation (its height there
  // over the sclera's radius).
  const EyeModel& m = eye.model();
  const double seam = std::acos(
      std::clamp((m.rotation_center_depth_mm - m.sclera_seam_depth_mm()) / m.sclera_radius_mm, -1.0, 1.0));
  return textured(a.sclera_albedo, a.sclera_vessel_contrast, sclera_texture(mix64(a.iris_seed), turn, polar, seam));
}

}  // namespace purkinje::renderer
