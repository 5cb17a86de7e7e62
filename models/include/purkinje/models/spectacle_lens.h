#pragma once
// A spectacle lens: glass between two spherical surfaces, cut to an
// elliptical outline (the frame's opening). Every spectacle lens is a
// meniscus (Tscherning's best forms): both surfaces bulge away from the
// eye, so both centres of curvature lie on the eye's side, a minus lens's
// back surface being the steeper. Plain data; the specular-path solver
// finds paths through it and mirrored by it (specular.h), the renderer
// refracts rays through it.

#include <array>
#include <string>

#include "purkinje/models/geometry.h"
#include "purkinje/models/rotation.h"

namespace purkinje {

struct Scene;

struct SpectacleLens {
  std::string name;
  // Lens frame: origin at the front surface's vertex (the optical centre),
  // +z along the optical axis out of the front (away from the eye), +x
  // along the outline's first semi-axis.
  Pose world_from_lens;
  // Radii of curvature, mm, both centres on the eye's side (-z): the front
  // surface's at z = -front_radius_mm, the back's at
  // z = -center_thickness_mm - back_radius_mm.
  double front_radius_mm = 100;
  double back_radius_mm = 100;
  double center_thickness_mm = 2;
  double refractive_index = 1.498;  // CR-39 near 850 nm
  // The outline's semi-axes along lens x and y, measured perpendicular to
  // the axis; the lens's edge is the elliptic cylinder through it.
  std::array<double, 2> outline_semi_axes_mm{25, 20};
};

enum class LensSurface { front, back };
const char* to_string(LensSurface s);

// Surface powers in dioptres (light travelling from the front to the
// back, as a prescription is written): F1 = (n - 1) / R1, F2 = (1 - n) / R2,
// and the back vertex power F1 / (1 - t F1 / n) + F2, the prescription's
// sphere.
double front_surface_power_d(const SpectacleLens& lens);
double back_vertex_power_d(const SpectacleLens& lens);
// The back radius that gives a back vertex power with this front radius,
// thickness and index (throws std::invalid_argument when none does: the
// back surface would have to bulge toward the eye).
double back_radius_for_power_mm(double back_vertex_power_d, double front_radius_mm, double center_thickness_mm,
                                double refractive_index);

// The lens's thickness along the axis direction at lens-frame (x, y), mm:
// negative where the two surfaces have crossed, NaN beyond either sphere.
double lens_thickness_mm(const SpectacleLens& lens, double x_mm, double y_mm);

// Throws std::invalid_argument naming the rule: radii in (0, 1e5] mm
// (a flat surface is a large radius), thickness in (0, 30] mm, index in
// (1, 3], semi-axes in (0, 60] mm and smaller than either radius, and an
// edge at least 0.1 mm thick all round the outline.
void check_spectacle_lens(const SpectacleLens& lens);

// Throws std::invalid_argument naming the rule when scene.spectacle_lenses
// [index] is placed where its optics do not hold: no eye's cornea (its
// apex) and no camera or illuminator may lie in its glass. Overlapping
// lenses are not checked.
void check_spectacle_lens_placement(const Scene& scene, int index);

// Which side of the lens a lens-frame point lies on: in front of its
// front surface (higher z than the front cap there; beyond the cap's
// reach, than its centre plane), behind its back surface (likewise), or
// between them (in the glass when inside the outline).
enum class LensSide { in_front, between, behind };
LensSide lens_side(const SpectacleLens& lens, const Point3& lens_point);

// Whether a lens-frame point lies within the outline's cylinder.
bool inside_outline(const SpectacleLens& lens, const Point3& lens_point);

// Whether the straight segment between two world points crosses either of
// the lens's surfaces inside its outline.
bool segment_crosses_lens(const SpectacleLens& lens, const Point3& a, const Point3& b);

}  // namespace purkinje
