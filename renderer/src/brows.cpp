#include "brows.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>

#include "purkinje/models/counter_random.h"

namespace purkinje::renderer {
namespace {

constexpr double kDeg = std::numbers::pi / 180;
constexpr double kTailPastCanthusMm = 14.0;
constexpr double kArchMm = 2.5;
constexpr double kArchAt = 0.52;        // fraction of the way from head to tail: above the lateral limbus
constexpr double kTaper = 0.6;          // the band's height falls by this share from head to tail
constexpr double kCellMm = 1.0;         // the lookup grid's cells

// The band's lower edge and height at fraction s from head to tail.
double lower_edge(const Brows& brows, double s) {
  const double q = (s - kArchAt) / kArchAt;
  return brows.height_mm + kArchMm * (1 - q * q);
}
double band_height(const Brows& brows, double s) { return brows.width_mm * (1 - kTaper * s); }

// The fraction s below which a share u of the band's area lies: the
// inverse of its area's cumulative share, (s - kTaper s^2 / 2) / (1 - kTaper / 2).
double fraction_of_area(double u) {
  return (1 - std::sqrt(std::max(0.0, 1 - 2 * kTaper * u * (1 - kTaper / 2)))) / kTaper;
}


// The face mesh's triangles over the band, seen along the head's -z: a
// grid of cells of the head frame's (x, y), each listing the triangles
// whose box meets it.
class SkinAbove {
 public:
  SkinAbove(const FaceMesh& mesh, const Pose& world_from_head, double x0, double x1, double y0, double y1)
      : mesh_(mesh), x0_(x0), y0_(y0) {
    const Pose head_from_world = world_from_head.inverse();
    head_.reserve(mesh.vertices.size());
    for (const Point3& v : mesh.vertices) head_.push_back(head_from_world * v);
    columns_ = std::max(1, static_cast<int>(std::ceil((x1 - x0) / kCellMm)));
    rows_ = std::max(1, static_cast<int>(std::ceil((y1 - y0) / kCellMm)));
    cells_.resize(static_cast<std::size_t>(columns_) * rows_);
    for (std::size_t k = 0; k < mesh.triangles.size(); ++k) {
      const Triangle& tri = mesh.triangles[k];
      double lo_x = head_[tri[0]].x, hi_x = lo_x, lo_y = head_[tri[0]].y, hi_y = lo_y;
      for (int j = 1; j < 3; ++j) {
        lo_x = std::min(lo_x, head_[tri[j]].x), hi_x = std::max(hi_x, head_[tri[j]].x);
        lo_y = std::min(lo_y, head_[tri[j]].y), hi_y = std::max(hi_y, head_[tri[j]].y);
      }
      const int c0 = std::max(0, column(lo_x)), c1 = std::min(columns_ - 1, column(hi_x));
      const int r0 = std::max(0, row(lo_y)), r1 = std::min(rows_ - 1, row(hi_y));
      for (int r = r0; r <= r1; ++r) {
        for (int c = c0; c <= c1; ++c) cells_[static_cast<std::size_t>(r) * columns_ + c].push_back(k);
      }
    }
  }

  struct Root {
    Point3 point;      // world
    Vector3 normal;    // world, unit
  };
  // The front-most (largest head z) point of the mesh above (x, y).
  std::optional<Root> at(double x, double y) const {
    const int c = column(x), r = row(y);
    if (c < 0 || r < 0 || c >= columns_ || r >= rows_) return std::nullopt;
    std::optional<Root> best;
    double best_z = -1e300;
    for (const std::size_t k : cells_[static_cast<std::size_t>(r) * columns_ + c]) {
      const Triangle& tri = mesh_.triangles[k];
      const Point3 &a = head_[tri[0]], &b = head_[tri[1]], &d = head_[tri[2]];
      const double det = (b.x - a.x) * (d.y - a.y) - (d.x - a.x) * (b.y - a.y);
      if (det == 0) continue;
      const double w1 = ((x - a.x) * (d.y - a.y) - (d.x - a.x) * (y - a.y)) / det;
      const double w2 = ((b.x - a.x) * (y - a.y) - (x - a.x) * (b.y - a.y)) / det;
      const double w0 = 1 - w1 - w2;
      if (w0 < 0 || w1 < 0 || w2 < 0) continue;
      const double z = w0 * a.z + w1 * b.z + w2 * d.z;
      if (z <= best_z) continue;
      const Vector3 n = mesh_.normals[tri[0]].vector() * w0 + mesh_.normals[tri[1]].vector() * w1 +
                        mesh_.normals[tri[2]].vector() * w2;
      const auto unit = UnitVector3::try_normalize(n);
      if (!unit) continue;
      best_z = z;
      const Point3 p = mesh_.vertices[tri[0]] + (mesh_.vertices[tri[1]] - mesh_.vertices[tri[0]]) * w1 +
                       (mesh_.vertices[tri[2]] - mesh_.vertices[tri[0]]) * w2;
      best = Root{p, unit->vector()};
    }
    return best;
  }

 private:
  int column(double x) const { return static_cast<int>(std::floor((x - x0_) / kCellMm)); }
  int row(double y) const { return static_cast<int>(std::floor((y - y0_) / kCellMm)); }

  const FaceMesh& mesh_;
  std::vector<Point3> head_;  // the mesh's vertices in the head frame
  double x0_, y0_;
  int columns_ = 0, rows_ = 0;
  std::vector<std::vector<std::size_t>> cells_;
};

}  // namespace

std::vector<HairSegment> build_brows(const Brows& brows, const Eyelids& lids, const Face& face, const FaceMesh& mesh,
                                     const Pose& world_from_head, int eye) {
  std::vector<HairSegment> segments;
  const double n_head = lids.half_width_mm;
  const double n_tail = -face.lateral_canthus_mm - kTailPastCanthusMm;
  const double length = n_head - n_tail;
  const double area = length * brows.width_mm * (1 - kTaper / 2);
  const auto count = static_cast<int>(std::lround(brows.hairs_per_mm2 * area));
  if (count <= 0 || mesh.normals.size() != mesh.vertices.size()) return segments;
  const double nasal = face.side == EyeSide::right ? 1.0 : -1.0;  // head x of +n

  double y_lo = 1e300, y_hi = -1e300;
  for (int k = 0; k <= 20; ++k) {
    const double s = k / 20.0;
    y_lo = std::min(y_lo, lower_edge(brows, s));
    y_hi = std::max(y_hi, lower_edge(brows, s) + band_height(brows, s));
  }
  // The skin under the band and under every hair's reach.
  const double x_a = nasal * n_head, x_b = nasal * n_tail, reach = 1.2 * brows.hair_length_mm + kCellMm;
  const SkinAbove skin(mesh, world_from_head, std::min(x_a, x_b) - reach, std::max(x_a, x_b) + reach, y_lo - reach,
                       y_hi + reach);
  const Rotation& head = world_from_head.rotation();
  const Pose head_from_world = world_from_head.inverse();
  const std::uint64_t key = stream_key(brows.seed, kBrowStreams + static_cast<std::uint64_t>(eye));
  const double root_radius = 0.5 * brows.thickness_mm;
  segments.reserve(static_cast<std::size_t>(count) * kBrowSegments);

  for (int k = 0; k < count; ++k) {
    // Eight numbers in [0, 1) per hair.
    const auto draw = [&](int j) { return to_unit(counter_key(key, 8 * static_cast<std::uint64_t>(k) + j)); };
    const double s = fraction_of_area(draw(0));
    const double across = draw(1);  // 0 at the band's lower edge, 1 at its upper
    // Feathered: sparser over the head's first seventh and within a fifth of
    // the band's height of its edges.
    const double edge = std::min(across, 1 - across);
    if (draw(6) >= smoothstep(s, -0.02, 0.15) * smoothstep(edge, -0.1, 0.2)) continue;
    const double n = n_head + (n_tail - n_head) * s;
    const double y = lower_edge(brows, s) + across * band_height(brows, s);
    const std::optional<SkinAbove::Root> root = skin.at(nasal * n, y);
    if (!root) continue;

    // Growth, from the front: degrees above the lateral direction.
    const double body = 20 * (1 - 2 * across);
    double growth = 80 + (body - 80) * smoothstep(s, 0.0, 0.25);
    growth += (-20 - growth) * smoothstep(s, 0.75, 1.0);
    growth = (growth + 24 * (draw(2) - 0.5)) * kDeg;
    const Vector3 seen = head * Vector3{-nasal * std::cos(growth), std::sin(growth), 0};
    const double lift = (brows.lift_deg + 10 * (draw(3) - 0.5)) * kDeg;
    const double curl = brows.curl_deg * kDeg * (1 + 0.6 * (draw(4) - 0.5));
    const double step = brows.hair_length_mm * (1 + 0.4 * (draw(5) - 0.5)) / kBrowSegments;
    // Chord by chord along the skin: each leaves the tangent plane of the
    // skin below its start (the root's, for the first) toward the growth,
    // at the hair's elevation at its middle (lift at the root, falling by
    // curl over the length, to no less than 0): the hair lies over the
    // ridge's curve instead of leaving it along the root's plane.
    std::array<HairSegment, kBrowSegments> hair;
    Point3 a = root->point - root->normal * root_radius;  // sunk into the skin: no gap at the root
    Vector3 normal = root->normal;
    bool whole = true;
    for (int j = 0; j < kBrowSegments && whole; ++j) {
      const double mid = (j + 0.5) / kBrowSegments;
      if (j > 0) {
        const Point3 h = head_from_world * a;
        if (const auto below = skin.at(h.x, h.y)) normal = below->normal;
      }
      const auto along = UnitVector3::try_normalize(seen - normal * dot(normal, seen));
      whole = along.has_value();
      if (!whole) break;
      const double elevation = std::max(lift - curl * mid, 0.0);
      const Point3 b = a + (along->vector() * std::cos(elevation) + normal * std::sin(elevation)) * step;
      hair[static_cast<std::size_t>(j)] = {a, b, root_radius * (1 - 2.0 / 3.0 * mid)};
      a = b;
    }
    if (whole) segments.insert(segments.end(), hair.begin(), hair.end());
  }
  return segments;
}

}  // namespace purkinje::renderer
