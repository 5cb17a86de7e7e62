#pragma once
// The scene's geometry as the ray tracer meets it, free of Embree
// (internal to renderer/): each eye's surfaces (corneal caps, sclera and
// limbal band, iris and pupil discs) and, when it has lids, the lids, socket
// and face, each an exact analytic shape (surfaces.h) placed by its local
// frame; each mesh with its double-precision vertices; and the lane, one
// double-precision ray of a query with its closest hit so far. The Embree
// adapter (ray_tracer.cpp) hands these to Embree as user and triangle
// geometries.
//
// Geometry. Eye frame (eye.h): origin at the anterior cornea's centre of
// curvature, +z out along the optical axis. R = anterior radius, k = 1 + Q,
// w = R - z the depth below the anterior apex, d_L = limbus depth,
// z_L = R - d_L the limbus plane, r_L = limbus radius, z_c = R - (rotation
// centre depth) the centre of rotation, R_s = sclera radius.
//   cornea_anterior   x^2 + y^2 + k w^2 - 2 R w = 0, 0 <= w <= d_L.
//   cornea_posterior  the posterior conicoid, apex at depth = thickness,
//                     same orientation, no deeper than the limbus plane.
//   sclera            the sphere |p - (0, 0, z_c)| = R_s behind the seam
//                     z <= z_m, plus the limbal band from the cornea's edge
//                     (radius r_L in the limbus plane) to the sphere:
//                     - when the sphere reaches radius r_L behind the limbus
//                       plane, at z_m = z_c + sqrt(R_s^2 - r_L^2) < z_L: the
//                       cylinder of radius r_L for z_m <= z <= z_L;
//                     - otherwise z_m = z_L and the band is the annulus of
//                       the limbus plane between r_L and the sphere.
//                     Cap, band and sphere close the eye: a ray from outside
//                     meets this shell before anything inside it.
//   iris, pupil       the plane z = R - iris depth: the pupil is the disc
//                     about the decentred pupil centre, the iris the rest
//                     out to max(iris radius, the shell's radius there), so
//                     that the anterior chamber is closed too.
// Head frame (eyelids, when the appearance has them): origin at the centre
// of rotation, z = head_forward, y = head_up made perpendicular to z,
// x = y cross z. R_l = rotation centre depth + 0.3 mm (the corneal apex,
// at most rotation-centre-depth from the origin, clears it in every gaze),
// z_f = 0.45 R_l.
//   skin (lids)       the sphere |p| = R_l where z >= z_f, minus the
//                     palpebral opening (surfaces.h), both sides; the
//                     opening's margins turned about x as the lids follow
//                     the eye's elevation (Eyelids in appearance.h).
//   skin (face)       the plane z = z_f from the lid sphere's rim out to
//                     150 mm; with several eyes, each eye's face stops
//                     half way to the other eyes' centres of rotation, so a
//                     face never covers another eye.
//   skin (socket)     the rest of the lid sphere, z < z_f, closed: near the
//                     canthi the opening reaches beyond the eyeball's
//                     silhouette, and rays through that gap meet the socket
//                     (from inside) instead of the background.
//   face              with a face (appearance.h) instead of the three
//                     above: a mesh built per image (face_mesh.h), kind
//                     skin, and the socket's floor, the plane z = 0 out to
//                     the eyelids' half width + 3 mm.
// Outward normals: out of the eye, forward for the iris, pupil and face,
// away from the centre of rotation for the lids.
// Meshes (scene.meshes, world coordinates): one Embree triangle geometry
// each, the vertices rounded to float for Embree only. Normal: the
// triangle's front, (v1 - v0) x (v2 - v0), from the double vertices.
//

#include <algorithm>
#include <cmath>
#include <memory>
#include <type_traits>
#include <vector>

#include "purkinje/models/scene.h"
#include "purkinje/renderer/ray_tracer.h"
#include "face_mesh.h"
#include "lashes.h"
#include "surfaces.h"

namespace purkinje::renderer {

using surfaces::Box;
using surfaces::Segment;

class PlacedSurface;
class PlacedMesh;
class PlacedHairs;

// A local frame (eye or head), shared by the surfaces built in it: its Pose
// and that Pose's inverse as plain numbers, so that the hot path's
// world-to-local map inlines (Pose's own inverse() builds a Pose).
class Frame {
 public:
  explicit Frame(const Pose& world_from_local) : world_from_local_(world_from_local) {
    const Pose local_from_world = world_from_local.inverse();
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) m_[3 * i + j] = local_from_world.rotation()(i, j);
    }
    t_ = local_from_world.translation();
  }
  const Pose& world_from_local() const { return world_from_local_; }
  Vector3 to_local(const Vector3& v) const {
    return {m_[0] * v.x + m_[1] * v.y + m_[2] * v.z, m_[3] * v.x + m_[4] * v.y + m_[5] * v.z,
            m_[6] * v.x + m_[7] * v.y + m_[8] * v.z};
  }
  Point3 to_local(const Point3& p) const { return Point3::origin() + to_local(p.from_origin()) + t_; }

 private:
  Pose world_from_local_;
  double m_[9];
  Vector3 t_;
};

// Per-ray scratch that every query writes before it reads: no default
// member initialiser runs. Zeroing a lane's 128 bytes of it for every ray
// (a `rep stos`) took a tenth of a camera ray's time.
template <typename T>
union Unset {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);
  T value;
  Unset() {}
};

// A ray in a surface's frame, from its closest approach to the frame's
// origin (at `shift` along the world ray).
struct LocalRay {
  Point3 origin;
  Vector3 direction;
  double shift = 0;
};

// One ray of a query, in double precision.
struct Lane {
  Point3 origin;
  Vector3 direction;
  double t_lo = 0;
  double t_hi = 0;     // shrinks to the closest hit so far
  double t_shift = 0;  // the Embree ray starts at origin + t_shift direction
  // The closest hit so far, or the occluder: a surface, a mesh's triangle
  // or a hair's capsule (a lash's or a brow's; at most one of the three set).
  const PlacedSurface* surface = nullptr;
  const PlacedMesh* mesh = nullptr;
  const PlacedHairs* hairs = nullptr;
  unsigned primitive = 0;  // the triangle or capsule
  Unset<Point3> local_point;  // the surface's hit, set with `surface`
  // The ray in the last frame used, set with `frame`: an eye's surfaces
  // share one frame, so most callbacks skip the transform.
  const Frame* frame = nullptr;
  Unset<LocalRay> local;

  bool found() const { return surface || mesh || hairs; }
};

// One Embree geometry: a shape placed in the world by its local frame.
class PlacedSurface {
 public:
  PlacedSurface(Surface kind, int eye, std::shared_ptr<const Frame> frame)
      : kind_(kind), eye_(eye), frame_(std::move(frame)) {}
  virtual ~PlacedSurface() = default;

  Surface kind() const { return kind_; }
  // The eye it belongs to; for Surface::spectacle_lens, the lens.
  int eye() const { return eye_; }
  bool is_cornea() const {
    return kind_ == Surface::cornea_anterior || kind_ == Surface::cornea_posterior;
  }

  // First hit of the lane's ray with t in (t_lo, t_hi); the local point too.
  bool hit(Lane& lane, double& t, Point3& local_point) const {
    // (A null frame never matches: the compiler then sees `local` written
    // before it is read.)
    if (!lane.frame || lane.frame != frame_.get()) {
      const Point3 o = frame_->to_local(lane.origin);
      const Vector3 d = frame_->to_local(lane.direction);
      // Solve from the closest approach to the local origin: the shapes'
      // coefficients are then millimetre-sized whatever the ray's origin.
      const double shift = -dot(o.from_origin(), d);
      lane.local.value = LocalRay{o + d * shift, d, shift};
      lane.frame = frame_.get();
    }
    const LocalRay& local = lane.local.value;
    const double shift = local.shift;
    const Segment segment{local.origin, local.direction, lane.t_lo - shift, lane.t_hi - shift};
    double r;
    if (!first_hit(segment, r)) return false;
    t = shift + r;
    local_point = segment.origin + segment.direction * r;
    return true;
  }

  UnitVector3 world_normal(const Point3& local_point) const {
    return UnitVector3::normalize(frame_->world_from_local() * local_normal(local_point));
  }

  // The world bounds of the local box, padded so that float traversal of a
  // ray starting within the scene's bounds never misses a double hit.
  Box world_bounds() const {
    const Box local = local_bounds();
    Box world{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    double extent = 0;
    for (int corner = 0; corner < 8; ++corner) {
      const Point3 p =
          frame_->world_from_local() * Point3{(corner & 1) ? local.hi.x : local.lo.x,
                                              (corner & 2) ? local.hi.y : local.lo.y,
                                              (corner & 4) ? local.hi.z : local.lo.z};
      world.lo = {std::min(world.lo.x, p.x), std::min(world.lo.y, p.y), std::min(world.lo.z, p.z)};
      world.hi = {std::max(world.hi.x, p.x), std::max(world.hi.y, p.y), std::max(world.hi.z, p.z)};
      extent = std::max({extent, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    }
    const double pad = 1e-3 + 1e-6 * extent;
    world.lo = world.lo - Vector3{pad, pad, pad};
    world.hi = world.hi + Vector3{pad, pad, pad};
    return world;
  }

 protected:
  virtual bool first_hit(const Segment& segment, double& t) const = 0;
  virtual Vector3 local_normal(const Point3& p) const = 0;
  virtual Box local_bounds() const = 0;

 private:
  Surface kind_;
  int eye_;
  std::shared_ptr<const Frame> frame_;
};

template <class Shape>
class Placed final : public PlacedSurface {
 public:
  Placed(Surface kind, int eye, std::shared_ptr<const Frame> frame, Shape shape)
      : PlacedSurface(kind, eye, std::move(frame)), shape_(std::move(shape)) {}

 private:
  bool first_hit(const Segment& segment, double& t) const override {
    return shape_.first_hit(segment, t);
  }
  Vector3 local_normal(const Point3& p) const override { return shape_.normal(p); }
  Box local_bounds() const override { return shape_.bounds(); }

  Shape shape_;
};

// One mesh: Embree finds the triangle in float, the hit is recomputed here
// from the double vertices (see the file's comment). Either one of the
// scene's meshes (Surface::mesh, flat triangles) or an eye's face
// (Surface::skin, face_mesh.h, shaded with its vertices' normals).
class PlacedMesh {
 public:
  PlacedMesh(int index, const Mesh& mesh)
      : kind_(Surface::mesh), index_(index), vertices_(mesh.vertices), triangles_(mesh.triangles) {}
  PlacedMesh(int eye, FaceMesh face)
      : kind_(Surface::skin),
        index_(eye),
        vertices_(std::move(face.vertices)),
        triangles_(std::move(face.triangles)),
        normals_(std::move(face.normals)) {}

  Surface kind() const { return kind_; }
  // Into scene.meshes for Surface::mesh, scene.eyes for Surface::skin.
  int index() const { return index_; }
  const std::vector<Point3>& vertices() const { return vertices_; }
  const std::vector<Triangle>& triangles() const { return triangles_; }

  // Where the lane's ray crosses the plane of `triangle`, if in (t_lo, t_hi).
  bool hit(const Lane& lane, unsigned triangle, double& t) const {
    const Triangle& v = triangles_[triangle];
    const Point3& p0 = vertices_[v[0]];
    const Vector3 n = cross(vertices_[v[1]] - p0, vertices_[v[2]] - p0);
    const double along = dot(lane.direction, n);
    // Parallel to the plane, or a triangle without area: no crossing.
    if (along == 0) return false;
    const double r = dot(p0 - lane.origin, n) / along;
    if (!(r > lane.t_lo && r < lane.t_hi)) return false;
    t = r;
    return true;
  }

  // For shading: the vertices' normals interpolated at `p` (on the
  // triangle's plane) by barycentric coordinates computed in double, so
  // that every Embree kernel gives the same bytes; the triangle's own
  // normal for a mesh without vertex normals.
  UnitVector3 shading_normal(unsigned triangle, const Point3& p) const {
    if (normals_.empty()) return normal(triangle);
    const Triangle& v = triangles_[triangle];
    const Point3& p0 = vertices_[v[0]];
    const Vector3 n = cross(vertices_[v[1]] - p0, vertices_[v[2]] - p0);
    const double area = dot(n, n);
    if (!(area > 0)) return normal(triangle);
    const double b1 = dot(cross(p - p0, vertices_[v[2]] - p0), n) / area;
    const double b2 = dot(cross(vertices_[v[1]] - p0, p - p0), n) / area;
    const Vector3 mixed = normals_[v[0]].vector() * (1 - b1 - b2) + normals_[v[1]].vector() * b1 +
                          normals_[v[2]].vector() * b2;
    const auto unit = UnitVector3::try_normalize(mixed);
    return unit ? *unit : normal(triangle);
  }

  UnitVector3 normal(unsigned triangle) const {
    const Triangle& v = triangles_[triangle];
    const Point3& p0 = vertices_[v[0]];
    const UnitVector3 n = UnitVector3::normalize(cross(vertices_[v[1]] - p0, vertices_[v[2]] - p0));
    // Zeros without a sign (-0 + 0 = +0): coplanar triangles' cross
    // products can differ in a zero's sign, and which of two triangles
    // sharing an edge Embree reports differs between its kernels; the
    // normal AOV's bytes would follow (measured: remote_glasses, 40 pixels
    // of -0 natively, +0 with isa=avx2).
    return UnitVector3::from_normalized_unchecked(n.vector() + Vector3{0, 0, 0});
  }

  // Padded as PlacedSurface::world_bounds, so that the scene's bounds clip
  // no ray short of a triangle.
  Box world_bounds() const {
    Box b{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    double extent = 0;
    for (const Point3& p : vertices_) {
      b.lo = {std::min(b.lo.x, p.x), std::min(b.lo.y, p.y), std::min(b.lo.z, p.z)};
      b.hi = {std::max(b.hi.x, p.x), std::max(b.hi.y, p.y), std::max(b.hi.z, p.z)};
      extent = std::max({extent, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    }
    const double pad = 1e-3 + 1e-6 * extent;
    return {b.lo - Vector3{pad, pad, pad}, b.hi + Vector3{pad, pad, pad}};
  }

 private:
  Surface kind_;
  int index_;
  std::vector<Point3> vertices_;
  std::vector<Triangle> triangles_;
  std::vector<UnitVector3> normals_;  // per vertex; empty: flat
};

// An eye's lashes or its brows (lashes.h, brows.h): one Embree user
// primitive per capsule, each
// intersected in double precision as the analytic surfaces are (and
// unlike Embree's own curves, which are intersected in float by kernels
// that differ between instruction sets). Shaded with the capsule's
// normal: a hair's fibre seen across.
class PlacedHairs {
 public:
  // `kind`: Surface::lash or Surface::brow.
  PlacedHairs(Surface kind, int eye, std::vector<HairSegment> segments)
      : kind_(kind), eye_(eye), segments_(std::move(segments)) {}

  Surface kind() const { return kind_; }
  int eye() const { return eye_; }
  const std::vector<HairSegment>& segments() const { return segments_; }

  // The first crossing of capsule `segment` by the lane's ray in (t_lo, t_hi).
  bool hit(const Lane& lane, unsigned segment, double& t) const;
  UnitVector3 normal(unsigned segment, const Point3& p) const;
  // Padded as PlacedSurface::world_bounds.
  Box bounds(unsigned segment) const;
  Box world_bounds() const;

 private:
  Surface kind_;
  int eye_;
  std::vector<HairSegment> segments_;
};

using SurfaceList = std::vector<std::unique_ptr<PlacedSurface>>;

// Where an eye's lids (and face) are placed: the head frame (origin at the
// centre of rotation, z along appearance.head_forward, y toward head_up)
// and how far the margins turn with the eye's elevation. For an eye with
// eyelids; throws as build_scene_geometry for parallel head axes or gains
// out of [0, 2].
struct HeadPlacement {
  Pose world_from_head;
  surfaces::MarginTurns turns;
};
HeadPlacement head_placement(const Scene& scene, int eye);

// Every surface and mesh of a scene, placed. Throws std::invalid_argument
// naming eyes[i] or meshes[i] for an eye whose surfaces cannot be built (a
// cornea that does not reach its limbus, a sclera that cannot join it), lids
// whose head axes are parallel or gains out of [0, 2], or a mesh with a
// vertex beyond +-1e6 mm or an index beyond its vertices.
struct SceneGeometry {
  SurfaceList surfaces;
  std::vector<std::unique_ptr<PlacedMesh>> meshes;  // those with triangles
  std::vector<std::unique_ptr<PlacedHairs>> hairs;  // an eye's lashes, an eye's brows: those with at least one hair
};
SceneGeometry build_scene_geometry(const Scene& scene);

// A ray as a query's lane.
inline Lane lane_of(const Ray& ray) {
  Lane lane;
  lane.origin = ray.origin;
  lane.direction = ray.direction;
  lane.t_lo = ray.t_min;
  lane.t_hi = ray.t_max;
  return lane;
}

// The hit a query left in its lane, written into `hit` (in place: a
// returned Hit copied into a packet's array stalled on store forwarding).
inline void hit_of(const Ray& ray, const Lane& lane, Hit& hit) {
  hit = Hit{};
  if (!lane.found()) return;
  hit.t = lane.t_hi;
  hit.point = ray.origin + ray.direction * lane.t_hi;
  if (lane.mesh) {
    const PlacedMesh& mesh = *lane.mesh;
    hit.surface = mesh.kind();
    (mesh.kind() == Surface::mesh ? hit.mesh : hit.eye) = mesh.index();
    hit.triangle = static_cast<int>(lane.primitive);
    // Which side the ray meets is the triangle's; the shading normal may
    // lean past the ray at a silhouette.
    hit.front_face = dot(ray.direction, mesh.normal(lane.primitive)) < 0;
    hit.normal = mesh.shading_normal(lane.primitive, hit.point);
  } else if (lane.hairs) {
    hit.surface = lane.hairs->kind();
    hit.eye = lane.hairs->eye();
    hit.triangle = static_cast<int>(lane.primitive);
    hit.normal = lane.hairs->normal(lane.primitive, hit.point);
    hit.front_face = dot(ray.direction, hit.normal) < 0;
  } else {
    hit.surface = lane.surface->kind();
    (hit.surface == Surface::spectacle_lens ? hit.lens : hit.eye) = lane.surface->eye();
    hit.normal = lane.surface->world_normal(lane.local_point.value);
    hit.front_face = dot(ray.direction, hit.normal) < 0;
  }
}

}  // namespace purkinje::renderer
