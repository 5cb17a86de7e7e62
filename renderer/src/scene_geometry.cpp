#include "scene_geometry.h"
#include "purkinje/models/check.h"
#include "brows.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace purkinje::renderer {

const char* to_string(Surface s) {
  switch (s) {
    case Surface::none: return "none";
    case Surface::skin: return "skin";
    case Surface::sclera: return "sclera";
    case Surface::iris: return "iris";
    case Surface::pupil: return "pupil";
    case Surface::cornea_anterior: return "cornea_anterior";
    case Surface::cornea_posterior: return "cornea_posterior";
    case Surface::mesh: return "mesh";
    case Surface::lash: return "lash";
    case Surface::brow: return "brow";
    case Surface::spectacle_lens: return "spectacle_lens";
  }
  return "unknown";
}

namespace {

constexpr double kLidClearanceMm = 0.3;
constexpr double kFaceHeightFraction = 0.45;
constexpr double kFaceRadiusMm = 150.0;

std::string eye_label(int index, const EyeModel& m) {
  return "RayTracer: eyes[" + std::to_string(index) + "] (" + m.name + ")";
}

[[noreturn]] void fail_eye(int index, const EyeModel& m, const std::string& what) {
  throw std::invalid_argument(eye_label(index, m) + ": " + what);
}

using check::format_number;

// The scene reader's checks, repeated for meshes built in code: an index
// out of range would read beyond the vertices, a vertex beyond float range
// would break Embree's bounds.
void check_mesh(int index, const Mesh& mesh) {
  const auto fail = [&](const std::string& what) {
    throw std::invalid_argument("RayTracer: meshes[" + std::to_string(index) + "] (" + mesh.name +
                                "): " + what);
  };
  constexpr double kLimitMm = 1e6;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Point3& p = mesh.vertices[i];
    if (!p.is_finite() || std::abs(p.x) > kLimitMm || std::abs(p.y) > kLimitMm || std::abs(p.z) > kLimitMm) {
      fail("vertex " + std::to_string(i) + " (" + format_number(p.x) + ", " + format_number(p.y) + ", " + format_number(p.z) +
           ") must be finite and within +-1e6 mm");
    }
  }
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    for (std::uint32_t v : mesh.triangles[i]) {
      if (v >= mesh.vertices.size()) {
        fail("triangle " + std::to_string(i) + " has vertex index " + std::to_string(v) + ", but the mesh has " +
             std::to_string(mesh.vertices.size()) + " vertices");
      }
    }
  }
}

template <class Shape>
void add(SurfaceList& list, Surface kind, int eye, const std::shared_ptr<const Frame>& frame,
         Shape shape) {
  list.push_back(std::make_unique<Placed<Shape>>(kind, eye, frame, std::move(shape)));
}

void add_eyeball(SurfaceList& list, int index, const Eye& eye) {
  const EyeModel& m = eye.model();
  const auto world_from_eye = std::make_shared<const Frame>(eye.world_from_eye());
  // The eye model's own rules, as the scene reader applies them: an eye
  // built in code meets them here.
  if (const std::optional<AnatomyProblem> problem = anatomy_problem(m)) {
    fail_eye(index, m, problem->key + " = " + problem->value + ": " + problem->rule);
  }
  const double R = m.anterior_cornea.radius_mm;
  const double d_L = m.limbus_depth_mm();
  const double r_L = m.limbus_radius_mm;
  const double z_L = R - d_L;
  add(list, Surface::cornea_anterior, index, world_from_eye,
      surfaces::ConicoidCap{R, 1.0 + m.anterior_cornea.asphericity, R, d_L});

  if (m.posterior_cornea) {
    // Down to the limbus plane, or on to the iris plane behind it (the
    // chamber angle: EyeModel::iris_outer_radius_mm).
    const PosteriorCornea& p = *m.posterior_cornea;
    const double depth = std::max(d_L, m.iris_depth_mm) - p.thickness_mm;
    add(list, Surface::cornea_posterior, index, world_from_eye,
        surfaces::ConicoidCap{p.surface.radius_mm, 1.0 + p.surface.asphericity,
                              R - p.thickness_mm, depth});
  }

  // Sclera and the limbal band between it and the cornea's edge.
  const double R_s = m.sclera_radius_mm;
  const double z_c = R - m.rotation_center_depth_mm;
  // Height of the limbus plane above the centre of rotation: 0 < h < R_s
  // (anatomy_problem).
  // (The seam of EyeModel::sclera_seam_depth_mm, computed as it always was
  // here so that every render keeps its bytes.)
  const double h = z_L - z_c;
  double z_seam;  // the sphere is kept behind this plane
  if (R_s >= r_L && std::sqrt(R_s * R_s - r_L * r_L) < h) {
    z_seam = z_c + std::sqrt(R_s * R_s - r_L * r_L);
    add(list, Surface::sclera, index, world_from_eye, surfaces::Cylinder{r_L, z_seam, z_L});
  } else {
    z_seam = z_L;
    const double rho = std::sqrt(R_s * R_s - h * h);
    surfaces::PlaneRegion annulus;
    annulus.z_mm = z_L;
    annulus.outer_radius_mm = std::max(rho, r_L);
    annulus.hole_radius_mm = std::min(rho, r_L);
    add(list, Surface::sclera, index, world_from_eye, std::move(annulus));
  }
  add(list, Surface::sclera, index, world_from_eye,
      surfaces::SphereBelowPlane{{0, 0, z_c}, R_s, z_seam});

  // Iris and pupil.
  const double z_I = R - m.iris_depth_mm;
  const double r_p = m.pupil_radius_mm;
  surfaces::PlaneRegion iris;
  iris.z_mm = z_I;
  // Out to the sclera, or in a two-surface eye to the chamber angle: past
  // it, camera rays and light that crossed only the anterior cornea go on
  // into the eye's dark inside.
  iris.outer_radius_mm = m.iris_outer_radius_mm();
  iris.hole_x_mm = m.pupil_decentration_x_mm;
  iris.hole_y_mm = m.pupil_decentration_y_mm;
  iris.hole_radius_mm = r_p;
  add(list, Surface::iris, index, world_from_eye, std::move(iris));
  if (r_p > 0) {
    surfaces::PlaneRegion pupil;
    pupil.z_mm = z_I;
    pupil.outer_x_mm = m.pupil_decentration_x_mm;
    pupil.outer_y_mm = m.pupil_decentration_y_mm;
    pupil.outer_radius_mm = r_p;
    add(list, Surface::pupil, index, world_from_eye, std::move(pupil));
  }
}

// The face (face_mesh.h) in place of the lid sphere, socket and wall, and
// the socket's floor, the plane z = 0 of the head frame: seen only through
// the canthi, where the opening reaches past the globe (elsewhere the
// globe and the lids hide it, and no ray inside the eye gets behind the
// iris plane).
void add_face(SceneGeometry& geometry, const Scene& scene, int index, const Eye& eye,
              const std::shared_ptr<const Frame>& head,
              const surfaces::MarginTurns& turns, std::size_t eyeball_begin) {
  std::vector<const PlacedSurface*> outer;
  for (std::size_t i = eyeball_begin; i < geometry.surfaces.size(); ++i) {
    const Surface kind = geometry.surfaces[i]->kind();
    if (kind == Surface::cornea_anterior || kind == Surface::sclera) outer.push_back(geometry.surfaces[i].get());
  }
  const Pose& H = head->world_from_local();
  constexpr double kFarMm = 100.0;  // in front of any eye surface (head frame z)
  const UnitVector3 back = H * -UnitVector3::unit_z();
  const auto support_depth = [&](double x, double y) -> std::optional<double> {
    Lane lane;
    lane.origin = H * Point3{x, y, kFarMm};
    lane.direction = back;
    lane.t_lo = 0;
    lane.t_hi = 2 * kFarMm;
    bool found = false;
    for (const PlacedSurface* s : outer) {
      double t;
      Point3 local;
      if (s->hit(lane, t, local)) {
        lane.t_hi = t;
        found = true;
      }
    }
    if (!found) return std::nullopt;
    return kFarMm - lane.t_hi;
  };
  bool alone = true;
  for (std::size_t j = 0; j < scene.eyes.size(); ++j) {
    if (static_cast<int>(j) != index && scene.eyes[j].appearance().face) alone = false;
  }
  FaceMesh face = build_face_mesh(eye, H, turns, support_depth, alone);
  if (const auto& lashes = eye.appearance().face->lashes) {
    // Streams 2 index and 2 index + 1: each lid of each eye its own draws.
    const auto stream = 2 * static_cast<std::uint64_t>(index);
    std::vector<HairSegment> segments = build_lashes(*lashes, face.upper_edge, true, stream);
    const std::vector<HairSegment> lower = build_lashes(*lashes, face.lower_edge, false, stream + 1);
    segments.insert(segments.end(), lower.begin(), lower.end());
    if (!segments.empty()) geometry.hairs.push_back(std::make_unique<PlacedHairs>(Surface::lash, index, std::move(segments)));
  }
  if (const auto& brows = eye.appearance().face->brows) {
    std::vector<HairSegment> hairs = build_brows(*brows, *eye.appearance().eyelids, *eye.appearance().face, face, H, index);
    if (!hairs.empty()) geometry.hairs.push_back(std::make_unique<PlacedHairs>(Surface::brow, index, std::move(hairs)));
  }
  geometry.meshes.push_back(std::make_unique<PlacedMesh>(index, std::move(face)));

  const Eyelids& lids = *eye.appearance().eyelids;
  surfaces::PlaneRegion floor;
  floor.z_mm = 0.0;
  floor.outer_radius_mm = lids.half_width_mm + 3.0;
  add(geometry.surfaces, Surface::skin, index, head, std::move(floor));
}

}  // namespace

HeadPlacement head_placement(const Scene& scene, int index) {
  const Eye& eye = scene.eyes[index];
  const EyeAppearance& look = eye.appearance();
  const Eyelids& lids = *look.eyelids;
  const UnitVector3 z = look.head_forward;
  const auto y = UnitVector3::try_normalize(look.head_up.vector() - z.vector() * dot(look.head_up, z));
  if (!y) fail_eye(index, eye.model(), "appearance head_up is parallel to head_forward");
  const UnitVector3 x = UnitVector3::normalize(cross(*y, z));
  HeadPlacement out{Pose(Rotation::from_columns(x, *y, z), eye.rotation_center().from_origin()), {}};
  const Pose head_from_world = out.world_from_head.inverse();

  // The margins follow the eye's vertical rotation (Eyelids in appearance.h).
  for (const auto& [key, gain] : {std::pair{"upper_gain_upgaze", lids.upper_gain_upgaze},
                                  std::pair{"upper_gain_downgaze", lids.upper_gain_downgaze},
                                  std::pair{"lower_gain_upgaze", lids.lower_gain_upgaze},
                                  std::pair{"lower_gain_downgaze", lids.lower_gain_downgaze}}) {
    if (!(gain >= 0 && gain <= 2)) {
      fail_eye(index, eye.model(), std::string("eyelids ") + key + " = " + format_number(gain) + ": must be in [0, 2]");
    }
  }
  const double elevation = surfaces::eye_elevation_rad(head_from_world * eye.optical_axis().vector());
  out.turns = surfaces::margin_turns(lids.upper_gain_upgaze, lids.upper_gain_downgaze, lids.lower_gain_upgaze,
                                     lids.lower_gain_downgaze, elevation);
  return out;
}

namespace {

void add_lids(SceneGeometry& geometry, int index, const Scene& scene, std::size_t eyeball_begin) {
  SurfaceList& list = geometry.surfaces;
  const Eye& eye = scene.eyes[index];
  const EyeAppearance& look = eye.appearance();
  const Eyelids& lids = *look.eyelids;
  const HeadPlacement head = head_placement(scene, index);
  const auto world_from_head = std::make_shared<const Frame>(head.world_from_head);
  const surfaces::MarginTurns& turns = head.turns;
  if (look.face) {
    add_face(geometry, scene, index, eye, world_from_head, turns, eyeball_begin);
    return;
  }
  const double R_l = eye.model().rotation_center_depth_mm + kLidClearanceMm;
  const double z_f = kFaceHeightFraction * R_l;
  surfaces::EyelidSphere lid;
  lid.radius_mm = R_l;
  lid.min_z_mm = z_f;
  lid.max_z_mm = R_l;
  lid.opening.opening = lids.opening;
  lid.opening.upper_margin_mm = lids.upper_margin_mm;
  lid.opening.lower_margin_mm = lids.lower_margin_mm;
  lid.opening.closing_line_mm = lids.closing_line_mm;
  lid.opening.half_width_mm = lids.half_width_mm;
  lid.opening.upper_turn = surfaces::MarginTurn::by(turns.upper_rad);
  lid.opening.lower_turn = surfaces::MarginTurn::by(turns.lower_rad);
  add(list, Surface::skin, index, world_from_head, lid);
  // The socket: the rest of the sphere, behind the face, without an
  // opening. Near the canthi the opening reaches past the eyeball's
  // silhouette; without the socket those rays would see the background.
  surfaces::EyelidSphere socket;
  socket.radius_mm = R_l;
  socket.min_z_mm = -R_l;
  socket.max_z_mm = z_f;
  socket.opening.opening = 0.0;  // contains no point
  add(list, Surface::skin, index, world_from_head, socket);

  surfaces::PlaneRegion face;
  face.z_mm = z_f;
  face.outer_radius_mm = kFaceRadiusMm;
  face.hole_radius_mm = std::sqrt(R_l * R_l - z_f * z_f);
  for (std::size_t j = 0; j < scene.eyes.size(); ++j) {
    if (static_cast<int>(j) == index) continue;
    const Vector3 other = (head.world_from_head.inverse() * scene.eyes[j].rotation_center()).from_origin();
    const double gap = other.norm();
    if (!(gap > 1e-9)) continue;  // the same place: nothing to split
    face.cuts.push_back({other / gap, 0.5 * gap + surfaces::kSeamOverlapMm});
  }
  add(list, Surface::skin, index, world_from_head, std::move(face));
}

}  // namespace

bool PlacedHairs::hit(const Lane& lane, unsigned segment, double& t) const {
  const HairSegment& c = segments_[segment];
  // Solved from the ray's closest approach to the capsule's root end, so
  // that the coefficients are millimetre-sized whatever the ray's origin.
  const Vector3& d = lane.direction;  // unit
  const double shift = dot(c.a - lane.origin, d);
  const Point3 o = lane.origin + d * shift;
  const double lo = lane.t_lo - shift, hi = lane.t_hi - shift;
  const Vector3 ba = c.b - c.a, oa = o - c.a;
  const double baba = dot(ba, ba), bard = dot(ba, d), baoa = dot(ba, oa), rdoa = dot(d, oa);
  const double r2 = c.radius_mm * c.radius_mm;
  double best = INFINITY;
  // A crossing counts where it lies on the capsule's own surface: the side
  // between the ends, or an end's hemisphere beyond it.
  const auto consider = [&](double r, bool on_surface) {
    if (on_surface && r > lo && r < hi && r < best) best = r;
  };
  const double a = baba - bard * bard;
  if (a > 1e-12 * baba) {  // not along the axis: the side
    const double b = baba * rdoa - baoa * bard;
    const double cc = baba * dot(oa, oa) - baoa * baoa - r2 * baba;
    const double disc = b * b - a * cc;
    if (disc >= 0) {
      const double q = -(b + std::copysign(std::sqrt(disc), b));
      for (const double r : {q / a, q != 0 ? cc / q : q / a}) {
        const double y = baoa + r * bard;
        // Closed at the ends, overlapping the hemispheres' tests: no
        // crossing can fall between the two (the nearest root wins anyway).
        consider(r, y >= 0 && y <= baba);
      }
    }
  }
  for (int end = 0; end < 2; ++end) {
    const Vector3 oc = end == 0 ? oa : o - c.b;
    const double b = dot(d, oc), cc = dot(oc, oc) - r2;
    const double disc = b * b - cc;
    if (disc < 0) continue;
    const double root = std::sqrt(disc);
    for (const double r : {-b - root, -b + root}) {
      const double y = baoa + r * bard;
      consider(r, end == 0 ? y <= 0 : y >= baba);
    }
  }
  if (!(best < INFINITY)) return false;
  t = shift + best;
  return true;
}

UnitVector3 PlacedHairs::normal(unsigned segment, const Point3& p) const {
  const HairSegment& c = segments_[segment];
  const Vector3 ba = c.b - c.a;
  const double h = std::clamp(dot(p - c.a, ba) / dot(ba, ba), 0.0, 1.0);
  const auto n = UnitVector3::try_normalize(p - (c.a + ba * h));
  return n ? *n : UnitVector3::normalize(ba);
}

Box PlacedHairs::bounds(unsigned segment) const {
  const HairSegment& c = segments_[segment];
  const double extent = std::max({std::abs(c.a.x), std::abs(c.a.y), std::abs(c.a.z), std::abs(c.b.x),
                                  std::abs(c.b.y), std::abs(c.b.z)});
  const double pad = c.radius_mm + 1e-3 + 1e-6 * extent;
  const Vector3 p{pad, pad, pad};
  return {Point3{std::min(c.a.x, c.b.x), std::min(c.a.y, c.b.y), std::min(c.a.z, c.b.z)} - p,
          Point3{std::max(c.a.x, c.b.x), std::max(c.a.y, c.b.y), std::max(c.a.z, c.b.z)} + p};
}

Box PlacedHairs::world_bounds() const {
  Box all{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
  for (unsigned i = 0; i < segments_.size(); ++i) {
    all = united(all, bounds(i));
  }
  return all;
}

namespace {

// A spectacle lens: its front, back and edge in the lens frame, placed with
// their lens's index where other surfaces hold their eye's.
void add_spectacle_lens(SurfaceList& surfaces, int index, const Scene& scene) {
  const SpectacleLens& lens = scene.spectacle_lenses[index];
  try {
    check_spectacle_lens(lens);
    check_spectacle_lens_placement(scene, index);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("RayTracer: spectacle_lenses[" + std::to_string(index) + "] (\"" + lens.name +
                                "\"): " + e.what());
  }
  const auto frame = std::make_shared<const Frame>(lens.world_from_lens);
  const auto [a, b] = lens.outline_semi_axes_mm;
  const surfaces::LensCap front{lens.front_radius_mm, 0.0, a, b, 1.0};
  const surfaces::LensCap back{lens.back_radius_mm, -lens.center_thickness_mm, a, b, -1.0};
  surfaces.push_back(std::make_unique<Placed<surfaces::LensCap>>(Surface::spectacle_lens, index, frame, front));
  surfaces.push_back(std::make_unique<Placed<surfaces::LensCap>>(Surface::spectacle_lens, index, frame, back));
  surfaces.push_back(
      std::make_unique<Placed<surfaces::LensEdge>>(Surface::spectacle_lens, index, frame, surfaces::LensEdge{front, back}));
}

}  // namespace

SceneGeometry build_scene_geometry(const Scene& scene) {
  SceneGeometry geometry;
  for (std::size_t i = 0; i < scene.eyes.size(); ++i) {
    const int index = static_cast<int>(i);
    const std::size_t eyeball_begin = geometry.surfaces.size();
    add_eyeball(geometry.surfaces, index, scene.eyes[i]);
    if (scene.eyes[i].appearance().eyelids) add_lids(geometry, index, scene, eyeball_begin);
  }
  for (std::size_t i = 0; i < scene.spectacle_lenses.size(); ++i) {
    add_spectacle_lens(geometry.surfaces, static_cast<int>(i), scene);
  }
  for (std::size_t i = 0; i < scene.meshes.size(); ++i) {
    check_mesh(static_cast<int>(i), scene.meshes[i]);
    if (scene.meshes[i].triangles.empty()) continue;  // nothing to meet
    geometry.meshes.push_back(std::make_unique<PlacedMesh>(static_cast<int>(i), scene.meshes[i]));
  }
  return geometry;
}

}  // namespace purkinje::renderer
