// The one Embree adapter (Embree 3): every surface of the eyes is an Embree
// user geometry with one primitive, whose callbacks intersect the exact
// analytic shape of surfaces.h in double precision; every mesh is an
// Embree triangle geometry whose hits are recomputed in double precision.
//
// The shapes and their placement: scene_geometry.h, built Embree-free.
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
// Spectacle lenses the same, skipped by every occlusion query.
//
// Hairs (lashes and brows): one user primitive per capsule, intersected in
// double precision like the eyes' surfaces (not Embree's curves, which are
// intersected in float by kernels that differ between instruction sets).
// They have their own mask bit and flag (queries that look through them),
// and sit in a second scene of their own too (occluded_by_hair: a shadow
// ray tested against the hairs alone traverses only their tree). Toward a
// light, HairShadows answers the same without Embree: a light's map of
// the directions each capsule covers, then the capsules' own test.

#include "purkinje/renderer/ray_tracer.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <mutex>
#include <new>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "purkinje/models/check.h"
#include "scene_geometry.h"

namespace purkinje::renderer {


namespace {

constexpr unsigned kCorneaMask = 1u;
constexpr unsigned kOtherMask = 2u;
constexpr unsigned kHairMask = 4u;
constexpr unsigned kLensMask = 8u;

// Which surfaces a query skips.
struct Skip {
  bool cornea = false;
  bool hair = false;
  bool lenses = false;
};

// Embree hands the context pointer back to the callbacks, so extending it
// carries the double rays to them (the Embree 3 idiom; Embree 4 keeps it
// as RTCRayQueryContext).
struct Query {
  RTCIntersectContext embree;
  Lane* lanes = nullptr;
  Skip skip;
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

// A double box as Embree's float bounds, rounded outward.
void set_bounds(const Box& b, RTCBounds* out) {
  out->lower_x = std::nextafter(static_cast<float>(b.lo.x), -INFINITY);
  out->lower_y = std::nextafter(static_cast<float>(b.lo.y), -INFINITY);
  out->lower_z = std::nextafter(static_cast<float>(b.lo.z), -INFINITY);
  out->upper_x = std::nextafter(static_cast<float>(b.hi.x), INFINITY);
  out->upper_y = std::nextafter(static_cast<float>(b.hi.y), INFINITY);
  out->upper_z = std::nextafter(static_cast<float>(b.hi.z), INFINITY);
}

// What a user callback's hit tells Embree: which primitive, and nothing of
// the float hit (the lane holds the double one).
void set_hit(RTCHitN* hits, unsigned n, unsigned i, unsigned geometry, unsigned primitive, unsigned instance) {
  RTCHitN_geomID(hits, n, i) = geometry;
  RTCHitN_primID(hits, n, i) = primitive;
  RTCHitN_instID(hits, n, i, 0) = instance;
  RTCHitN_Ng_x(hits, n, i) = 0.0f;
  RTCHitN_Ng_y(hits, n, i) = 0.0f;
  RTCHitN_Ng_z(hits, n, i) = 0.0f;
  RTCHitN_u(hits, n, i) = 0.0f;
  RTCHitN_v(hits, n, i) = 0.0f;
}

void bounds_callback(const RTCBoundsFunctionArguments* args) {
  set_bounds(static_cast<const PlacedSurface*>(args->geometryUserPtr)->world_bounds(), args->bounds_o);
}

// Whether the query looks through this surface (without ray masks, the
// callbacks' own test).
bool skipped(const Skip& skip, const PlacedSurface& surface) {
  return (skip.cornea && surface.is_cornea()) || (skip.lenses && surface.kind() == Surface::spectacle_lens);
}

void intersect_callback(const RTCIntersectFunctionNArguments* args) {
  auto* query = reinterpret_cast<Query*>(args->context);
  const auto& surface = *static_cast<const PlacedSurface*>(args->geometryUserPtr);
  if (skipped(query->skip, surface)) return;
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
    lane.hairs = nullptr;
    lane.local_point.value = local_point;
    RTCRayN_tfar(rays, args->N, i) = embree_far(t - lane.t_shift);
    set_hit(hits, args->N, i, args->geomID, args->primID, query->embree.instID[0]);
  }
}

void occluded_callback(const RTCOccludedFunctionNArguments* args) {
  auto* query = reinterpret_cast<Query*>(args->context);
  const auto& surface = *static_cast<const PlacedSurface*>(args->geometryUserPtr);
  if (skipped(query->skip, surface)) return;
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
    lane.hairs = nullptr;
    lane.primitive = triangle;
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

// An eye's lashes or brows: one user primitive per capsule, as the surfaces'
// callbacks but indexed by primID.
void hair_bounds_callback(const RTCBoundsFunctionArguments* args) {
  set_bounds(static_cast<const PlacedHairs*>(args->geometryUserPtr)->bounds(args->primID), args->bounds_o);
}

void hair_intersect_callback(const RTCIntersectFunctionNArguments* args) {
  auto* query = reinterpret_cast<Query*>(args->context);
  if (query->skip.hair) return;
  const auto& hairs = *static_cast<const PlacedHairs*>(args->geometryUserPtr);
  RTCRayN* rays = RTCRayHitN_RayN(args->rayhit, args->N);
  RTCHitN* hits = RTCRayHitN_HitN(args->rayhit, args->N);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    Lane& lane = query->lanes[RTCRayN_id(rays, args->N, i)];
    double t;
    if (!hairs.hit(lane, args->primID, t)) continue;
    lane.t_hi = t;
    lane.surface = nullptr;
    lane.mesh = nullptr;
    lane.hairs = &hairs;
    lane.primitive = args->primID;
    RTCRayN_tfar(rays, args->N, i) = embree_far(t - lane.t_shift);
    set_hit(hits, args->N, i, args->geomID, args->primID, query->embree.instID[0]);
  }
}

void hair_occluded_callback(const RTCOccludedFunctionNArguments* args) {
  auto* query = reinterpret_cast<Query*>(args->context);
  if (query->skip.hair) return;
  const auto& hairs = *static_cast<const PlacedHairs*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    Lane& lane = query->lanes[RTCRayN_id(args->ray, args->N, i)];
    if (lane.found()) continue;
    double t;
    if (!hairs.hit(lane, args->primID, t)) continue;
    lane.hairs = &hairs;
    lane.primitive = args->primID;
    RTCRayN_tfar(args->ray, args->N, i) = -INFINITY;  // Embree's "occluded"
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

[[noreturn]] [[gnu::cold]] [[gnu::noinline]] void throw_invalid_ray(const Point3& origin, const Vector3& direction,
                                                                double t_min, double t_max) {
  using check::format_number;
  throw std::invalid_argument("RayTracer: invalid ray: origin (" + format_number(origin.x) + ", " +
                              format_number(origin.y) + ", " + format_number(origin.z) + "), direction (" +
                              format_number(direction.x) + ", " + format_number(direction.y) + ", " +
                              format_number(direction.z) + "), t_min " + format_number(t_min) + ", t_max " +
                              format_number(t_max) + ": coordinates must be finite and 0 <= t_min");
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
  RTCScene hair_scene = nullptr;  // the lashes and brows alone (occluded_by_hair); none without
  std::vector<Box> hair_bounds;  // of each group of hairs (an eye's lashes, its brows), padded
  SurfaceList surfaces;
  std::vector<std::unique_ptr<PlacedMesh>> meshes;
  std::vector<std::unique_ptr<PlacedHairs>> hairs;
  Box bounds{{0, 0, 0}, {0, 0, 0}};
  double diagonal = 0;  // of the bounds: no ray from inside stays inside longer
  bool empty = true;
  bool masks = false;
  int packet_width = 4;  // rays per Embree packet: 4, 8 or 16

  std::mutex error_mutex;
  std::string error_message;

  ~Impl() {
    if (hair_scene) rtcReleaseScene(hair_scene);
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
  // On `in`, the whole scene unless given (the hairs' own scene).
  void run(Lane& lane, Skip skip, RTCScene in = nullptr) const {
    Point3 start;
    float tfar = 0;
    if (!start_float_ray(lane, start, tfar)) return;

    Query query;
    rtcInitIntersectContext(&query.embree);
    query.lanes = &lane;
    query.skip = skip;

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
    ray.mask = ~0u;
    if (masks && skip.cornea) ray.mask &= ~kCorneaMask;
    if (masks && skip.hair) ray.mask &= ~kHairMask;
    if (masks && skip.lenses) ray.mask &= ~kLensMask;
    ray.id = 0;  // the lane
    ray.flags = 0;
    if constexpr (kOcclusion) {
      rtcOccluded1(in ? in : scene, &query.embree, &ray);
    } else {
      rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(in ? in : scene, &query.embree, &rayhit);
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

  // The segment's lane, both ends trimmed (see occluded()); false for a
  // segment too short to hold anything.
  static bool segment_lane(const Point3& from, const Point3& to, Lane& lane) {
    const Vector3 v = to - from;
    check_ray(from, v, 0, 0);
    check_ray(to, v, 0, 0);
    const double length = v.norm();
    const double eps = 1e-6 * length + 1e-9;
    if (!(length > 2 * eps)) return false;
    lane.origin = from;
    lane.direction = v / length;
    lane.t_lo = eps;
    lane.t_hi = length - eps;
    return true;
  }

  // Spectacle lenses never occlude (RayTracer::occluded).
  bool occluded(const Point3& from, const Point3& to, Skip skip, RTCScene in = nullptr) const {
    Lane lane;
    if (!segment_lane(from, to, lane)) return false;
    skip.lenses = true;
    run<true>(lane, skip, in);
    return lane.found();
  }

  // The closest hit from `to` back toward `from`.
  Surface occluder(const Point3& from, const Point3& to, Skip skip) const {
    Lane lane;
    if (!segment_lane(to, from, lane)) return Surface::none;
    skip.lenses = true;
    run<false>(lane, skip);
    return lane.surface ? lane.surface->kind() : lane.mesh ? lane.mesh->kind() : lane.hairs ? lane.hairs->kind() : Surface::none;
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
  SceneGeometry geometry = build_scene_geometry(scene);
  impl.surfaces = std::move(geometry.surfaces);
  impl.meshes = std::move(geometry.meshes);
  impl.hairs = std::move(geometry.hairs);

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
    if (impl.masks) {
      rtcSetGeometryMask(geometry, surface->is_cornea()                           ? kCorneaMask
                                   : surface->kind() == Surface::spectacle_lens ? kLensMask
                                                                                : kOtherMask);
    }
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(impl.scene, geometry);
    rtcReleaseGeometry(geometry);
    impl.check("adding a surface");

    const Box b = surface->world_bounds();
    bounds = united(bounds, b);
  }
  for (const auto& mesh : impl.meshes) {
    impl.add_mesh(*mesh);
    const Box b = mesh->world_bounds();
    bounds = united(bounds, b);
  }
  if (!impl.hairs.empty()) {
    impl.hair_scene = rtcNewScene(impl.device);
    impl.check("creating the hairs' scene");
    rtcSetSceneFlags(impl.hair_scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(impl.hair_scene, RTC_BUILD_QUALITY_HIGH);
  }
  for (const auto& hairs : impl.hairs) {
    // In the whole scene and in the hairs' own (a geometry can be
    // attached to one scene only: two geometries share the capsules).
    for (RTCScene in : {impl.scene, impl.hair_scene}) {
      RTCGeometry geometry = rtcNewGeometry(impl.device, RTC_GEOMETRY_TYPE_USER);
      impl.check("creating a user geometry");
      rtcSetGeometryUserPrimitiveCount(geometry, static_cast<unsigned>(hairs->segments().size()));
      rtcSetGeometryUserData(geometry, hairs.get());
      rtcSetGeometryBoundsFunction(geometry, &hair_bounds_callback, nullptr);
      rtcSetGeometryIntersectFunction(geometry, &hair_intersect_callback);
      rtcSetGeometryOccludedFunction(geometry, &hair_occluded_callback);
      if (impl.masks) rtcSetGeometryMask(geometry, kHairMask);
      rtcCommitGeometry(geometry);
      rtcAttachGeometry(in, geometry);
      rtcReleaseGeometry(geometry);
      impl.check("adding hairs");
    }
    impl.hair_bounds.push_back(hairs->world_bounds());
    bounds = united(bounds, impl.hair_bounds.back());
  }
  rtcCommitScene(impl.scene);
  impl.check("building the scene");
  if (impl.hair_scene) {
    rtcCommitScene(impl.hair_scene);
    impl.check("building the hairs' scene");
  }
  impl.empty = impl.surfaces.empty() && impl.meshes.empty() && impl.hairs.empty();
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

Hit RayTracer::intersect(const Ray& ray) const {
  check_ray(ray.origin, ray.direction, ray.t_min, ray.t_max);
  if (!(ray.t_min < ray.t_max)) return {};
  Lane lane = lane_of(ray);
  impl_->run<false>(lane, {});
  Hit hit;
  hit_of(ray, lane, hit);
  return hit;
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
        if (rays[first + i].t_min < rays[first + i].t_max) impl_->run<false>(lanes[i], {});
      }
    } else {
      impl_->run_packet(lanes, count);
    }
    for (std::size_t i = 0; i < count; ++i) hit_of(rays[first + i], lanes[i], hits[first + i]);
  }
}

bool RayTracer::occluded(const Point3& from, const Point3& to) const {
  return impl_->occluded(from, to, {});
}

bool RayTracer::occluded_except_cornea(const Point3& from, const Point3& to) const {
  return impl_->occluded(from, to, {.cornea = true});
}

Surface RayTracer::occluder_except_cornea(const Point3& from, const Point3& to) const {
  return impl_->occluder(from, to, {.cornea = true});
}

bool RayTracer::has_hair() const { return impl_->hair_scene != nullptr; }

Hit RayTracer::intersect_except_hair(const Ray& ray) const {
  check_ray(ray.origin, ray.direction, ray.t_min, ray.t_max);
  if (!(ray.t_min < ray.t_max)) return {};
  Lane lane = lane_of(ray);
  impl_->run<false>(lane, {.hair = true});
  Hit hit;
  hit_of(ray, lane, hit);
  return hit;
}

bool RayTracer::occluded_except_hair(const Point3& from, const Point3& to) const {
  return impl_->occluded(from, to, {.hair = true});
}

bool RayTracer::occluded_by_hair(const Point3& from, const Point3& to) const {
  check_ray(from, to - from, 0, 0);
  check_ray(to, to - from, 0, 0);
  // Box tests first: cheaper than Embree's query for a shadow ray that
  // passes the hairs by (a group's box each: an eye's lashes and its brows
  // lie apart).
  if (!impl_->hair_scene) return false;
  const bool near = std::any_of(impl_->hair_bounds.begin(), impl_->hair_bounds.end(), [&](const Box& box) {
    double t0 = 0, t1 = 1;
    return clip_to_box(box, from, to - from, t0, t1);
  });
  return near && impl_->occluded(from, to, {}, impl_->hair_scene);
}

bool HairShadows::Footprint::covers(double u, double v, double pad) const {
  const double dx = bu - au, dy = bv - av, px = u - au, py = v - av;
  const double length2 = dx * dx + dy * dy;
  const double h = length2 > 0 ? std::clamp((px * dx + py * dy) / length2, 0.0, 1.0) : 0.0;
  const double ex = px - h * dx, ey = py - h * dy, r = reach + pad;
  return ex * ex + ey * ey <= r * r;
}

// The map. A capsule with axis a-b and radius r projects (w = (x / z, y / z)
// in the light's frame, z along the plane's normal) into the points within
// `reach` of the segment from w(a) to w(b): lines project to lines, and
// w's derivative is at most sqrt(1 + |w|^2) / z, so a point r from the
// axis lands at most r sqrt(1 + |w|^2) / z from the axis's image, with z
// and |w| bounded over the capsule's box by its corners (the box projects
// to the hull of its corners' images). Each cell lists the capsules whose
// reach, padded by half the cell's diagonal, covers its centre.
HairShadows RayTracer::hair_shadows(const Point3& light) const {
  check_ray(light, Vector3{0, 0, 0}, 0, 0);
  HairShadows map(this, light);
  const auto& hairs = impl_->hairs;
  if (hairs.empty()) return map;
  Box all = impl_->hair_bounds.front();
  for (const Box& b : impl_->hair_bounds) all = united(all, b);
  const auto axis = UnitVector3::try_normalize((all.lo - light) * 0.5 + (all.hi - light) * 0.5);
  if (!axis) return map;
  const Vector3 ez = *axis;
  const auto [ex, ey] = perpendiculars(*axis);

  std::vector<HairShadows::Footprint>& footprints = map.footprints_;
  double u_lo = INFINITY, u_hi = -INFINITY, v_lo = INFINITY, v_hi = -INFINITY;
  for (std::size_t g = 0; g < hairs.size(); ++g) {
    const std::vector<HairSegment>& segments = hairs[g]->segments();
    for (std::size_t i = 0; i < segments.size(); ++i) {
      const Box box = hairs[g]->bounds(static_cast<unsigned>(i));
      double z_min = INFINITY, w2_max = 0;
      for (int corner = 0; corner < 8; ++corner) {
        const Point3 c{corner & 1 ? box.hi.x : box.lo.x, corner & 2 ? box.hi.y : box.lo.y,
                       corner & 4 ? box.hi.z : box.lo.z};
        const Vector3 d = c - light;
        const double z = dot(d, ez);
        // Within about 78 degrees of the normal, or no map: a light among
        // the hairs or beside them, which no one plane in front of it shows
        // well.
        if (!(z > 0.2 * d.norm())) return map;
        const double u = dot(d, ex) / z, v = dot(d, ey) / z;
        z_min = std::min(z_min, z);
        w2_max = std::max(w2_max, u * u + v * v);
      }
      const HairSegment& c = segments[i];
      const Vector3 a = c.a - light, b = c.b - light;
      const double reach = c.radius_mm * std::sqrt(1 + w2_max) / z_min;
      const HairShadows::Footprint f{dot(a, ex) / dot(a, ez),    dot(a, ey) / dot(a, ez),
                                     dot(b, ex) / dot(b, ez),    dot(b, ey) / dot(b, ez),
                                     reach * (1 + 1e-6) + 1e-9, static_cast<std::uint32_t>(g),
                                     static_cast<std::uint32_t>(i)};
      u_lo = std::min({u_lo, f.au - f.reach, f.bu - f.reach});
      u_hi = std::max({u_hi, f.au + f.reach, f.bu + f.reach});
      v_lo = std::min({v_lo, f.av - f.reach, f.bv - f.reach});
      v_hi = std::max({v_hi, f.av + f.reach, f.bv + f.reach});
      footprints.push_back(f);
    }
  }
  // Square cells, 256 along the longer side.
  constexpr double kCellsAcross = 256;
  const double cell = std::max(u_hi - u_lo, v_hi - v_lo) / kCellsAcross;
  if (!(cell > 0)) return map;
  map.ex_ = ex;
  map.ey_ = ey;
  map.ez_ = ez;
  map.u0_ = u_lo;
  map.v0_ = v_lo;
  map.inverse_cell_ = 1 / cell;
  map.columns_ = static_cast<std::size_t>(std::ceil((u_hi - u_lo) / cell)) + 1;
  map.rows_ = static_cast<std::size_t>(std::ceil((v_hi - v_lo) / cell)) + 1;
  const double half_diagonal = cell * std::numbers::sqrt2 / 2;
  // Twice over the capsules' cells: counting, then filling.
  map.first_.assign(map.columns_ * map.rows_ + 1, 0);
  const auto each_cell = [&](const HairShadows::Footprint& f, const auto& visit) {
    // A cell wider on each side: the queries round their own way.
    const auto index = [&](double w, double w0, std::size_t n) {
      return std::min(static_cast<std::size_t>(std::max(0.0, (w - w0) / cell)), n - 1);
    };
    const std::size_t c0 = index(std::min(f.au, f.bu) - f.reach - cell, u_lo, map.columns_);
    const std::size_t c1 = index(std::max(f.au, f.bu) + f.reach + cell, u_lo, map.columns_);
    const std::size_t r0 = index(std::min(f.av, f.bv) - f.reach - cell, v_lo, map.rows_);
    const std::size_t r1 = index(std::max(f.av, f.bv) + f.reach + cell, v_lo, map.rows_);
    for (std::size_t r = r0; r <= r1; ++r) {
      for (std::size_t col = c0; col <= c1; ++col) {
        const double u = u_lo + (static_cast<double>(col) + 0.5) * cell;
        const double v = v_lo + (static_cast<double>(r) + 0.5) * cell;
        if (f.covers(u, v, half_diagonal)) visit(r * map.columns_ + col);
      }
    }
  };
  for (const HairShadows::Footprint& f : footprints) each_cell(f, [&](std::size_t c) { ++map.first_[c + 1]; });
  for (std::size_t c = 0; c + 1 < map.first_.size(); ++c) map.first_[c + 1] += map.first_[c];
  map.footprint_of_entry_.resize(map.first_.back());
  std::vector<std::uint32_t> next(map.first_.begin(), map.first_.end() - 1);
  for (std::size_t k = 0; k < footprints.size(); ++k) {
    each_cell(footprints[k], [&](std::size_t c) { map.footprint_of_entry_[next[c]++] = static_cast<std::uint32_t>(k); });
  }
  map.mapped_ = true;
  return map;
}

bool HairShadows::occluded(const Point3& from) const {
  // Every point of the segment to the light projects where `from` does; one
  // behind the light's plane meets no hair (all lie in front).
  const Vector3 d = from - light_;
  if (!mapped_ || !d.is_finite()) return tracer_->occluded_by_hair(from, light_);  // which checks the points
  const double z = dot(d, ez_);
  if (!(z > 0)) return false;
  const double u = dot(d, ex_) / z, v = dot(d, ey_) / z;
  const double column = (u - u0_) * inverse_cell_, row = (v - v0_) * inverse_cell_;
  if (!(column >= 0 && row >= 0 && column < static_cast<double>(columns_) && row < static_cast<double>(rows_))) {
    return false;
  }
  const std::size_t cell = static_cast<std::size_t>(row) * columns_ + static_cast<std::size_t>(column);
  const std::uint32_t begin = first_[cell], end = first_[cell + 1];
  if (begin == end) return false;
  Lane lane;
  if (!RayTracer::Impl::segment_lane(from, light_, lane)) return false;
  const auto& hairs = tracer_->impl_->hairs;
  for (std::uint32_t i = begin; i < end; ++i) {
    // The footprint first (a few multiplications): most of a cell's
    // capsules pass the ray by.
    const Footprint& f = footprints_[footprint_of_entry_[i]];
    double t;
    if (f.covers(u, v, 0) && hairs[f.group]->hit(lane, f.segment, t)) return true;
  }
  return false;
}

}  // namespace purkinje::renderer
