// The one Embree adapter (Embree 3): every surface of the eyes is an Embree
// user geometry with one primitive, whose callbacks intersect the exact
// analytic shape of surfaces.h in double precision; every mesh is an
// Embree triangle geometry whose hits are recomputed in double precision.
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
// Outward normals: out of the eye, forward for the iris, pupil and face,
// away from the centre of rotation for the lids.
// Meshes (scene.meshes, world coordinates): one Embree triangle geometry
// each, the vertices rounded to float for Embree only. Normal: the
// triangle's front, (v1 - v0) x (v2 - v0), from the double vertices.
//
// Precision. Embree traces float rays. The callbacks ignore the float ray
// and intersect the caller's double ray, which the query context carries
// (indexed by the Embree ray's id: Embree may reorder a packet's rays
// before calling back); the float ray serves traversal only. Packets of 16
// (rtcIntersect16, for camera rays) find exactly the hits of single rays:
// the double-precision callbacks decide, the float traversal only has to
// be conservative. To keep that traversal
// conservative, the float ray starts where the double ray enters the
// scene's bounds (its origin then has millimetre-sized coordinates), the
// geometry bounds are padded and the float tfar is rounded up. Each
// callback moves the ray origin to its closest approach to the shape's
// local origin before solving, so quadratics never cancel metre-sized
// terms: hit points are exact to ~1e-13 mm.
//
// Mesh hits. Embree's own (watertight, float) triangle test decides which
// triangle a ray meets; an intersection filter then recomputes where, in
// double precision from the mesh's own vertices (the t of Moller-Trumbore:
// the ray's crossing of the triangle's plane), accepts it only inside the
// double ray's interval and nearer than the closest hit so far, and, like
// the user callbacks, hands Embree a rounded-up tfar. The filter does not
// test the barycentric bounds again: along an edge shared by two triangles
// Embree reports one of them, and a second, double test could reject both
// and open a crack. Where a triangle's edge lies is thus known to float
// precision (about 1e-7 of the coordinates, 0.06 um at 600 mm); where along
// the ray the hit lies, to double precision.
//
// Ignoring the cornea (occluded_except_cornea): a flag in the query context
// read by the cornea's callbacks; when this Embree build supports ray
// masks, the cornea also gets its own mask bit so that traversal skips it.

#include "purkinje/renderer/ray_tracer.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <mutex>
#include <new>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "surfaces.h"

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
  }
  return "unknown";
}

namespace {

using surfaces::Box;
using surfaces::Segment;

constexpr double kLidClearanceMm = 0.3;
constexpr double kFaceHeightFraction = 0.45;
constexpr double kFaceRadiusMm = 150.0;
constexpr unsigned kCorneaMask = 1u;
constexpr unsigned kOtherMask = 2u;

class PlacedSurface;
class PlacedMesh;

// A local frame (eye or head), shared by the surfaces built in it. The
// world-to-local map is kept as plain numbers so the hot path inlines it.
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

// One ray of a query, in double precision.
struct Lane {
  Point3 origin;
  Vector3 direction;
  double t_lo = 0;
  double t_hi = 0;     // shrinks to the closest hit so far
  double t_shift = 0;  // the Embree ray starts at origin + t_shift direction
  // The closest hit so far, or the occluder: a surface or a mesh's triangle.
  const PlacedSurface* surface = nullptr;
  const PlacedMesh* mesh = nullptr;
  unsigned triangle = 0;
  Point3 local_point;
  // The ray in the last frame used: an eye's surfaces share one frame, so
  // most callbacks skip the transform.
  const Frame* frame = nullptr;
  Point3 local_origin;  // the closest approach to the frame's origin
  Vector3 local_direction;
  double local_shift = 0;  // t of local_origin

  bool found() const { return surface || mesh; }
};

// One Embree geometry: a shape placed in the world by its local frame.
class PlacedSurface {
 public:
  PlacedSurface(Surface kind, int eye, std::shared_ptr<const Frame> frame)
      : kind_(kind), eye_(eye), frame_(std::move(frame)) {}
  virtual ~PlacedSurface() = default;

  Surface kind() const { return kind_; }
  int eye() const { return eye_; }
  bool is_cornea() const {
    return kind_ == Surface::cornea_anterior || kind_ == Surface::cornea_posterior;
  }

  // First hit of the lane's ray with t in (t_lo, t_hi); the local point too.
  bool hit(Lane& lane, double& t, Point3& local_point) const {
    if (lane.frame != frame_.get()) {
      const Point3 o = frame_->to_local(lane.origin);
      const Vector3 d = frame_->to_local(lane.direction);
      // Solve from the closest approach to the local origin: the shapes'
      // coefficients are then millimetre-sized whatever the ray's origin.
      lane.local_shift = -dot(o.from_origin(), d);
      lane.local_origin = o + d * lane.local_shift;
      lane.local_direction = d;
      lane.frame = frame_.get();
    }
    const double shift = lane.local_shift;
    const Segment segment{lane.local_origin, lane.local_direction, lane.t_lo - shift,
                          lane.t_hi - shift};
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
// from the double vertices (see the file's comment).
class PlacedMesh {
 public:
  PlacedMesh(int index, const Mesh& mesh)
      : index_(index), vertices_(mesh.vertices), triangles_(mesh.triangles) {}

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
  int index_;
  std::vector<Point3> vertices_;
  std::vector<Triangle> triangles_;
};

// Embree hands the context pointer back to the callbacks, so extending it
// carries the double rays to them (the Embree 3 idiom; Embree 4 keeps it
// as RTCRayQueryContext).
struct Query {
  RTCIntersectContext embree;
  Lane* lanes = nullptr;
  bool skip_cornea = false;
};
static_assert(std::is_standard_layout_v<Query> && offsetof(Query, embree) == 0);

// Embree's packet types and calls by width.
template <int kWidth>
struct EmbreePacket;
template <>
struct EmbreePacket<4> {
  using RayHit = RTCRayHit4;
  static void intersect(const int* valid, RTCScene scene, RTCIntersectContext* context, RayHit* rayhit) {
    rtcIntersect4(valid, scene, context, rayhit);
  }
};
template <>
struct EmbreePacket<8> {
  using RayHit = RTCRayHit8;
  static void intersect(const int* valid, RTCScene scene, RTCIntersectContext* context, RayHit* rayhit) {
    rtcIntersect8(valid, scene, context, rayhit);
  }
};
template <>
struct EmbreePacket<16> {
  using RayHit = RTCRayHit16;
  static void intersect(const int* valid, RTCScene scene, RTCIntersectContext* context, RayHit* rayhit) {
    rtcIntersect16(valid, scene, context, rayhit);
  }
};

// A float distance for Embree at or beyond the double one (traversal culls
// beyond tfar, so it must never fall short).
float embree_far(double t) { return static_cast<float>(t * (1.0 + 1e-6) + 1e-4); }

void bounds_callback(const RTCBoundsFunctionArguments* args) {
  const auto& surface = *static_cast<const PlacedSurface*>(args->geometryUserPtr);
  const Box b = surface.world_bounds();
  RTCBounds* out = args->bounds_o;
  out->lower_x = std::nextafter(static_cast<float>(b.lo.x), -INFINITY);
  out->lower_y = std::nextafter(static_cast<float>(b.lo.y), -INFINITY);
  out->lower_z = std::nextafter(static_cast<float>(b.lo.z), -INFINITY);
  out->upper_x = std::nextafter(static_cast<float>(b.hi.x), INFINITY);
  out->upper_y = std::nextafter(static_cast<float>(b.hi.y), INFINITY);
  out->upper_z = std::nextafter(static_cast<float>(b.hi.z), INFINITY);
}

void intersect_callback(const RTCIntersectFunctionNArguments* args) {
  auto* query = reinterpret_cast<Query*>(args->context);
  const auto& surface = *static_cast<const PlacedSurface*>(args->geometryUserPtr);
  if (query->skip_cornea && surface.is_cornea()) return;
  RTCRayN* rays = RTCRayHitN_RayN(args->rayhit, args->N);
  RTCHitN* hits = RTCRayHitN_HitN(args->rayhit, args->N);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    Lane& lane = query->lanes[RTCRayN_id(rays, args->N, i)];
    double t;
    Point3 local_point;
    if (!surface.hit(lane, t, local_point)) continue;
    lane.t_hi = t;
    lane.surface = &surface;
    lane.mesh = nullptr;
    lane.local_point = local_point;
    RTCRayN_tfar(rays, args->N, i) = embree_far(t - lane.t_shift);
    RTCHitN_geomID(hits, args->N, i) = args->geomID;
    RTCHitN_primID(hits, args->N, i) = args->primID;
    RTCHitN_instID(hits, args->N, i, 0) = query->embree.instID[0];
    RTCHitN_Ng_x(hits, args->N, i) = 0.0f;
    RTCHitN_Ng_y(hits, args->N, i) = 0.0f;
    RTCHitN_Ng_z(hits, args->N, i) = 0.0f;
    RTCHitN_u(hits, args->N, i) = 0.0f;
    RTCHitN_v(hits, args->N, i) = 0.0f;
  }
}

void occluded_callback(const RTCOccludedFunctionNArguments* args) {
  auto* query = reinterpret_cast<Query*>(args->context);
  const auto& surface = *static_cast<const PlacedSurface*>(args->geometryUserPtr);
  if (query->skip_cornea && surface.is_cornea()) return;
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    Lane& lane = query->lanes[RTCRayN_id(args->ray, args->N, i)];
    if (lane.found()) continue;
    double t;
    Point3 local_point;
    if (!surface.hit(lane, t, local_point)) continue;
    lane.surface = &surface;
    RTCRayN_tfar(args->ray, args->N, i) = -INFINITY;  // Embree's "occluded"
  }
}

// A mesh triangle that Embree's float test hit: kept when the double hit
// is nearer than the closest so far (see the file's comment).
void mesh_intersect_filter(const RTCFilterFunctionNArguments* args) {
  const auto* query = reinterpret_cast<const Query*>(args->context);
  const auto& mesh = *static_cast<const PlacedMesh*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    Lane& lane = query->lanes[RTCRayN_id(args->ray, args->N, i)];
    const unsigned triangle = RTCHitN_primID(args->hit, args->N, i);
    double t;
    if (!mesh.hit(lane, triangle, t)) {
      args->valid[i] = 0;
      continue;
    }
    lane.t_hi = t;
    lane.surface = nullptr;
    lane.mesh = &mesh;
    lane.triangle = triangle;
    RTCRayN_tfar(args->ray, args->N, i) = embree_far(t - lane.t_shift);
  }
}

void mesh_occluded_filter(const RTCFilterFunctionNArguments* args) {
  const auto* query = reinterpret_cast<const Query*>(args->context);
  const auto& mesh = *static_cast<const PlacedMesh*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    Lane& lane = query->lanes[RTCRayN_id(args->ray, args->N, i)];
    double t;
    if (lane.found() || !mesh.hit(lane, RTCHitN_primID(args->hit, args->N, i), t)) {
      args->valid[i] = 0;
      continue;
    }
    lane.mesh = &mesh;  // Embree ends the query on an accepted hit
  }
}

// Clips the ray's [t0, t1] to a box; false when they do not meet.
bool clip_to_box(const Box& box, const Point3& o, const Vector3& d, double& t0, double& t1) {
  for (int axis = 0; axis < 3; ++axis) {
    const double lo = box.lo[axis], hi = box.hi[axis], oa = o[axis], da = d[axis];
    // Parallel to the slab for any distance that matters (and 1 / da would
    // overflow below this).
    if (!(std::abs(da) > 1e-300)) {
      if (oa < lo || oa > hi) return false;
      continue;
    }
    // One division per axis, not two: a ray's clip is on every query's path.
    const double inverse = 1.0 / da;
    double ta = (lo - oa) * inverse, tb = (hi - oa) * inverse;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

std::string eye_label(int index, const EyeModel& m) {
  return "RayTracer: eyes[" + std::to_string(index) + "] (" + m.name + ")";
}

[[noreturn]] void fail_eye(int index, const EyeModel& m, const std::string& what) {
  throw std::invalid_argument(eye_label(index, m) + ": " + what);
}

std::string number(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

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
      fail("vertex " + std::to_string(i) + " (" + number(p.x) + ", " + number(p.y) + ", " + number(p.z) +
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

using SurfaceList = std::vector<std::unique_ptr<PlacedSurface>>;

template <class Shape>
void add(SurfaceList& list, Surface kind, int eye, const std::shared_ptr<const Frame>& frame,
         Shape shape) {
  list.push_back(std::make_unique<Placed<Shape>>(kind, eye, frame, std::move(shape)));
}

void add_eyeball(SurfaceList& list, int index, const Eye& eye) {
  const EyeModel& m = eye.model();
  const auto world_from_eye = std::make_shared<const Frame>(eye.world_from_eye());
  const double R = m.anterior_cornea.radius_mm;
  const double d_L = m.limbus_depth_mm();
  const double r_L = m.limbus_radius_mm;
  if (!(R > 0) || !std::isfinite(R)) fail_eye(index, m, "anterior radius_mm = " + number(R) + ": must be > 0");
  if (!(r_L > 0) || !(d_L > 0) || !std::isfinite(d_L)) {
    fail_eye(index, m, "limbus_radius_mm = " + number(r_L) +
                           ": the anterior cornea does not reach a limbus of that radius");
  }
  const double z_L = R - d_L;
  add(list, Surface::cornea_anterior, index, world_from_eye,
      surfaces::ConicoidCap{R, 1.0 + m.anterior_cornea.asphericity, R, d_L});

  if (m.posterior_cornea) {
    const PosteriorCornea& p = *m.posterior_cornea;
    const double depth = d_L - p.thickness_mm;
    if (!(depth > 0) || !(p.surface.radius_mm > 0)) {
      fail_eye(index, m, "posterior cornea (thickness_mm = " + number(p.thickness_mm) +
                             ", radius_mm = " + number(p.surface.radius_mm) +
                             ") must have a positive radius and start in front of the limbus plane (" +
                             number(d_L) + " mm deep)");
    }
    add(list, Surface::cornea_posterior, index, world_from_eye,
        surfaces::ConicoidCap{p.surface.radius_mm, 1.0 + p.surface.asphericity,
                              R - p.thickness_mm, depth});
  }

  // Sclera and the limbal band between it and the cornea's edge.
  const double R_s = m.sclera_radius_mm;
  const double z_c = R - m.rotation_center_depth_mm;
  const double h = z_L - z_c;  // height of the limbus plane above the centre of rotation
  if (!(R_s > 0) || !(h > 0)) {
    fail_eye(index, m, "sclera_radius_mm = " + number(R_s) + " and rotation_center_depth_mm = " +
                           number(m.rotation_center_depth_mm) +
                           ": the sclera must have a positive radius and the limbus plane must lie "
                           "in front of the centre of rotation");
  }
  double z_seam;  // the sphere is kept behind this plane
  if (R_s >= r_L && std::sqrt(R_s * R_s - r_L * r_L) < h) {
    z_seam = z_c + std::sqrt(R_s * R_s - r_L * r_L);
    add(list, Surface::sclera, index, world_from_eye, surfaces::Cylinder{r_L, z_seam, z_L});
  } else if (h < R_s) {
    z_seam = z_L;
    const double rho = std::sqrt(R_s * R_s - h * h);
    surfaces::PlaneRegion annulus;
    annulus.z_mm = z_L;
    annulus.outer_radius_mm = std::max(rho, r_L);
    annulus.hole_radius_mm = std::min(rho, r_L);
    add(list, Surface::sclera, index, world_from_eye, std::move(annulus));
  } else {
    fail_eye(index, m, "sclera_radius_mm = " + number(R_s) +
                           " is smaller than the limbus radius and does not reach the limbus plane: "
                           "the sclera cannot be joined to the cornea");
  }
  add(list, Surface::sclera, index, world_from_eye,
      surfaces::SphereBelowPlane{{0, 0, z_c}, R_s, z_seam});

  // Iris and pupil, the iris reaching out to the shell.
  const double z_I = R - m.iris_depth_mm;
  double wall = 0;
  if (z_I <= z_seam) {
    if (std::abs(z_I - z_c) < R_s) wall = std::sqrt(R_s * R_s - (z_I - z_c) * (z_I - z_c));
  } else if (z_I <= z_L) {
    wall = r_L;  // beside the cylindrical band
  }
  const double r_p = m.pupil_radius_mm;
  surfaces::PlaneRegion iris;
  iris.z_mm = z_I;
  iris.outer_radius_mm = std::max(m.iris_radius_mm, wall);
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

void add_lids(SurfaceList& list, int index, const Scene& scene) {
  const Eye& eye = scene.eyes[index];
  const EyeAppearance& look = eye.appearance();
  const Eyelids& lids = *look.eyelids;
  const UnitVector3 z = look.head_forward;
  const auto y = UnitVector3::try_normalize(look.head_up.vector() - z.vector() * dot(look.head_up, z));
  if (!y) fail_eye(index, eye.model(), "appearance head_up is parallel to head_forward");
  const UnitVector3 x = UnitVector3::normalize(cross(*y, z));
  const Pose head_pose(Rotation::from_columns(x, *y, z), eye.rotation_center().from_origin());
  const Pose head_from_world = head_pose.inverse();
  const auto world_from_head = std::make_shared<const Frame>(head_pose);

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
  // The margins follow the eye's vertical rotation (Eyelids in appearance.h).
  for (const auto& [key, gain] : {std::pair{"upper_gain_upgaze", lids.upper_gain_upgaze},
                                  std::pair{"upper_gain_downgaze", lids.upper_gain_downgaze},
                                  std::pair{"lower_gain_upgaze", lids.lower_gain_upgaze},
                                  std::pair{"lower_gain_downgaze", lids.lower_gain_downgaze}}) {
    if (!(gain >= 0 && gain <= 2)) {
      fail_eye(index, eye.model(), std::string("eyelids ") + key + " = " + number(gain) + ": must be in [0, 2]");
    }
  }
  const double elevation = surfaces::eye_elevation_rad(head_from_world * eye.optical_axis().vector());
  const surfaces::MarginTurns turns = surfaces::margin_turns(
      lids.upper_gain_upgaze, lids.upper_gain_downgaze, lids.lower_gain_upgaze, lids.lower_gain_downgaze, elevation);
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
    const Vector3 other = (head_from_world * scene.eyes[j].rotation_center()).from_origin();
    const double gap = other.norm();
    if (!(gap > 1e-9)) continue;  // the same place: nothing to split
    face.cuts.push_back({other / gap, 0.5 * gap + surfaces::kSeamOverlapMm});
  }
  add(list, Surface::skin, index, world_from_head, std::move(face));
}

[[noreturn]] [[gnu::cold]] [[gnu::noinline]] void throw_invalid_ray(const Point3& origin, const Vector3& direction,
                                                                double t_min, double t_max) {
  std::ostringstream msg;
  msg << "RayTracer: invalid ray: origin (" << origin.x << ", " << origin.y << ", " << origin.z << "), direction ("
      << direction.x << ", " << direction.y << ", " << direction.z << "), t_min " << t_min << ", t_max " << t_max
      << ": coordinates must be finite and 0 <= t_min";
  throw std::invalid_argument(msg.str());
}

// On every ray's path: the check inline, the message out of line.
inline void check_ray(const Point3& origin, const Vector3& direction, double t_min, double t_max) {
  if (!origin.is_finite() || !direction.is_finite() || !(t_min >= 0) || std::isnan(t_max)) [[unlikely]] {
    throw_invalid_ray(origin, direction, t_min, t_max);
  }
}

}  // namespace

struct RayTracer::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  SurfaceList surfaces;
  std::vector<std::unique_ptr<PlacedMesh>> meshes;
  Box bounds{{0, 0, 0}, {0, 0, 0}};
  double diagonal = 0;  // of the bounds: no ray from inside stays inside longer
  bool empty = true;
  bool masks = false;
  int packet_width = 4;  // rays per Embree packet: 4, 8 or 16

  std::mutex error_mutex;
  std::string error_message;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  static void on_error(void* user, RTCError code, const char* message) {
    auto* self = static_cast<Impl*>(user);
    const std::lock_guard lock(self->error_mutex);
    self->error_message = message ? message : "error code " + std::to_string(static_cast<int>(code));
  }

  void check(const char* doing) {
    const RTCError code = rtcGetDeviceError(device);
    if (code == RTC_ERROR_NONE) return;
    const std::lock_guard lock(error_mutex);
    throw std::runtime_error(std::string("Embree failed while ") + doing + ": " +
                             (error_message.empty() ? "error code " + std::to_string(static_cast<int>(code))
                                                    : error_message));
  }

  // The lane clipped to the scene's bounds: where its float ray starts
  // (recorded as the lane's t_shift) and Embree's rounded-up tfar; false
  // when the lane misses the bounds.
  bool start_float_ray(Lane& lane, Point3& start, float& tfar) const {
    double t0 = lane.t_lo, t1 = lane.t_hi;
    if (empty) return false;
    // A ray from inside the bounds needs no clip, only an end no nearer
    // than their far side: the clip's three divisions on every shadow ray
    // and gathered ray were 3% of the headset's time.
    const Point3 o = lane.origin + lane.direction * t0;
    if (o.x >= bounds.lo.x && o.y >= bounds.lo.y && o.z >= bounds.lo.z && o.x <= bounds.hi.x &&
        o.y <= bounds.hi.y && o.z <= bounds.hi.z) {
      t1 = std::min(t1, t0 + diagonal);
    } else if (!clip_to_box(bounds, lane.origin, lane.direction, t0, t1)) {
      return false;
    }
    lane.t_shift = t0;
    start = lane.origin + lane.direction * t0;
    tfar = embree_far(t1 - t0);
    return true;
  }

  // Runs the query on `lane`, whose `surface` is left null when nothing is hit.
  template <bool kOcclusion>
  void run(Lane& lane, bool skip_cornea) const {
    Point3 start;
    float tfar = 0;
    if (!start_float_ray(lane, start, tfar)) return;

    Query query;
    rtcInitIntersectContext(&query.embree);
    query.lanes = &lane;
    query.skip_cornea = skip_cornea;

    RTCRayHit rayhit{};  // every field written: Embree is given no uninitialised data
    RTCRay& ray = rayhit.ray;
    ray.org_x = static_cast<float>(start.x);
    ray.org_y = static_cast<float>(start.y);
    ray.org_z = static_cast<float>(start.z);
    ray.tnear = 0.0f;
    ray.dir_x = static_cast<float>(lane.direction.x);
    ray.dir_y = static_cast<float>(lane.direction.y);
    ray.dir_z = static_cast<float>(lane.direction.z);
    ray.time = 0.0f;
    ray.tfar = tfar;
    ray.mask = skip_cornea && masks ? kOtherMask : ~0u;
    ray.id = 0;  // the lane
    ray.flags = 0;
    if constexpr (kOcclusion) {
      rtcOccluded1(scene, &query.embree, &ray);
    } else {
      rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene, &query.embree, &rayhit);
    }
  }

  // run<false> for up to kWidth lanes in one packet (coherent rays, such as
  // neighbouring camera rays, share the traversal). Every lane of the
  // packet is written: Embree's fallback for a width its ISA has no
  // kernel for (rtcIntersect16 without AVX-512) ignores the valid mask
  // and traces any lane with tnear <= tfar, so an unused lane is an empty
  // interval (tfar = -inf) whose id no callback can mistake for a lane.
  template <int kWidth>
  void run_packet(Lane* lanes, std::size_t count) const {
    using Packet = EmbreePacket<kWidth>;
    alignas(64) typename Packet::RayHit rayhit;
    alignas(64) int valid[kWidth];
    bool any = false;
    for (int i = 0; i < kWidth; ++i) {
      Point3 start;
      float tfar = 0;
      Lane* lane = static_cast<std::size_t>(i) < count ? &lanes[i] : nullptr;
      const bool active = lane && lane->t_lo < lane->t_hi && start_float_ray(*lane, start, tfar);
      rayhit.ray.org_x[i] = active ? static_cast<float>(start.x) : 0.0f;
      rayhit.ray.org_y[i] = active ? static_cast<float>(start.y) : 0.0f;
      rayhit.ray.org_z[i] = active ? static_cast<float>(start.z) : 0.0f;
      rayhit.ray.tnear[i] = 0.0f;
      rayhit.ray.dir_x[i] = active ? static_cast<float>(lane->direction.x) : 0.0f;
      rayhit.ray.dir_y[i] = active ? static_cast<float>(lane->direction.y) : 0.0f;
      rayhit.ray.dir_z[i] = active ? static_cast<float>(lane->direction.z) : 1.0f;
      rayhit.ray.time[i] = 0.0f;
      rayhit.ray.tfar[i] = active ? tfar : -INFINITY;
      rayhit.ray.mask[i] = active ? ~0u : 0u;
      rayhit.ray.id[i] = static_cast<unsigned>(i);  // the lane
      rayhit.ray.flags[i] = 0;
      rayhit.hit.Ng_x[i] = rayhit.hit.Ng_y[i] = rayhit.hit.Ng_z[i] = 0.0f;
      rayhit.hit.u[i] = rayhit.hit.v[i] = 0.0f;
      rayhit.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
      rayhit.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
      rayhit.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
      valid[i] = active ? -1 : 0;
      any = any || active;
    }
    if (!any) return;
    Query query;
    rtcInitIntersectContext(&query.embree);
    query.lanes = lanes;
    Packet::intersect(valid, scene, &query.embree, &rayhit);
  }

  // The packets' width: the widest the device traces natively.
  void run_packet(Lane* lanes, std::size_t count) const {
    switch (packet_width) {
      case 16: run_packet<16>(lanes, count); break;
      case 8: run_packet<8>(lanes, count); break;
      default: run_packet<4>(lanes, count); break;
    }
  }

  bool occluded(const Point3& from, const Point3& to, bool skip_cornea) const {
    const Vector3 v = to - from;
    check_ray(from, v, 0, 0);
    check_ray(to, v, 0, 0);
    const double length = v.norm();
    const double eps = 1e-6 * length + 1e-9;
    if (!(length > 2 * eps)) return false;
    Lane lane;
    lane.origin = from;
    lane.direction = v / length;
    lane.t_lo = eps;
    lane.t_hi = length - eps;
    run<true>(lane, skip_cornea);
    return lane.found();
  }

  // One Embree triangle geometry; its filters recompute hits in double.
  void add_mesh(const PlacedMesh& mesh) {
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    check("creating a triangle geometry");
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.vertices().size()));
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.triangles().size()));
    check("allocating a mesh's buffers");
    for (std::size_t i = 0; i < mesh.vertices().size(); ++i) {
      const Point3& p = mesh.vertices()[i];
      vertices[3 * i + 0] = static_cast<float>(p.x);
      vertices[3 * i + 1] = static_cast<float>(p.y);
      vertices[3 * i + 2] = static_cast<float>(p.z);
    }
    for (std::size_t i = 0; i < mesh.triangles().size(); ++i) {
      for (int k = 0; k < 3; ++k) indices[3 * i + k] = mesh.triangles()[i][k];
    }
    rtcSetGeometryUserData(geometry, const_cast<PlacedMesh*>(&mesh));
    rtcSetGeometryIntersectFilterFunction(geometry, &mesh_intersect_filter);
    rtcSetGeometryOccludedFilterFunction(geometry, &mesh_occluded_filter);
    if (masks) rtcSetGeometryMask(geometry, kOtherMask);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene, geometry);
    rtcReleaseGeometry(geometry);
    check("adding a mesh");
  }
};

RayTracer::RayTracer(const Scene& scene) : impl_(std::make_unique<Impl>()) {
  Impl& impl = *impl_;
  for (std::size_t i = 0; i < scene.eyes.size(); ++i) {
    const int index = static_cast<int>(i);
    add_eyeball(impl.surfaces, index, scene.eyes[i]);
    if (scene.eyes[i].appearance().eyelids) add_lids(impl.surfaces, index, scene);
  }
  for (std::size_t i = 0; i < scene.meshes.size(); ++i) {
    check_mesh(static_cast<int>(i), scene.meshes[i]);
    if (scene.meshes[i].triangles.empty()) continue;  // nothing to meet
    impl.meshes.push_back(std::make_unique<PlacedMesh>(static_cast<int>(i), scene.meshes[i]));
  }

  const EmbreeDevice wanted = embree_device();
  impl.device = rtcNewDevice(wanted.config.c_str());
  if (!impl.device) {
    throw std::runtime_error("Embree failed to create a device with configuration \"" + wanted.config +
                             "\" (from " + kEmbreeConfigVariable + "): error code " +
                             std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))));
  }
  rtcSetDeviceErrorFunction(impl.device, &Impl::on_error, &impl);
  impl.packet_width = rtcGetDeviceProperty(impl.device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) ? 16
                      : rtcGetDeviceProperty(impl.device, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED) ? 8
                                                                                                       : 4;
  impl.masks = rtcGetDeviceProperty(impl.device, RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) != 0;
  if (!impl.meshes.empty() &&
      rtcGetDeviceProperty(impl.device, RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED) == 0) {
    throw std::runtime_error(
        "Embree was built without intersection filters, which meshes need (their hits are recomputed in "
        "double precision by a filter)");
  }
  impl.scene = rtcNewScene(impl.device);
  impl.check("creating a scene");
  rtcSetSceneFlags(impl.scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(impl.scene, RTC_BUILD_QUALITY_HIGH);

  Box bounds{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
  for (const auto& surface : impl.surfaces) {
    RTCGeometry geometry = rtcNewGeometry(impl.device, RTC_GEOMETRY_TYPE_USER);
    impl.check("creating a user geometry");
    rtcSetGeometryUserPrimitiveCount(geometry, 1);
    rtcSetGeometryUserData(geometry, surface.get());
    rtcSetGeometryBoundsFunction(geometry, &bounds_callback, nullptr);
    rtcSetGeometryIntersectFunction(geometry, &intersect_callback);
    rtcSetGeometryOccludedFunction(geometry, &occluded_callback);
    if (impl.masks) rtcSetGeometryMask(geometry, surface->is_cornea() ? kCorneaMask : kOtherMask);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(impl.scene, geometry);
    rtcReleaseGeometry(geometry);
    impl.check("adding a surface");

    const Box b = surface->world_bounds();
    bounds.lo = {std::min(bounds.lo.x, b.lo.x), std::min(bounds.lo.y, b.lo.y),
                 std::min(bounds.lo.z, b.lo.z)};
    bounds.hi = {std::max(bounds.hi.x, b.hi.x), std::max(bounds.hi.y, b.hi.y),
                 std::max(bounds.hi.z, b.hi.z)};
  }
  for (const auto& mesh : impl.meshes) {
    impl.add_mesh(*mesh);
    const Box b = mesh->world_bounds();
    bounds.lo = {std::min(bounds.lo.x, b.lo.x), std::min(bounds.lo.y, b.lo.y),
                 std::min(bounds.lo.z, b.lo.z)};
    bounds.hi = {std::max(bounds.hi.x, b.hi.x), std::max(bounds.hi.y, b.hi.y),
                 std::max(bounds.hi.z, b.hi.z)};
  }
  rtcCommitScene(impl.scene);
  impl.check("building the scene");
  impl.empty = impl.surfaces.empty() && impl.meshes.empty();
  if (!impl.empty) {
    // A margin more, so that a float ray starting on this box starts
    // clear of every geometry's (padded) bounds.
    const Vector3 pad{1e-3, 1e-3, 1e-3};
    impl.bounds = {bounds.lo - pad, bounds.hi + pad};
    impl.diagonal = (impl.bounds.hi - impl.bounds.lo).norm();
  }
}

RayTracer::~RayTracer() = default;

int RayTracer::packet_width() const { return impl_->packet_width; }

namespace {

Lane lane_of(const Ray& ray) {
  Lane lane;
  lane.origin = ray.origin;
  lane.direction = ray.direction;
  lane.t_lo = ray.t_min;
  lane.t_hi = ray.t_max;
  return lane;
}

Hit hit_of(const Ray& ray, const Lane& lane) {
  Hit hit;
  if (!lane.found()) return hit;
  if (lane.mesh) {
    hit.surface = Surface::mesh;
    hit.mesh = lane.mesh->index();
    hit.triangle = static_cast<int>(lane.triangle);
    hit.normal = lane.mesh->normal(lane.triangle);
  } else {
    hit.surface = lane.surface->kind();
    hit.eye = lane.surface->eye();
    hit.normal = lane.surface->world_normal(lane.local_point);
  }
  hit.t = lane.t_hi;
  hit.point = ray.origin + ray.direction * lane.t_hi;
  hit.front_face = dot(ray.direction, hit.normal) < 0;
  return hit;
}

}  // namespace

Hit RayTracer::intersect(const Ray& ray) const {
  check_ray(ray.origin, ray.direction, ray.t_min, ray.t_max);
  if (!(ray.t_min < ray.t_max)) return {};
  Lane lane = lane_of(ray);
  impl_->run<false>(lane, false);
  return hit_of(ray, lane);
}

void RayTracer::intersect(std::span<const Ray> rays, std::span<Hit> hits) const {
  if (rays.size() != hits.size()) {
    throw std::invalid_argument("RayTracer::intersect: " + std::to_string(rays.size()) + " rays but room for " +
                                std::to_string(hits.size()) + " hits");
  }
  for (const Ray& ray : rays) check_ray(ray.origin, ray.direction, ray.t_min, ray.t_max);
  constexpr std::size_t kMaxPacket = 16, kMinPacket = 4;
  const auto width = static_cast<std::size_t>(impl_->packet_width);
  for (std::size_t first = 0; first < rays.size(); first += width) {
    const std::size_t count = std::min(width, rays.size() - first);
    // Only the lanes in use are constructed: a packet of 7 (a refined
    // pixel's rays) need not initialise 16.
    static_assert(std::is_trivially_destructible_v<Lane>);
    alignas(Lane) unsigned char storage[kMaxPacket * sizeof(Lane)];
    Lane* lanes = reinterpret_cast<Lane*>(storage);
    for (std::size_t i = 0; i < count; ++i) new (&lanes[i]) Lane(lane_of(rays[first + i]));
    if (count < kMinPacket) {
      // A packet this thin costs more than its rays one by one.
      for (std::size_t i = 0; i < count; ++i) {
        if (rays[first + i].t_min < rays[first + i].t_max) impl_->run<false>(lanes[i], false);
      }
    } else {
      impl_->run_packet(lanes, count);
    }
    for (std::size_t i = 0; i < count; ++i) hits[first + i] = hit_of(rays[first + i], lanes[i]);
  }
}

bool RayTracer::occluded(const Point3& from, const Point3& to) const {
  return impl_->occluded(from, to, false);
}

bool RayTracer::occluded_except_cornea(const Point3& from, const Point3& to) const {
  return impl_->occluded(from, to, true);
}

}  // namespace purkinje::renderer
