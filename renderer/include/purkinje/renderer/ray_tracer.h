#pragma once
// The one Embree adapter: the scene's surfaces as exact analytic shapes
// (Embree user geometry), intersected in double precision inside the
// callbacks. No Embree type appears here, so an Embree 4 port touches
// ray_tracer.cpp only.
//
// Surfaces built per eye: the anterior cornea (the conicoid cap inside the
// limbus), the posterior cornea (two-surface eyes), the iris (an annulus in
// the iris plane reaching out to the sclera), the pupil (the disc in the
// iris plane: whatever is seen through it), the sclera (the sphere about the
// centre of rotation, outside the limbus, with a short limbal band closing
// the gap to the cornea's edge) and, when the eye has eyelids, the lids
// (a sphere about the centre of rotation, minus the palpebral opening) and
// the skin around them (a plane facing forward with a hole for the lids,
// and the rest of the lid sphere behind it as the eye's socket), or the
// face's mesh in their place with its lashes and brows (chains of
// capsules, one user primitive each, also intersected in double precision). Each of
// the scene's meshes is an Embree triangle geometry whose hits are
// recomputed in double precision from the mesh's own vertices.
// Geometry is documented in src/scene_geometry.h, precision in
// src/ray_tracer.cpp.

#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "purkinje/models/geometry.h"
#include "purkinje/models/scene.h"

namespace purkinje::renderer {

enum class Surface : unsigned char {
  none = 0,  // the ray left the scene
  skin,      // eyelids and the skin around them
  sclera,
  iris,
  pupil,
  cornea_anterior,
  cornea_posterior,
  mesh,      // a triangle of one of the scene's meshes
  lash,      // one of an eye's eyelashes
  brow,      // a hair of one of an eye's brows
  spectacle_lens,  // a surface of one of the scene's spectacle lenses (front, back or edge)
};
const char* to_string(Surface s);

struct Ray {
  Point3 origin;
  UnitVector3 direction = UnitVector3::unit_z();
  double t_min = 0;
  double t_max = std::numeric_limits<double>::infinity();
};

struct Hit {
  Surface surface = Surface::none;
  int eye = -1;             // index into scene.eyes (-1 for Surface::mesh)
  int mesh = -1;            // index into scene.meshes (Surface::mesh only)
  int lens = -1;            // index into scene.spectacle_lenses (Surface::spectacle_lens only)
  int triangle = -1;        // index into that mesh's (or face's) triangles, or the hairs' capsules
  double t = 0;             // distance along the ray, mm
  Point3 point;             // world, recomputed in double precision
  // Outward: out of the eye; toward the front for skin and iris; for a
  // mesh, the triangle's front, (v1 - v0) x (v2 - v0); out of a hair; out
  // of a spectacle lens's glass.
  UnitVector3 normal = UnitVector3::unit_z();
  bool front_face = true;   // the ray meets the side `normal` points to
};

// Embree picks its kernels (SSE2 to AVX-512) at run time. Every device
// purkinje creates takes its configuration from this environment variable,
// in Embree's syntax: comma-separated key=value pairs, e.g. "isa=avx2" or
// "isa=sse4.2,threads=1" (docs/rendering.md). Images are the same under
// every ISA, byte for byte: the callbacks decide every hit in double.
inline constexpr const char* kEmbreeConfigVariable = "PURKINJE_EMBREE_CONFIG";

struct EmbreeDevice {
  std::string config;  // passed to Embree, checked
  std::string isa;     // its kernels: sse2, sse4.2, avx, avx2 or avx512
};
// The best of Embree's instruction sets this CPU runs.
std::string cpu_isa();
// The configuration in kEmbreeConfigVariable, checked against Embree's
// documented keys, its instruction sets and this CPU (Embree itself accepts
// an unknown key silently and runs an unknown isa as SSE2). Throws
// std::invalid_argument naming the variable, its value and the rule.
EmbreeDevice embree_device();
// The same for a given configuration and CPU instruction set (cpu_isa()).
EmbreeDevice embree_device(std::string_view config, std::string_view cpu_isa);

class RayTracer;

// The hairs' shadows toward one point, a light: occluded_by_hair(from,
// light) for any `from`, with the same answers, from a map of the
// directions out of the light that each hair's capsule covers (a central
// projection onto a plane facing the hairs). Every point of a shadow ray
// lies on one such direction, so a ray through an empty cell of the map
// meets no hair and tests none, and one through a full cell tests that
// cell's few capsules rather than traversing a tree: shadow rays against
// the hairs were 29% of the time of a headset with lashes. Made by
// RayTracer::hair_shadows(); valid while its tracer lives.
class HairShadows {
 public:
  // Throws std::invalid_argument for a non-finite point.
  bool occluded(const Point3& from) const;
  // Whether the map answers (else every query asks the tracer): false
  // without hairs, or where some hair lies more than 78 degrees off the
  // plane's normal (a light among the hairs or beside them).
  bool mapped() const { return mapped_; }

 private:
  friend class RayTracer;
  HairShadows(const RayTracer* tracer, const Point3& light) : tracer_(tracer), light_(light) {}
  // Where a capsule lands on the plane: within `reach` of its axis's image,
  // the segment from (au, av) to (bu, bv).
  struct Footprint {
    double au, av, bu, bv, reach;
    std::uint32_t group, segment;  // which hairs (an eye's lashes, its brows) and which capsule of them
    // Whether (u, v) lies within reach + pad of the axis's image.
    bool covers(double u, double v, double pad) const;
  };
  const RayTracer* tracer_ = nullptr;
  Point3 light_;
  bool mapped_ = false;  // mapped()
  Vector3 ex_, ey_, ez_;  // the plane's axes and its normal, away from the light
  double u0_ = 0, v0_ = 0, inverse_cell_ = 0;
  std::size_t columns_ = 0, rows_ = 0;
  std::vector<Footprint> footprints_;  // every capsule's
  std::vector<std::uint32_t> first_;  // [cell]: where its entries start; one more than cells
  std::vector<std::uint32_t> footprint_of_entry_;  // the cells' capsules, cell by cell
};

class RayTracer {
 public:
  // Throws std::runtime_error on an Embree error, std::invalid_argument
  // for a bad kEmbreeConfigVariable (see embree_device()) or (naming eyes[i] or meshes[i]) for an eye whose surfaces cannot be built
  // or sealed, or a mesh with an index out of range or a non-finite vertex.
  explicit RayTracer(const Scene& scene);
  ~RayTracer();
  RayTracer(const RayTracer&) = delete;
  RayTracer& operator=(const RayTracer&) = delete;

  // The closest hit with t_min < t < t_max. Throws std::invalid_argument
  // for a non-finite origin or t_min < 0; an empty interval hits nothing.
  Hit intersect(const Ray& ray) const;
  // The closest hit of each ray, as intersect(ray) finds it, traced in
  // packets of packet_width(): cheaper for coherent rays such as
  // neighbouring camera rays. `hits` must be as long as `rays`.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits) const;
  // The widest packet the device's ISA traces natively: 16 with AVX-512,
  // 8 with AVX or AVX2, 4 with SSE (wider packets would run Embree's slower
  // stream fallback).
  int packet_width() const;
  // Whether any surface (meshes included) lies on the open segment between
  // two points (both ends trimmed by 1e-6 of the length + 1e-9 mm, so a
  // segment may start or end on a surface). The cornea counts: light does
  // not pass it without refracting. Spectacle lenses never count: what
  // they do to light on its way is the caller's (a light seen through one
  // is its image, materials.h). Throws std::invalid_argument for
  // non-finite points.
  bool occluded(const Point3& from, const Point3& to) const;
  // As occluded(), ignoring the anterior and posterior cornea (for a path
  // whose refraction the caller handles, e.g. from a light to the cornea).
  bool occluded_except_cornea(const Point3& from, const Point3& to) const;
  // What occluded_except_cornea() finds, nearest `to`: Surface::none when
  // nothing blocks the segment.
  Surface occluder_except_cornea(const Point3& from, const Point3& to) const;

  // Hairs (lashes and brows): thin and many, they are left to the samples
  // by the fast mode's screen-space caches, which interpolate the rest.
  bool has_hair() const;
  // As intersect() and occluded(), ignoring the hairs.
  Hit intersect_except_hair(const Ray& ray) const;
  bool occluded_except_hair(const Point3& from, const Point3& to) const;
  // Whether a hair lies on the segment (as occluded() trims it), tested
  // against the hairs alone.
  bool occluded_by_hair(const Point3& from, const Point3& to) const;
  // occluded_by_hair(from, light) for many `from`, faster (HairShadows).
  // Throws std::invalid_argument for a non-finite light.
  HairShadows hair_shadows(const Point3& light) const;

 private:
  friend class HairShadows;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace purkinje::renderer
