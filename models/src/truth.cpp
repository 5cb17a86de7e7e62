#include "purkinje/models/truth.h"

#include <cmath>
#include <vector>

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

Leg leg_to(const Scene& scene, const Point3& from, const Point3& end) {
  Leg out;
  for (int k = 0; k < static_cast<int>(scene.spectacle_lenses.size()); ++k) {
    const SpectacleLens& lens = scene.spectacle_lenses[k];
    if (!segment_crosses_lens(lens, from, end)) continue;
    const LensPassage p = solve_lens_passage(lens, from, end);
    // Ends on one side with the segment grazing through the glass: no path.
    out.status = p.status == PathStatus::invalid_input ? PathStatus::no_solution : p.status;
    out.lens = k;
    if (p.status == PathStatus::ok) out.passage = p;
    return out;
  }
  return out;
}

// A point along the leg's first segment as far from `from` as its end:
// the eye's solver's virtual end.
Point3 aim_of(const Leg& leg, const Point3& from, const Point3& end) {
  return leg.passage ? from + leg.passage->leaving * distance(from, end) : end;
}

// The leg's last corner before its end: where the camera sees what lies
// at `from`.
Point3 last_of(const Leg& leg, const Point3& from) { return leg.passage ? leg.passage->second : from; }

bool path_exists(PathStatus s) { return s == PathStatus::ok || s == PathStatus::off_cornea; }

// The eye's own solver, run with its far ends moved to the legs' aims:
// at its fixed point the path obeys the eye's law with the directions in
// which its legs leave through the lenses, which is the whole path's law.
// A lens a dozen millimetres from the eye turns a leg's direction by about
// 1e-3 of a change in the eye's point, so the iteration contracts fast.
// `solve(light_aim, camera_aim)` returns the eye's path, `point_of` its
// point where the legs start; `light` is absent for a refracted path.
template <class Path, class Solve, class PointOf>
Path through_lenses(const Scene& scene, const Point3* light, const Point3& camera, const Solve& solve,
                    const PointOf& point_of, Leg& camera_leg, Leg& light_leg) {
  const Point3& light_end = light ? *light : camera;
  const auto legs_from = [&](const Path& p) {
    camera_leg = leg_to(scene, point_of(p), camera);
    light_leg = light ? leg_to(scene, point_of(p), *light) : Leg{};
    return camera_leg.status != PathStatus::ok ? camera_leg.status : light_leg.status;
  };
  const auto straight = [&] { return !camera_leg.passage && !light_leg.passage; };
  Path path = solve(light_end, camera);
  camera_leg = light_leg = Leg{};
  if (scene.spectacle_lenses.empty() || !path_exists(path.status)) return path;
  constexpr double kToleranceMm = 1e-11;
  for (int i = 0; i < 100; ++i) {
    if (const PathStatus s = legs_from(path); s != PathStatus::ok) {
      path.status = s;
      return path;
    }
    if (straight()) {
      if (i == 0) return path;  // no lens in the way
      // The iteration left the lens: the straight path (iteration 0's)
      // crosses it and the refracted one misses it, so none exists here
      // (an end seen past the lens's edge).
      path.status = PathStatus::no_solution;
      return path;
    }
    const Point3 point = point_of(path);
    Path next = solve(aim_of(light_leg, point, light_end), aim_of(camera_leg, point, camera));
    if (!path_exists(next.status)) return next;
    const bool converged = distance(point_of(next), point) <= kToleranceMm;
    path = next;
    if (converged) {
      if (const PathStatus s = legs_from(path); s != PathStatus::ok) path.status = s;
      return path;
    }
  }
  path.status = PathStatus::not_converged;
  return path;
}

// What the scene's occlusion finds along a leg from `from` to `end`.
Occluder occluder_along(const TruthOptions& options, const Point3& from, const Leg& leg, const Point3& end) {
  if (!options.occluded) return Occluder::none;
  Point3 a = from;
  if (leg.passage) {
    for (const Point3& b : {leg.passage->first, leg.passage->second}) {
      if (const Occluder o = options.occluded(a, b); o != Occluder::none) return o;
      a = b;
    }
  }
  return options.occluded(a, end);
}

}  // namespace

const char* to_string(Occluder o) {
  switch (o) {
    case Occluder::none: return "none";
    case Occluder::skin: return "skin";
    case Occluder::lash: return "lash";
    case Occluder::brow: return "brow";
    case Occluder::mesh: return "mesh";
    case Occluder::eye: return "eye";
  }
  return "unknown";
}

const char* to_string(DistractorKind kind) {
  switch (kind) {
    case DistractorKind::sclera: return "sclera";
    case DistractorKind::tear_meniscus: return "tear_meniscus";
    case DistractorKind::spectacle_lens_front: return "spectacle_lens_front";
    case DistractorKind::spectacle_lens_back: return "spectacle_lens_back";
    case DistractorKind::upper_tear_meniscus: return "upper_tear_meniscus";
  }
  return "unknown";
}

namespace {

// A highlight as the camera sees it (before occlusion): its pixel and status.
struct SeenReflection {
  SeenHighlight highlight;
  PathStatus status = PathStatus::no_solution;
  Pixel pixel;
};

SeenReflection seen_by(const SeenHighlight& h, const Camera& camera) {
  SeenReflection out;
  out.highlight = h;
  out.status = image_of(h.reflection.status, h.seen_at(), camera, out.pixel);
  return out;
}

DistractorTruth seen_distractor(DistractorKind kind, const SeenReflection& h, const Scene& scene, const Eye& eye,
                                int light, const Camera& camera, const TruthOptions& options) {
  DistractorTruth d;
  d.kind = kind;
  d.illuminator = light;
  d.reflection = h.highlight.reflection;
  d.pixel = h.pixel;
  d.status = h.status;
  if (d.status == PathStatus::ok) {
    // The cornea stands out of the sclera's sphere: it can hide a
    // highlight near the limbus. What the camera sees in front of the
    // highlight comes first, then what shadows it (as for glints).
    const auto blocker = [&](const Leg& leg, const Point3& end) {
      const Point3& first = leg.passage ? leg.passage->first : end;
      if (eye.cap_crosses(d.reflection.point, first)) return Occluder::eye;
      return occluder_along(options, d.reflection.point, leg, end);
    };
    d.occluder = blocker(h.highlight.to_camera, camera.center());
    if (d.occluder == Occluder::none) d.occluder = blocker(h.highlight.to_light, scene.illuminators.at(light).position);
    if (d.occluder != Occluder::none) d.status = PathStatus::occluded;
  }
  return d;
}

}  // namespace

DistractorTruth distractor_truth(DistractorKind kind, const Reflection& highlight, const Scene& scene,
                                 const Eye& eye, int light, const Camera& camera, const TruthOptions& options) {
  SeenHighlight straight;
  straight.reflection = highlight;
  return seen_distractor(kind, seen_by(straight, camera), scene, eye, light, camera, options);
}

DistractorTruth distractor_truth(DistractorKind kind, const SeenHighlight& highlight, const Scene& scene,
                                 const Eye& eye, int light, const Camera& camera, const TruthOptions& options) {
  return seen_distractor(kind, seen_by(highlight, camera), scene, eye, light, camera, options);
}

SeenHighlight see_highlight(const Scene& scene, const Point3& light, const Point3& camera_center, const Mirror& mirror) {
  SeenHighlight out;
  out.reflection = through_lenses<Reflection>(
      scene, &light, camera_center, mirror, [](const Reflection& r) { return r.point; }, out.to_camera, out.to_light);
  return out;
}

namespace {

RefractedImage refracted_image(const Scene& scene, const Eye& eye, const Camera& camera, const Point3& inner,
                               Leg& camera_leg) {
  RefractedImage out;
  Leg no_light;
  out.path = through_lenses<Refraction>(
      scene, nullptr, camera.center(), [&](const Point3&, const Point3& aim) { return solve_refraction(eye, inner, aim); },
      [](const Refraction& r) { return r.anterior_point; }, camera_leg, no_light);
  out.status = image_of(out.path.status, last_of(camera_leg, out.path.anterior_point), camera, out.pixel);
  return out;
}

SeenReflection seen_reflection(const Scene& scene, const Camera& camera, const Point3& light, const Mirror& mirror) {
  return seen_by(see_highlight(scene, light, camera.center(), mirror), camera);
}

// The occluder of a highlight the camera would see: what it sees in front
// of it first, then what shadows it from its light.
Occluder highlight_occluder(const TruthOptions& options, const SeenHighlight& h, const Point3& camera,
                            const Point3& light) {
  const Occluder o = occluder_along(options, h.reflection.point, h.to_camera, camera);
  return o != Occluder::none ? o : occluder_along(options, h.reflection.point, h.to_light, light);
}

// A ghost's label: where the camera sees it, and whether it does.
DistractorTruth ghost_truth(const Scene& scene, int lens, const LensReflection& g, int light, const Camera& camera,
                            const TruthOptions& options) {
  DistractorTruth d;
  d.kind = g.surface == LensSurface::front ? DistractorKind::spectacle_lens_front : DistractorKind::spectacle_lens_back;
  d.illuminator = light;
  d.spectacle_lens = lens;
  d.reflection = g.mirror;
  d.status = image_of(g.status, g.exit, camera, d.pixel);
  if (d.status == PathStatus::ok && options.occluded) {
    const Point3& light_position = scene.illuminators.at(light).position;
    d.occluder = options.occluded(g.exit, camera.center());
    if (d.occluder == Occluder::none) d.occluder = options.occluded(g.entry, light_position);
    if (d.occluder != Occluder::none) d.status = PathStatus::occluded;
  }
  return d;
}

}  // namespace

int eye_behind(const Scene& scene, int lens_index) {
  const SpectacleLens& lens = scene.spectacle_lenses.at(lens_index);
  const Point3 back = lens.world_from_lens * Point3{0, 0, -lens.center_thickness_mm};
  int best = -1;
  double nearest = 0;
  for (int e = 0; e < static_cast<int>(scene.eyes.size()); ++e) {
    const double d = distance(scene.eyes[e].corneal_apex(), back);
    if (best < 0 || d < nearest) {
      best = e;
      nearest = d;
    }
  }
  return best;
}

RefractedImage image_through_cornea(const Eye& eye, const Camera& camera, const Point3& inner) {
  return image_through_cornea(Scene{}, eye, camera, inner);
}

RefractedImage image_through_cornea(const Scene& scene, const Eye& eye, const Camera& camera, const Point3& inner) {
  Leg leg;
  return refracted_image(scene, eye, camera, inner, leg);
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
        const Point3& light = scene.illuminators[l].position;
        const SeenReflection seen = seen_reflection(
            scene, camera, light, [&](const Point3& source, const Point3& target) { return solve_reflection(eye, source, target); });
        GlintTruth g;
        g.illuminator = l;
        g.reflection = seen.highlight.reflection;
        g.pixel = seen.pixel;
        g.status = seen.status;
        if (g.status == PathStatus::ok) {
          g.occluder = highlight_occluder(options, seen.highlight, camera.center(), light);
          if (g.occluder != Occluder::none) g.status = PathStatus::occluded;
        }
        view.glints.push_back(g);
      }
      if (eye.appearance().tear_film) {
        for (int l = 0; l < static_cast<int>(scene.illuminators.size()); ++l) {
          const SeenReflection seen =
              seen_reflection(scene, camera, scene.illuminators[l].position, [&](const Point3& source, const Point3& target) {
                return solve_scleral_reflection(eye, source, target);
              });
          if (seen.highlight.reflection.status != PathStatus::ok) continue;
          view.distractors.push_back(seen_distractor(DistractorKind::sclera, seen, scene, eye, l, camera, options));
        }
      }
      for (int k = 0; k < static_cast<int>(scene.spectacle_lenses.size()); ++k) {
        const SpectacleLens& lens = scene.spectacle_lenses[k];
        if (eye_behind(scene, k) != e) continue;
        for (const LensSurface surface : {LensSurface::front, LensSurface::back}) {
          for (int l = 0; l < static_cast<int>(scene.illuminators.size()); ++l) {
            const LensReflection g = solve_lens_reflection(lens, surface, scene.illuminators[l].position, camera.center());
            if (g.status != PathStatus::ok) continue;
            view.distractors.push_back(ghost_truth(scene, k, g, l, camera, options));
          }
        }
      }
      std::vector<Pixel> ok_pixels, visible_pixels;
      for (int k = 0; k < options.pupil_border_points; ++k) {
        PupilBorderPointTruth b;
        b.angle_rad = kTwoPi * k / options.pupil_border_points;
        b.border_point = eye.pupil_border_point(b.angle_rad);
        Leg leg;
        const RefractedImage img = refracted_image(scene, eye, camera, b.border_point, leg);
        b.status = img.status;
        b.pixel = img.pixel;
        b.refraction = img.path;
        if (b.status == PathStatus::ok) {
          ok_pixels.push_back(b.pixel);
          b.occluder = occluder_along(options, b.refraction.anterior_point, leg, camera.center());
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
      Leg centre_leg;
      const RefractedImage centre = refracted_image(scene, eye, camera, eye.pupil_center(), centre_leg);
      view.pupil.refracted_center_status = centre.status;
      if (centre.status == PathStatus::ok) {
        view.pupil.refracted_center_occluder =
            occluder_along(options, centre.path.anterior_point, centre_leg, camera.center());
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
