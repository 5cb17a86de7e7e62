// The iris's procedural albedo (radiometry.h: iris_albedo), a material
// both integrators shade with.
//
// Pattern coordinates: rho, 0 at the pupil border and 1 at the iris border
// along the ray from the (decentred) pupil centre, so the pattern stretches
// with the pupil as a real iris does; and the angle about the pupil centre
// as a fraction of a turn. Every feature is a function of (turn, rho) and a
// seeded hash of integer lattice points, so the texture is deterministic
// and has no state.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "purkinje/models/eye.h"
#include "purkinje/renderer/radiometry.h"
#include "sampler.h"

namespace purkinje::renderer {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Hashes of lattice points for one seed and one texture layer: the seed
// mixed once per lookup, each layer offset by its own odd constant, and
// one cheap mix per lattice point (enough for value noise).
struct Lattice {
  std::uint64_t key;
  Lattice(std::uint64_t mixed_seed, std::uint64_t layer)
      : key(mixed_seed + layer * 0xd6e8feb86659fd93ULL) {}
  std::uint64_t at(std::int64_t i, std::int64_t j) const {
    std::uint64_t h = key ^ (static_cast<std::uint64_t>(i) * 0x9e3779b97f4a7c15ULL) ^
                      (static_cast<std::uint64_t>(j) * 0xc2b2ae3d27d4eb4fULL);
    h ^= h >> 32;
    h *= 0xd6e8feb86659fd93ULL;
    h ^= h >> 32;
    h *= 0xd6e8feb86659fd93ULL;
    return h ^ (h >> 32);
  }
  double value(std::int64_t i, std::int64_t j) const {  // [-1, 1)
    return static_cast<double>(at(i, j) >> 11) * 0x1.0p-52 - 1.0;
  }
};

// The angle of (x, y) as a fraction of a turn in [0, 1), to ~1e-6 turn:
// continuous and monotone, which is all the texture needs, at a fraction
// of std::atan2's cost.
double turn_of(double x, double y) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double hi = std::max(ax, ay), lo = std::min(ax, ay);
  if (!(hi > 0)) return 0;
  const double t = lo / hi, t2 = t * t;
  // atan(t) on [0, 1], minimax polynomial (error < 1e-5 rad).
  double a = t * (0.99997726 + t2 * (-0.33262347 + t2 * (0.19354346 + t2 * (-0.11643287 +
                                                          t2 * (0.05265332 - t2 * 0.01172120)))));
  if (ay > ax) a = 0.5 * std::numbers::pi - a;
  if (x < 0) a = std::numbers::pi - a;
  if (y < 0) a = 2 * std::numbers::pi - a;
  const double turn = a * (1.0 / kTwoPi);
  return turn < 1.0 ? turn : 0.0;
}

double smooth(double t) { return t * t * (3.0 - 2.0 * t); }

// floor() for the texture's coordinates, all >= 0: a truncation, where
// std::floor is a library call on baseline x86-64.
double floor_of_nonnegative(double s) { return static_cast<double>(static_cast<std::int64_t>(s)); }

// Index of a cell at [0, periods] (turns times periods), wrapped to
// [0, periods) without an integer division.
std::int64_t wrapped(double cell, int periods) {
  const auto i = static_cast<std::int64_t>(cell);
  return i >= periods ? i - periods : (i < 0 ? i + periods : i);
}

// Value noise in [-1, 1]: `periods` cells per turn in u (u in turns,
// periodic) and one cell per unit of v.
double value_noise(const Lattice& lattice, double u, int periods, double v) {
  const double su = u * periods;
  const double cu = floor_of_nonnegative(su), cv = floor_of_nonnegative(v);
  const double fu = smooth(su - cu), fv = smooth(v - cv);
  const std::int64_t i0 = wrapped(cu, periods), i1 = i0 + 1 == periods ? 0 : i0 + 1;
  const auto j0 = static_cast<std::int64_t>(cv);
  const double a0 = lattice.value(i0, j0), a1 = lattice.value(i1, j0);
  const double b0 = lattice.value(i0, j0 + 1), b1 = lattice.value(i1, j0 + 1);
  const double a = a0 + (a1 - a0) * fu, b = b0 + (b1 - b0) * fu;
  return a + (b - a) * fv;
}

// The same along u only.
double value_noise(const Lattice& lattice, double u, int periods) {
  const double su = u * periods;
  const double cu = floor_of_nonnegative(su);
  const double fu = smooth(su - cu);
  const std::int64_t i0 = wrapped(cu, periods), i1 = i0 + 1 == periods ? 0 : i0 + 1;
  const double a0 = lattice.value(i0, 0), a1 = lattice.value(i1, 0);
  return a0 + (a1 - a0) * fu;
}

// Texture layers (see iris_albedo).
enum Layer : std::uint64_t { kFibres = 1, kFineFibres, kWaviness, kCrypts, kCollarette, kFurrows, kFreckles };

// Crypts: at most one per cell of kCryptCells per turn by kCryptRows over
// rho, a radially elongated lozenge reaching at most into the next row (so
// two hashes per lookup), most likely just outside the collarette.
constexpr int kCryptCells = 26;
constexpr int kCryptRows = 5;
constexpr double kCryptChance[kCryptRows] = {0.15, 0.45, 0.35, 0.2, 0.08};

double crypt_in_cell(const Lattice& lattice, std::int64_t column, std::int64_t row, double su,
                     double sv) {
  if (row < 0 || row >= kCryptRows) return 0;
  const std::uint64_t h = lattice.at(column, row);
  if (static_cast<double>(h >> 48) * 0x1.0p-16 >= kCryptChance[row]) return 0;
  const auto byte = [h](int k) { return static_cast<double>((h >> (8 * k)) & 0xff) * (1.0 / 255); };
  const double centre_u = 0.3 + 0.4 * byte(0), half_u = 0.12 + 0.1 * byte(1);
  const double centre_v = static_cast<double>(row) + 0.3 + 0.4 * byte(2), half_v = 0.35 + 0.25 * byte(3);
  const double du = (su - centre_u) / half_u, dv = (sv - centre_v) / half_v;
  // A lozenge: pointed along the radius, rounded across it.
  const double q = du * du + std::abs(dv) * (1.0 + std::abs(dv)) * 0.5;
  return q < 1.0 ? (0.6 + 0.4 * byte(4)) * (1.0 - smooth(std::max(0.0, 2.0 * q - 1.0))) : 0.0;
}

double crypt_darkening(const Lattice& lattice, double turn, double rho) {
  const double su = turn * kCryptCells, sv = rho * kCryptRows;
  const double cu = floor_of_nonnegative(su), cv = floor_of_nonnegative(sv);
  const std::int64_t column = wrapped(cu, kCryptCells);
  const auto row = static_cast<std::int64_t>(cv);
  const std::int64_t other = sv - cv < 0.5 ? row - 1 : row + 1;
  return std::max(crypt_in_cell(lattice, column, row, su - cu, sv),
                  crypt_in_cell(lattice, column, other, su - cu, sv));
}

// Contraction furrows: kFurrowCount circular folds over the outer third
// (rho 0.62 to 0.92, 0.1 apart), each wavy by up to +-0.015 and of 1/e
// half-width 0.0125 in rho, broken: shown where a slow noise along its
// turn (9 cells a turn) is positive, fading in over its first quarter.
// The darkening's largest value over the furrows, 0 to 1.
constexpr int kFurrowCount = 4;
double furrow_darkening(const Lattice& lattice, double turn, double rho) {
  double darkest = 0;
  for (int f = 0; f < kFurrowCount; ++f) {
    const double row = 4.0 * f + 0.5;  // each furrow its own lattice rows
    const double middle = 0.62 + 0.1 * f + 0.015 * value_noise(lattice, turn, 16, row);
    const double x = (rho - middle) * (1.0 / 0.0125);
    if (std::abs(x) > 3) continue;
    const double shown = value_noise(lattice, turn, 9, row + 2);
    if (shown <= 0) continue;
    darkest = std::max(darkest, std::exp(-x * x) * smooth(std::min(4 * shown, 1.0)));
  }
  return darkest;
}

// Freckles: `count` round spots at turns and rho (0.25 to 0.95) drawn per
// spot from the seed, 0.1 to 0.3 mm across, each 0.4 to 0.7 of the mean
// darker at its middle with a soft edge. `r_mm` is the point's distance
// from the pupil centre and `span_mm` the iris's width along its ray: the
// spot is round in millimetres. The darkening's largest value, 0 to 0.7.
double freckle_darkening(const Lattice& lattice, int count, double turn, double rho, double r_mm,
                         double span_mm) {
  double darkest = 0;
  for (int k = 0; k < count; ++k) {
    const std::uint64_t h = lattice.at(k, 0);
    const auto part = [h](int i) { return static_cast<double>((h >> (12 * i)) & 0xfff) * (1.0 / 4095); };
    double d_turn = turn - part(0);
    d_turn -= std::round(d_turn);
    const double along = d_turn * kTwoPi * r_mm, across = (rho - (0.25 + 0.7 * part(1))) * span_mm;
    const double radius = 0.05 + 0.1 * part(2);
    const double d2 = (along * along + across * across) / (radius * radius);
    if (d2 >= 1) continue;
    darkest = std::max(darkest, (0.4 + 0.3 * part(3)) * (1 - smooth(std::sqrt(d2))));
  }
  return darkest;
}

// Amplitudes of the texture's parts, as fractions of the mean albedo at
// contrast 1.
constexpr double kFibreAmplitude = 1.2;
constexpr double kCryptAmplitude = 0.8;
constexpr double kCollaretteAmplitude = 0.5;
constexpr double kRuffAmplitude = 0.9;
constexpr double kLimbalAmplitude = 0.55;
constexpr double kFurrowAmplitude = 0.8;  // at iris_furrow_contrast 1
// The area-weighted mean of the darkening parts above (measured over
// seeds, for pupils of 1.5 to 3 mm in a 5.5 mm iris), added back so that
// the iris' mean is the requested albedo.
constexpr double kMeanDarkening = 0.135;

}  // namespace

double iris_albedo(const EyeModel& model, const EyeAppearance& appearance, double x_mm, double y_mm) {
  const double mean = appearance.iris_albedo;
  const double contrast = appearance.iris_texture_contrast;
  const double flat = std::isfinite(mean) ? std::clamp(mean, 0.0, 1.0) : 0.0;
  const double furrows = appearance.iris_furrow_contrast;
  const int freckles = std::clamp(appearance.iris_freckles, 0, 20);
  const bool varied = (furrows > 0 && std::isfinite(furrows)) || freckles > 0;
  if ((contrast == 0 && !varied) || !std::isfinite(x_mm) || !std::isfinite(y_mm) || !std::isfinite(contrast)) {
    return flat;
  }
  // Furrows and freckles darken by their own contrasts, the rest by the
  // texture's.
  const auto albedo_of = [&](double texture, double variety = 0) {
    const double a = mean * (1.0 + contrast * (texture + kMeanDarkening) - variety);
    return std::isfinite(a) ? std::clamp(a, 0.0, 1.0) : flat;
  };
  // Beyond the iris, out to the sclera: the limbal ring's darkest value.
  const double iris_r = model.iris_radius_mm;
  if (x_mm * x_mm + y_mm * y_mm > iris_r * iris_r) return albedo_of(-kLimbalAmplitude);

  const double cx = model.pupil_decentration_x_mm, cy = model.pupil_decentration_y_mm;
  const double dx = x_mm - cx, dy = y_mm - cy;
  const double from_centre = std::sqrt(dx * dx + dy * dy);
  double ux = 1, uy = 0;
  if (from_centre > 0) {
    const double inverse = 1.0 / from_centre;
    ux = dx * inverse;
    uy = dy * inverse;
  }
  // Distance from the pupil centre to the iris border along (ux, uy).
  const double along = cx * ux + cy * uy;
  const double border =
      -along + std::sqrt(std::max(0.0, along * along - (cx * cx + cy * cy) + iris_r * iris_r));
  const double span = std::max(border - model.pupil_radius_mm, 1e-3);
  const double rho = std::clamp((from_centre - model.pupil_radius_mm) / span, 0.0, 1.0);
  double turn = turn_of(dx, dy);
  const std::uint64_t seed = mix64(appearance.iris_seed);

  // Radial fibres: noise of high angular and low radial frequency, with a
  // slow angular waviness so that the fibres are not straight spokes.
  turn += 0.002 * value_noise(Lattice(seed, kWaviness), turn, 24, rho * 3.0);
  if (turn < 0) turn += 1;
  if (turn >= 1) turn -= 1;
  const double fibres = 0.65 * value_noise(Lattice(seed, kFibres), turn, 180, rho * 3.0) +
                        0.35 * value_noise(Lattice(seed, kFineFibres), turn, 450, rho * 7.0);
  // Collarette: a zigzag ring about a third of the way out.
  const double collarette_rho = 0.33 + 0.04 * value_noise(Lattice(seed, kCollarette), turn, 22);
  const double t = (rho - collarette_rho) * (1.0 / 0.06);
  const double collarette = std::abs(t) < 1 ? (1 - t * t) * (1 - t * t) : 0.0;
  const double ruff = 1.0 - smooth(std::min(rho * (1.0 / 0.06), 1.0));
  const double limbal = smooth(std::max(0.0, (rho - 0.82) * (1.0 / 0.18)));

  const double texture = kFibreAmplitude * fibres -
                         kCryptAmplitude * crypt_darkening(Lattice(seed, kCrypts), turn, rho) -
                         kCollaretteAmplitude * collarette - kRuffAmplitude * ruff -
                         kLimbalAmplitude * limbal;
  double variety = 0;
  if (furrows > 0 && std::isfinite(furrows)) {
    variety += kFurrowAmplitude * furrows * furrow_darkening(Lattice(seed, kFurrows), turn, rho);
  }
  if (freckles > 0) {
    variety += freckle_darkening(Lattice(seed, kFreckles), freckles, turn, rho, from_centre, span);
  }
  return albedo_of(texture, variety);
}

}  // namespace purkinje::renderer
