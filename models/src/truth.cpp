#include "purkinje/models/truth.h"

#include <cmath>

namespace purkinje {
namespace {

constexpr double kTwoPi = 6.28318530717958647692;

// The camera's view of a path's surface point: its pixel (left as it is
// when the path has no point or the point is behind the camera) and the
// path's status, which for an ok path becomes the projection's verdict.
PathStatus image_of(PathStatus path, const Point3& point, const Camera& camera, Pixel& pixel) {
  if (path != PathStatus::ok && path != PathStatus::off_cornea) return path;
  const Projection p = camera.project(point);
  if (p.status != ProjectionStatus::behind_camera) pixel = p.pixel;
  if (path == PathStatus::off_cornea) return path;
  switch (p.status) {
    case ProjectionStatus::ok: return PathStatus::ok;
    case ProjectionStatus::behind_camera: return PathStatus::behind_camera;
    case ProjectionStatus::outside_image: return PathStatus::outside_image;
  }
  return PathStatus::no_solution;
}

}  // namespace

const char* to_string(Occluder o) {
  switch (o) {
    case Occluder::none: return "none";
    case Occluder::skin: return "skin";
    case Occluder::lash: return "lash";
    case Occluder::mesh: return "mesh";
    case Occluder::eye: return "eye";
  }
  return "unknown";
}

const char* to_string(DistractorKind kind) {
  switch (kind) {
    case DistractorKind::sclera: return "sclera";
    case DistractorKind::tear_meniscus: return "tear_meniscus";
  }
  return "unknown";
}

DistractorTruth distractor_truth(DistractorKind kind, const Reflection& highlight, const Scene& scene,
                                 const Eye& eye, int light, const Camera& camera, const TruthOptions& options) {
  DistractorTruth d;
  d.kind = kind;
  d.illuminator = light;
  d.reflection = highlight;
  d.status = image_of(highlight.status, highlight.point, camera, d.pixel);
  if (d.status == PathStatus::ok) {
    // The cornea stands out of the sclera's sphere: it can hide a
    // highlight near the limbus. What the camera sees in front of the
    // highlight comes first, then what shadows it (as for glints).
    const auto blocker = [&](const Point3& end) {
      if (eye.cap_crosses(highlight.point, end)) return Occluder::eye;
      return options.occluded ? options.occluded(highlight.point, end) : Occluder::none;
    };
    d.occluder = blocker(camera.center());
    if (d.occluder == Occluder::none) d.occluder = blocker(scene.illuminators.at(light).position);
    if (d.occluder != Occluder::none) d.status = PathStatus::occluded;
  }
  return d;
}

RefractedImage image_through_cornea(const Eye& eye, const Camera& camera, const Point3& inner) {
  RefractedImage out;
  out.path = solve_refraction(eye, inner, camera.center());
  out.status = image_of(out.path.status, out.path.anterior_point, camera, out.pixel);
  return out;
}

SceneTruth compute_truth(const Scene& scene, const TruthOptions& options) {
  SceneTruth truth;
  for (const Eye& eye : scene.eyes) {
    EyeTruth e;
    e.cornea_center = eye.cornea_center();
    e.rotation_center = eye.rotation_center();
    e.pupil_center = eye.pupil_center();
    e.optical_axis = eye.optical_axis();
    e.visual_axis = eye.visual_axis();
    e.cornea_radius_mm = eye.model().anterior_cornea.radius_mm;
    e.pupil_radius_mm = eye.model().pupil_radius_mm;
    truth.eyes.push_back(e);
  }
  for (int c = 0; c < static_cast<int>(scene.cameras.size()); ++c) {
    const Camera& camera = scene.cameras[c];
    for (int e = 0; e < static_cast<int>(scene.eyes.size()); ++e) {
      const Eye& eye = scene.eyes[e];
      EyeInCameraTruth view;
      view.camera = c;
      view.eye = e;
      for (int l = 0; l < static_cast<int>(scene.illuminators.size()); ++l) {
        GlintTruth g;
        g.illuminator = l;
        g.reflection = solve_reflection(eye, scene.illuminators[l].position, camera.center());
        g.status = image_of(g.reflection.status, g.reflection.point, camera, g.pixel);
        if (g.status == PathStatus::ok && options.occluded) {
          g.occluder = options.occluded(g.reflection.point, camera.center());
          if (g.occluder == Occluder::none) g.occluder = options.occluded(g.reflection.point, scene.illuminators[l].position);
          if (g.occluder != Occluder::none) g.status = PathStatus::occluded;
        }
        view.glints.push_back(g);
      }
      if (eye.appearance().tear_film) {
        for (int l = 0; l < static_cast<int>(scene.illuminators.size()); ++l) {
          const Reflection r = solve_scleral_reflection(eye, scene.illuminators[l].position, camera.center());
          if (r.status != PathStatus::ok) continue;
          view.distractors.push_back(distractor_truth(DistractorKind::sclera, r, scene, eye, l, camera, options));
        }
      }
      std::vector<Pixel> ok_pixels, visible_pixels;
      for (int k = 0; k < options.pupil_border_points; ++k) {
        PupilBorderPointTruth b;
        b.angle_rad = kTwoPi * k / options.pupil_border_points;
        b.border_point = eye.pupil_border_point(b.angle_rad);
        const RefractedImage img = image_through_cornea(eye, camera, b.border_point);
        b.status = img.status;
        b.pixel = img.pixel;
        b.refraction = img.path;
        if (b.status == PathStatus::ok) {
          ok_pixels.push_back(b.pixel);
          if (options.occluded) b.occluder = options.occluded(b.refraction.anterior_point, camera.center());
          if (b.occluder != Occluder::none) {
            b.status = PathStatus::occluded;
          } else {
            visible_pixels.push_back(b.pixel);
          }
        }
        view.pupil.border.push_back(b);
      }
      if (auto ellipse = fit_ellipse(ok_pixels)) {
        view.pupil.ellipse_valid = true;
        view.pupil.ellipse = *ellipse;
      }
      if (visible_pixels.size() == ok_pixels.size()) {
        // Nothing hidden: the same points, the same fit.
        view.pupil.visible_ellipse_valid = view.pupil.ellipse_valid;
        view.pupil.visible_ellipse = view.pupil.ellipse;
      } else if (auto ellipse = fit_ellipse(visible_pixels)) {
        view.pupil.visible_ellipse_valid = true;
        view.pupil.visible_ellipse = *ellipse;
      }
      const RefractedImage centre = image_through_cornea(eye, camera, eye.pupil_center());
      view.pupil.refracted_center_status = centre.status;
      if (centre.status == PathStatus::ok && options.occluded) {
        view.pupil.refracted_center_occluder = options.occluded(centre.path.anterior_point, camera.center());
        if (view.pupil.refracted_center_occluder != Occluder::none) {
          view.pupil.refracted_center_status = PathStatus::occluded;
        }
      }
      view.pupil.refracted_center = centre.pixel;
      view.pupil.refracted_center_path = centre.path;
      view.pupil.unrefracted_center = camera.project(eye.pupil_center());
      view.cornea_center = camera.project(eye.cornea_center());
      view.rotation_center = camera.project(eye.rotation_center());
      truth.views.push_back(std::move(view));
    }
  }
  return truth;
}

}  // namespace purkinje
