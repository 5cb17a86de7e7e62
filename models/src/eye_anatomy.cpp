// The anatomy rules of an eye model (eye.h: anatomy_problem), one place for
// the scene reader and for eyes built in code, which the renderer checks
// before building their surfaces.

#include <cmath>
#include <optional>
#include <string>

#include "purkinje/models/check.h"
#include "purkinje/models/eye.h"

namespace purkinje {
namespace {

using check::format_number;

// Depth below the apex of a conicoid at distance r from its axis; nullopt
// where the surface does not reach r.
std::optional<double> sag_mm(const Conicoid& s, double r) {
  const double disc = s.radius_mm * s.radius_mm - (1.0 + s.asphericity) * r * r;
  if (disc < 0) return std::nullopt;
  return r * r / (s.radius_mm + std::sqrt(disc));  // cancellation-free root
}

// The largest distance from the axis over which a conicoid stays a
// single-valued graph; infinite for paraboloids and hyperboloids.
double graph_radius_mm(const Conicoid& s) {
  if (s.asphericity <= -1.0) return INFINITY;
  return s.radius_mm / std::sqrt(1.0 + s.asphericity);
}

AnatomyProblem problem(std::string key, double value, std::string rule) {
  return {std::move(key), format_number(value), std::move(rule)};
}

bool positive(double v) { return v > 0 && std::isfinite(v); }

// pupil.decentration_mm as the scene file writes it.
// Appended, not "[" + ...: g++ 12 warns falsely (-Wrestrict, its bug 105329)
// on a string literal plus a std::string.
std::string decentration_text(const EyeModel& m) {
  std::string text = "[";
  text += format_number(m.pupil_decentration_x_mm);
  text += ", ";
  text += format_number(m.pupil_decentration_y_mm);
  text += "]";
  return text;
}

// Sizes that must be positive before any rule between keys means anything
// (the scene reader checks each key as it reads it; these catch models
// built in code).
std::optional<AnatomyProblem> size_problem(const EyeModel& m) {
  const char* const rule = "must be > 0 and finite";
  if (!positive(m.anterior_cornea.radius_mm)) return problem("cornea.radius_mm", m.anterior_cornea.radius_mm, rule);
  if (!(m.anterior_cornea.asphericity >= -1.0)) {
    return problem("cornea.asphericity", m.anterior_cornea.asphericity,
                   "must be >= -1 (hyperboloidal corneas are not modelled)");
  }
  if (!positive(m.limbus_radius_mm)) return problem("cornea.limbus_radius_mm", m.limbus_radius_mm, rule);
  if (m.posterior_cornea) {
    const PosteriorCornea& p = *m.posterior_cornea;
    if (!positive(p.surface.radius_mm)) return problem("posterior_cornea.radius_mm", p.surface.radius_mm, rule);
    if (!(p.surface.asphericity >= -1.0)) {
      return problem("posterior_cornea.asphericity", p.surface.asphericity,
                     "must be >= -1 (hyperboloidal corneas are not modelled)");
    }
    if (!positive(p.thickness_mm)) return problem("posterior_cornea.thickness_mm", p.thickness_mm, rule);
  }
  if (!positive(m.iris_radius_mm)) return problem("iris.radius_mm", m.iris_radius_mm, rule);
  if (!positive(m.iris_depth_mm)) return problem("iris.depth_mm", m.iris_depth_mm, rule);
  if (!(m.pupil_radius_mm >= 0 && std::isfinite(m.pupil_radius_mm))) {
    return problem("pupil.radius_mm", m.pupil_radius_mm, "must be >= 0 and finite");
  }
  if (!std::isfinite(m.pupil_decentration_x_mm) || !std::isfinite(m.pupil_decentration_y_mm)) {
    return AnatomyProblem{"pupil.decentration_mm", decentration_text(m), "must be finite"};
  }
  if (!positive(m.sclera_radius_mm)) return problem("sclera_radius_mm", m.sclera_radius_mm, rule);
  if (!positive(m.rotation_center_depth_mm)) {
    return problem("rotation_center_depth_mm", m.rotation_center_depth_mm, rule);
  }
  return std::nullopt;
}

}  // namespace

std::optional<AnatomyProblem> anatomy_problem(const EyeModel& m) {
  if (auto p = size_problem(m)) return p;
  const double limbus = m.limbus_radius_mm;
  const Conicoid& front = m.anterior_cornea;
  if (!(limbus < graph_radius_mm(front))) {
    return problem("cornea.limbus_radius_mm", limbus,
                   "must be < radius_mm / sqrt(1 + asphericity) = " + format_number(graph_radius_mm(front)) +
                       " mm, where the cornea stops being a single-valued cap");
  }

  // The inner surface of the cornea, as depth below the anterior apex.
  auto inner_depth = [&](double r) -> std::optional<double> {
    if (!m.posterior_cornea) return sag_mm(front, r);
    const auto back = sag_mm(m.posterior_cornea->surface, r);
    if (!back) return std::nullopt;
    return m.posterior_cornea->thickness_mm + *back;
  };

  const double limbus_depth = *sag_mm(front, limbus);
  if (m.posterior_cornea) {
    const PosteriorCornea& p = *m.posterior_cornea;
    if (!(limbus < graph_radius_mm(p.surface))) {
      return problem("posterior_cornea.radius_mm", p.surface.radius_mm,
                     "the posterior cornea must reach the limbus (limbus_radius_mm = " + format_number(limbus) +
                         ") as a single-valued surface");
    }
    // Sampling finely is exact enough here: the two sags are smooth and a
    // crossing that fits between samples would be thinner than a micron.
    constexpr int kSamples = 2000;
    for (int i = 0; i <= kSamples; ++i) {
      const double r = limbus * i / kSamples;
      const double thickness = *inner_depth(r) - *sag_mm(front, r);
      if (!(thickness > 0)) {
        return problem("posterior_cornea.thickness_mm", p.thickness_mm,
                       "the posterior cornea crosses the anterior one " + format_number(r) +
                           " mm from the axis, inside the limbus (" + format_number(limbus) + " mm)");
      }
    }
    // Its apex in front of the limbus plane, or the cap has no depth.
    if (!(p.thickness_mm < limbus_depth)) {
      return problem("posterior_cornea.thickness_mm", p.thickness_mm,
                     "must be < the limbus's depth behind the corneal apex (" + format_number(limbus_depth) +
                         " mm)");
    }
  }

  if (!(m.iris_radius_mm <= limbus)) {
    return problem("iris.radius_mm", m.iris_radius_mm,
                   "must be <= cornea.limbus_radius_mm (" + format_number(limbus) + ")");
  }
  if (!(m.pupil_radius_mm < m.iris_radius_mm)) {
    return problem("pupil.radius_mm", m.pupil_radius_mm,
                   "must be < iris.radius_mm (" + format_number(m.iris_radius_mm) + ")");
  }
  const double decentration = std::hypot(m.pupil_decentration_x_mm, m.pupil_decentration_y_mm);
  const double pupil_edge = m.pupil_radius_mm + decentration;
  if (!(pupil_edge < m.iris_radius_mm)) {
    return AnatomyProblem{"pupil.decentration_mm", decentration_text(m),
                          "moves the pupil's edge to " + format_number(pupil_edge) +
                              " mm from the axis, beyond iris.radius_mm (" + format_number(m.iris_radius_mm) + ")"};
  }
  // The pupil must sit in the aqueous humour, behind the cornea's inner
  // surface, or no refracted path reaches it.
  const auto inner_at_pupil = inner_depth(pupil_edge);
  if (!inner_at_pupil || !(m.iris_depth_mm > *inner_at_pupil)) {
    return problem("iris.depth_mm", m.iris_depth_mm,
                   "puts the pupil's edge (" + format_number(pupil_edge) +
                       " mm from the axis) in front of the cornea's inner surface" +
                       (inner_at_pupil ? " (" + format_number(*inner_at_pupil) + " mm deep there)" : std::string()));
  }
  if (!(m.iris_depth_mm < m.rotation_center_depth_mm)) {
    return problem("iris.depth_mm", m.iris_depth_mm,
                   "must be < rotation_center_depth_mm (" + format_number(m.rotation_center_depth_mm) + ")");
  }
  // A two-surface eye's posterior cornea runs on down to the iris plane
  // (the chamber angle, EyeModel::iris_outer_radius_mm): a single-valued
  // cap there too, within the limbus, so inside the eyeball's shell.
  if (m.posterior_cornea && m.iris_depth_mm > limbus_depth) {
    const Conicoid& back = m.posterior_cornea->surface;
    const double w = m.iris_depth_mm - m.posterior_cornea->thickness_mm;
    const double one_plus_q = 1.0 + back.asphericity;
    if (one_plus_q > 0 && !(w < back.radius_mm / one_plus_q)) {
      return problem("iris.depth_mm", m.iris_depth_mm,
                     "must be < " + format_number(m.posterior_cornea->thickness_mm + back.radius_mm / one_plus_q) +
                         " mm: the posterior cornea runs down to the iris plane and must still be a single-valued "
                         "cap there");
    }
    const double angle_radius = m.iris_outer_radius_mm();
    if (!(angle_radius <= limbus)) {
      return problem("iris.depth_mm", m.iris_depth_mm,
                     "the posterior cornea runs down to the iris plane and would meet it " +
                         format_number(angle_radius) + " mm from the axis, beyond cornea.limbus_radius_mm (" +
                         format_number(limbus) + ")");
    }
  }
  if (!(m.sclera_radius_mm < m.rotation_center_depth_mm)) {
    return problem("sclera_radius_mm", m.sclera_radius_mm,
                   "must be < rotation_center_depth_mm (" + format_number(m.rotation_center_depth_mm) +
                       ") so that the cornea stands out of the sclera");
  }
  // The sclera must reach the limbus plane, or nothing can join the
  // cornea's edge to the eyeball and light would leak into the eye.
  if (!(limbus_depth < m.rotation_center_depth_mm)) {
    return problem("rotation_center_depth_mm", m.rotation_center_depth_mm,
                   "must be > the limbus's depth behind the corneal apex (" + format_number(limbus_depth) + " mm)");
  }
  const double limbus_above_center = m.rotation_center_depth_mm - limbus_depth;
  if (!(limbus_above_center < m.sclera_radius_mm)) {
    return problem("sclera_radius_mm", m.sclera_radius_mm,
                   "must be > " + format_number(limbus_above_center) +
                       " mm, the limbus plane's distance from the centre of rotation, so that the sclera reaches "
                       "the cornea's edge");
  }
  return std::nullopt;
}

}  // namespace purkinje
