#include "lashes.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "purkinje/models/counter_random.h"

namespace purkinje::renderer {
namespace {

constexpr double kLateralEnd = -0.97;  // fissure coordinate of the last lash at the lateral canthus
constexpr double kPunctum = 0.6;       // and at the punctum, medially
constexpr double kDeg = std::numbers::pi / 180;

// The edge's arc length at fissure coordinate u (the edge runs along
// increasing u).
double arc_at(const MarginEdge& edge, const std::vector<double>& arc, double u) {
  const std::vector<double>& f = edge.fissure;
  if (u <= f.front()) return arc.front();
  if (u >= f.back()) return arc.back();
  const std::size_t i = static_cast<std::size_t>(std::upper_bound(f.begin(), f.end(), u) - f.begin()) - 1;
  const double w = (u - f[i]) / (f[i + 1] - f[i]);
  return arc[i] + w * (arc[i + 1] - arc[i]);
}

// One hair appended to `segments` as `count` capsules: from `root` (sunk
// by its radius along -n, so that no gap shows) along n cos(angle) +
// r sin(angle), turned toward t by `fan`, where the angle runs linearly
// from `root_angle` to root_angle + curl over its length (an arc of
// constant curvature cut into chords), its radius tapering from
// root_radius to a third of it at the tip.
void append_hair(std::vector<HairSegment>& segments, const Point3& root, const Vector3& n, const Vector3& r,
                 const Vector3& t, double root_angle, double curl, double fan, double length, double root_radius,
                 int count) {
  // A chord of an arc of constant curvature: along the mean angle, its
  // length the arc's times sinc(half the turn).
  const double step = length / count;
  const double turn = curl / count;
  const double chord = std::abs(turn) > 1e-12 ? step * std::sin(0.5 * turn) / (0.5 * turn) : step;
  Point3 a = root - n * root_radius;  // sunk into the skin: no gap at the root
  for (int j = 0; j < count; ++j) {
    const double mid = (j + 0.5) / count;
    const double angle = root_angle + curl * mid;
    const Vector3 direction = (n * std::cos(angle) + r * std::sin(angle)) * std::cos(fan) + t * std::sin(fan);
    const Point3 b = a + direction * chord;
    segments.push_back({a, b, root_radius * (1 - 2.0 / 3.0 * mid)});
    a = b;
  }
}

}  // namespace

std::vector<HairSegment> build_lashes(const Lashes& lashes, const MarginEdge& edge, bool upper, std::uint64_t stream) {
  std::vector<HairSegment> segments;
  if (edge.points.size() < 2) return segments;
  std::vector<double> arc(edge.points.size(), 0.0);
  for (std::size_t i = 1; i < arc.size(); ++i) arc[i] = arc[i - 1] + (edge.points[i] - edge.points[i - 1]).norm();
  const double s_lo = arc_at(edge, arc, kLateralEnd), s_hi = arc_at(edge, arc, kPunctum);
  const double lashed = s_hi - s_lo;
  const double per_mm = upper ? lashes.upper_per_mm : lashes.lower_per_mm;
  const auto count = static_cast<int>(std::lround(per_mm * lashed));
  if (count <= 0 || !(lashed > 0)) return segments;
  const double middle_length = upper ? lashes.upper_length_mm : lashes.lower_length_mm;
  const double middle_curl = (upper ? lashes.upper_curl_deg : lashes.lower_curl_deg) * kDeg;
  const double root_radius = 0.5 * lashes.thickness_mm;
  const std::uint64_t key = stream_key(lashes.seed, stream);
  segments.reserve(static_cast<std::size_t>(count) * kLashSegments);

  for (int k = 0; k < count; ++k) {
    // Five numbers in [-0.5, 0.5) per lash.
    const auto jitter = [&](int j) { return to_unit(counter_key(key, 8 * static_cast<std::uint64_t>(k) + j)) - 0.5; };
    const double s = std::clamp(s_lo + (k + 0.5 + 0.8 * jitter(0)) * lashed / count, s_lo, s_hi);
    // The edge between its columns i and i + 1 at arc length s.
    const std::size_t i =
        std::min(static_cast<std::size_t>(std::upper_bound(arc.begin(), arc.end(), s) - arc.begin()), arc.size() - 1) - 1;
    const double f = std::clamp((s - arc[i]) / std::max(arc[i + 1] - arc[i], 1e-12), 0.0, 1.0);
    const Point3 root = edge.points[i] + (edge.points[i + 1] - edge.points[i]) * f;
    const Vector3 n = UnitVector3::normalize(edge.normals[i].vector() * (1 - f) + edge.normals[i + 1].vector() * f).vector();
    const Vector3 rise = edge.rise[i] * (1 - f) + edge.rise[i + 1] * f;
    const Vector3 r = UnitVector3::normalize(rise - n * dot(n, rise)).vector();
    const Vector3 along = edge.points[i + 1] - edge.points[i];
    const Vector3 t = UnitVector3::normalize(along - n * dot(n, along) - r * dot(r, along)).vector();

    const double w = 2 * (s - s_lo) / lashed - 1;  // -1 lateral end, 1 punctum
    const double length = middle_length * (0.55 + 0.45 * (1 - w * w)) * (1 + 0.24 * jitter(1));
    const double fan = (20 * w + 10 * jitter(2)) * kDeg;
    const double tilt = lashes.root_deg * kDeg + 10 * kDeg * jitter(3);
    const double curl = middle_curl * (1 + 0.4 * jitter(4));

    append_hair(segments, root, n, r, t, -tilt, curl, fan, length, root_radius, kLashSegments);
  }
  return segments;
}

}  // namespace purkinje::renderer
