#include "face_mesh.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace purkinje::renderer {
namespace {

constexpr double kMarginWidthMm = 0.4;     // w_m: the margin's rounding seen along -z
constexpr double kMarginInsideMm = 0.03;   // the margin's posterior edge inside the support
constexpr double kBlendMm = 2.0;           // smooth maximum of lid and face
constexpr double kCreaseWidthMm = 0.45;    // 1/e half-width of the crease's groove
constexpr double kTempleMm = 60.0;         // the mesh's lateral end (n = -60)
constexpr double kForeheadMm = 60.0;       // its top, above the centre of rotation
constexpr double kChinwardMm = 55.0;       // its bottom, below it
constexpr double kSocketSlope = 2.5;       // the socket's floor past the globe, mm per mm
// Columns across the fissure and rows over the lids. Flat triangles of
// 0.25 x 0.25 mm as seen along -z stray about 1e-3 mm from the lid's
// sphere (circumradius squared over its diameter; 2e-3 mm where the lid
// slopes steeply away), far under a pixel of the headset (0.08 mm) or the
// remote (0.2 mm). Columns no wider: where the globe is steep seen
// along -z (near its silhouette) a chord of the closed lids' feet would dip
// below the 0.02 mm they stand in front of the eye (0.5 mm columns do).
// Rows half as far apart changed the remote face's image by at most 25 DN
// on 37 margin pixels for 1.5 times the triangles.
constexpr double kColumnStepMm = 0.25;
constexpr double kRowStepMm = 0.25;
constexpr double kCoarseStepMm = 2.5;      // the largest step, far from the eye

// Equal to max(a, b) where they differ by more than k; rounded within.
double smooth_max(double a, double b, double k) {
  const double h = std::clamp(0.5 + 0.5 * (a - b) / k, 0.0, 1.0);
  return b + (a - b) * h + k * h * (1 - h);
}

// Steps from 0 to `end`: `fine` up to `fine_until`, then growing by 20% per
// step up to kCoarseStepMm; the last one lands on `end`.
std::vector<double> steps_to(double end, double fine, double fine_until) {
  std::vector<double> at{0.0};
  double step = fine;
  while (at.back() < end) {
    const double here = at.back();
    if (here >= fine_until) step = std::min(step * 1.2, kCoarseStepMm);
    if (end - here < 1.5 * step) {
      at.push_back(end);
      break;
    }
    at.push_back(here + step);
  }
  return at;
}

// The face away from the lids, as depth z in the head frame at nasal
// coordinate n and height y; `apex` is the corneal apex's z in primary
// position. Shapes from average adult anthropometry, rounded: brow ridge
// (supraorbital rim) about 10-17 mm above the pupil, the cheek's front
// about 4 mm behind the apex, the nose's ridge at the midline rising as it
// descends, the side of the head receding from the lateral orbital rim.
double face_depth(const Face& face, double apex, double n, double y) {
  const double lateral = std::max(0.0, -n - 12.0);
  // The orbit's floor level, where the lids take over; deeper laterally
  // (the lateral orbital rim lies ~16 mm behind the apex).
  const double orbit = apex - 5.0;
  double z = orbit;
  z += (face.brow_prominence_mm + apex - orbit) * smoothstep(y, 5.0, 19.0) * (1 - smoothstep(-n, 14.0, 32.0));
  z -= 2.5 * smoothstep(y, 24.0, 45.0);                                 // the forehead slopes back
  z += (apex - 4.0 - orbit) * smoothstep(-y, 8.0, 22.0) * (1 - 0.5 * smoothstep(-n, 10.0, 30.0));  // cheek
  z -= 0.5 * lateral * lateral / 12.0;                                   // the side of the head
  // The nose: its ridge at the midline, 1 mm in front of the apex at the
  // eyes' height and coming forward below them; flanks at 45 deg.
  const double ridge = apex + 1.0 + 0.4 * std::max(0.0, -y) - 0.25 * std::max(0.0, y - 5.0);
  // Rounded over 3 mm at the ridge.
  const double across = face.midline_mm - n;
  const double flank = ridge - (std::sqrt(across * across + 9.0) - 3.0);
  return smooth_max(z, flank, 4.0);
}


double margin_turned(double m, double x, double radius, const surfaces::MarginTurn& turn) {
  // The margin point on a sphere of `radius` about the centre of rotation,
  // turned about the x axis as the lids follow the eye.
  const double z = std::sqrt(std::max(0.0, radius * radius - x * x - m * m));
  return m * turn.cos + z * turn.sin;
}

}  // namespace

double smoothstep(double x, double from, double to) {
  const double s = std::clamp((x - from) / (to - from), 0.0, 1.0);
  return s * s * (3 - 2 * s);
}

double fissure_coordinate(const Eyelids& lids, const Face& face, double x) {
  const double n = face.side == EyeSide::right ? x : -x;
  return n / (n >= 0 ? lids.half_width_mm : face.lateral_canthus_mm);
}

FissureMargins fissure_margins(const Eyelids& lids, const Face& face, double sclera_radius_mm,
                               const surfaces::MarginTurns& turns, double x) {
  const double nasal = face.side == EyeSide::right ? 1.0 : -1.0;
  const double u = fissure_coordinate(lids, face, x);
  const double shape = std::max(0.0, 1.0 - u * u);
  const double f = lids.opening * shape;
  const double tilt = std::tan(face.canthal_tilt_deg * std::numbers::pi / 180) * (-nasal * x);
  const double c = lids.closing_line_mm;
  const double m_u = c + (lids.upper_margin_mm - c) * f + tilt;
  const double m_l = c + (lids.lower_margin_mm - c) * f + tilt;
  // Turned about the x axis on a sphere just outside the globe, the
  // canthi held: only the middles move.
  const double radius = sclera_radius_mm + face.margin_thickness_mm;
  const double d_u = margin_turned(m_u, x, radius, surfaces::MarginTurn::by(turns.upper_rad)) - m_u;
  const double d_l = margin_turned(m_l, x, radius, surfaces::MarginTurn::by(turns.lower_rad)) - m_l;
  // Closed lids (opening 0) move together, by the mean turn.
  const double d_c = 0.5 * (d_u + d_l);
  FissureMargins m{m_u + shape * (d_c + lids.opening * (d_u - d_c)), m_l + shape * (d_c + lids.opening * (d_l - d_c))};
  if (m.upper_mm < m.lower_mm) m.upper_mm = m.lower_mm = 0.5 * (m.upper_mm + m.lower_mm);
  return m;
}

FaceMesh build_face_mesh(const Eye& eye, const Pose& world_from_head, const surfaces::MarginTurns& turns,
                         const SupportDepth& support_depth, bool alone) {
  const EyeModel& model = eye.model();
  const Eyelids& lids = *eye.appearance().eyelids;
  const Face& face = *eye.appearance().face;
  const double nasal = face.side == EyeSide::right ? 1.0 : -1.0;
  const double apex = model.rotation_center_depth_mm;
  const double t = face.margin_thickness_mm;
  const double globe = model.sclera_radius_mm;

  // Columns, by nasal coordinate: fine across the fissure, coarser out to
  // the temple and to the midline.
  std::vector<double> columns;
  {
    const std::vector<double> temporal = steps_to(kTempleMm, kColumnStepMm, face.lateral_canthus_mm + 2.0);
    const double fine = lids.half_width_mm + 2.0;
    // Alone, the face goes on past the midline as its mirror image, without
    // an eye, out to the other orbit's far side.
    const double nasal_end = alone ? 2 * face.midline_mm + 30.0 : face.midline_mm;
    const std::vector<double> toward_nose = steps_to(nasal_end, kColumnStepMm, fine);
    for (auto it = temporal.rbegin(); it != temporal.rend(); ++it) columns.push_back(-nasal * *it);
    for (std::size_t i = 1; i < toward_nose.size(); ++i) columns.push_back(nasal * toward_nose[i]);
    std::sort(columns.begin(), columns.end());
  }
  // Rows by distance from the margin: the margin's quarter ellipse in
  // equal angles, then fine steps over the lid (and the crease), coarser
  // beyond. The upper lid's rows reach the forehead, the lower's the cheek.
  std::vector<double> margin_rows;
  constexpr int kMarginRows = 6;
  for (int k = 0; k < kMarginRows; ++k) {
    margin_rows.push_back(kMarginWidthMm * (1 - std::cos(0.5 * std::numbers::pi * k / kMarginRows)));
  }
  const auto lid_rows = [&](double reach, double fine_until) {
    std::vector<double> rows = margin_rows;
    for (double d : steps_to(reach - kMarginWidthMm, kRowStepMm, fine_until)) rows.push_back(kMarginWidthMm + d);
    return rows;
  };
  const FissureMargins middle = fissure_margins(lids, face, globe, turns, 0.0);
  const std::vector<double> upper_rows = lid_rows(kForeheadMm - middle.upper_mm, face.crease_height_mm + 3.0);
  const std::vector<double> lower_rows = lid_rows(middle.lower_mm + kChinwardMm, 4.0);

  // Global rows bottom to top: the lower lid's, far to near, then the
  // upper lid's, near to far. `upper_start` is the upper lid's row 0.
  // The margins depend on the column only.
  std::vector<FissureMargins> column_margins;
  column_margins.reserve(columns.size());
  for (double x : columns) column_margins.push_back(fissure_margins(lids, face, globe, turns, x));

  const std::size_t lower_count = lower_rows.size();
  const std::size_t row_count = lower_count + upper_rows.size();
  const std::size_t column_count = columns.size();

  FaceMesh mesh;
  mesh.vertices.reserve(row_count * column_count);
  std::vector<bool> on_eye;  // the margins' posterior edges: lower, then upper
  const Pose& H = world_from_head;
  for (std::size_t r = 0; r < row_count; ++r) {
    const bool upper = r >= lower_count;
    const double d = upper ? upper_rows[r - lower_count] : lower_rows[lower_count - 1 - r];
    const double side = upper ? 1.0 : -1.0;
    const double far_line = upper ? middle.upper_mm : middle.lower_mm;
    // Far from the eye the rows straighten (the margins' curve would
    // otherwise ripple up to the forehead); slow enough that they stay in
    // order (the blend's slope times the margins' rise is below 1).
    const double straighten = smoothstep(d, 5.0, 30.0);
    for (std::size_t c = 0; c < column_count; ++c) {
      const double x = columns[c];
      const double n = nasal * x;
      const FissureMargins& margins = column_margins[c];
      const double margin = upper ? margins.upper_mm : margins.lower_mm;
      const double y = margin * (1 - straighten) + far_line * straighten + side * d;

      // Past the midline (alone): the mirror image, no lid.
      const bool mirrored = n > face.midline_mm;
      const std::optional<double> eye_z = mirrored ? std::nullopt : support_depth(x, y);
      // Past the globe the socket's floor rises toward the canthi.
      const double support = eye_z ? std::max(*eye_z, 0.0) : kSocketSlope * std::max(0.0, std::hypot(x, y) - globe);
      if (r == lower_count - 1 || r == lower_count) on_eye.push_back(eye_z.has_value());
      const double u = fissure_coordinate(lids, face, x);
      const double fissure = std::max(0.0, 1.0 - u * u);
      // The lid lies on the globe only; past it, it sinks away below the
      // face (the socket's floor is for the margins and the opening).
      double lid = std::max(eye_z.value_or(0.0), 0.0) + t;
      if (upper && face.crease_height_mm > 0) {
        const double at = face.crease_height_mm * (0.55 + 0.45 * fissure);
        const double g = (d - at) / kCreaseWidthMm;
        // Cut at 4 widths (1e-7 of its depth), so that past the canthi the
        // upper lid's row 0 equals the lower lid's to the bit: no crack.
        if (std::abs(g) < 4) lid -= face.crease_depth_mm * std::exp(-g * g) * (1 - smoothstep(std::abs(u), 0.9, 1.2));
      }
      // Past the globe the lid sinks away and the face takes over.
      const double r = std::hypot(x, y);
      const double beyond = std::max(0.0, r - (globe + 2.0));
      lid -= 0.5 * beyond * beyond;
      const double face_z = face_depth(face, apex, mirrored ? 2 * face.midline_mm - n : n, y);
      const double skin = mirrored ? face_z : smooth_max(lid, face_z, kBlendMm);

      double z = skin;
      if (d < kMarginWidthMm) {
        // Quarter ellipse from the support to the skin; past the canthi
        // (the lids joined) it flattens into the skin: no groove runs on.
        const double s = d / kMarginWidthMm;
        const double rise = std::sqrt(std::max(0.0, 1 - (1 - s) * (1 - s)));
        // The foot inside the support while the opening is open; where it
        // closes (under 0.05 mm) the feet rise 0.02 mm above it, so that the
        // two margins meet in front of the eye and no sliver of it shows.
        const double gap = margins.upper_mm - margins.lower_mm;
        const double bottom = support - kMarginInsideMm + (kMarginInsideMm + 0.02) * (1 - std::min(1.0, gap / 0.05));
        const double profile = bottom + (skin - bottom) * rise;
        const double joined = smoothstep(std::abs(u), 0.98, 1.02);
        z = profile + (skin - profile) * joined;
      }
      mesh.vertices.push_back(H * Point3{x, y, z});
    }
  }

  // Triangles: every cell of the grid but the strip between the margins.
  const auto index = [&](std::size_t r, std::size_t c) { return static_cast<std::uint32_t>(r * column_count + c); };
  for (std::size_t r = 0; r + 1 < row_count; ++r) {
    const bool opening = r + 1 == lower_count;
    for (std::size_t c = 0; c + 1 < column_count; ++c) {
      // The opening, but for where it lies past the globe: there the strip
      // between the margins' posterior edges is the socket's floor (no
      // part of it can be inside the eye).
      if (opening && (on_eye[c] || on_eye[c + 1] || on_eye[column_count + c] || on_eye[column_count + c + 1])) {
        continue;
      }
      const std::uint32_t a = index(r, c), b = index(r, c + 1), e = index(r + 1, c + 1), f = index(r + 1, c);
      // Counter-clockwise seen from +z (rows up, columns along +x), so that
      // the front faces out; in a left-handed placement too, since the
      // head frame is a rotation.
      mesh.triangles.push_back({a, b, e});
      mesh.triangles.push_back({a, e, f});
    }
  }

  // Per-vertex normals: the area-weighted sums of the triangles' normals.
  std::vector<Vector3> sums(mesh.vertices.size(), Vector3{0, 0, 0});
  for (const Triangle& tri : mesh.triangles) {
    const Point3& p0 = mesh.vertices[tri[0]];
    const Vector3 n = cross(mesh.vertices[tri[1]] - p0, mesh.vertices[tri[2]] - p0);
    for (std::uint32_t v : tri) sums[v] = sums[v] + n;
  }
  const UnitVector3 forward = UnitVector3::normalize(H.rotation() * Vector3{0, 0, 1});
  mesh.normals.reserve(sums.size());
  for (const Vector3& s : sums) {
    const auto n = UnitVector3::try_normalize(s);
    mesh.normals.push_back(n ? *n : forward);
  }

  // The margins' anterior edges: row kMarginRows of each lid lies at
  // d = kMarginWidthMm, where the margin's quarter ellipse meets the skin.
  const auto edge = [&](std::size_t row, std::size_t next_row) {
    MarginEdge e;
    for (std::size_t k = 0; k < column_count; ++k) {
      // Lateral to medial: along +x for a right eye, -x for a left one.
      const std::size_t c = nasal > 0 ? k : column_count - 1 - k;
      const double u = fissure_coordinate(lids, face, columns[c]);
      if (!(std::abs(u) < 1)) continue;
      e.points.push_back(mesh.vertices[index(row, c)]);
      e.normals.push_back(mesh.normals[index(row, c)]);
      e.rise.push_back(mesh.vertices[index(next_row, c)] - mesh.vertices[index(row, c)]);
      e.fissure.push_back(u);
    }
    return e;
  };
  mesh.upper_edge = edge(lower_count + kMarginRows, lower_count + kMarginRows + 1);
  mesh.lower_edge = edge(lower_count - 1 - kMarginRows, lower_count - 2 - kMarginRows);
  return mesh;
}

}  // namespace purkinje::renderer
