// Eye-model presets. Every value, its source and the conversions to 850 nm
// are listed in docs/eye-models.md; keep the two in step.

#include <numbers>
#include <optional>
#include <string>

#include "purkinje/models/eye.h"

namespace purkinje {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

// The anatomy outside the cornea is shared by all presets, so switching
// preset changes the corneal optics (and kappa, see below) and nothing else.
EyeModel shared_anatomy() {
  EyeModel m;
  // White-to-white (horizontal visible iris diameter) about 11.8 mm.
  m.limbus_radius_mm = 5.9;
  // The iris rests on the anterior lens surface: 0.55 + 3.05 mm in both
  // Le Grand's and Navarro's eyes.
  m.iris_depth_mm = 3.6;
  // Not 5.9: in the two-surface eyes the posterior cornea (R 6.5 mm, apex at
  // 0.55 mm) is only 5.509 mm from the axis at the iris depth, and a larger
  // iris would poke through it into the corneal stroma. Seen through the
  // cornea the 5.5 mm iris looks about as large as the limbus.
  m.iris_radius_mm = 5.5;
  m.pupil_radius_mm = 2.0;  // 4 mm pupil, a typical indoor (mesopic) size
  m.rotation_center_depth_mm = 13.5;
  m.sclera_radius_mm = 12.0;  // globe of about 24 mm axial length
  return m;
}

// Visual axis about 5 deg nasal and 1.5 deg up of the optical axis. Eye +x
// is nasal for a right eye facing the camera; negate the horizontal angle
// for a left eye.
void set_typical_kappa(EyeModel& m) {
  m.kappa_horizontal_rad = 5.0 * kDegree;
  m.kappa_vertical_rad = 1.5 * kDegree;
}

}  // namespace

EyeModel keratometric_eye() {
  EyeModel m = shared_anatomy();
  m.name = "keratometric";
  m.anterior_cornea = Conicoid{7.8, 0.0};
  m.posterior_cornea.reset();
  // A conventional index that turns the anterior radius into the whole
  // cornea's power (337.5 / R); it models no tissue, so it has no dispersion.
  m.aqueous_index = 1.3375;
  // The reference eye of model-based trackers: optical and visual axes agree.
  m.kappa_horizontal_rad = 0.0;
  m.kappa_vertical_rad = 0.0;
  return m;
}

EyeModel le_grand_eye() {
  EyeModel m = shared_anatomy();
  m.name = "le_grand";
  m.anterior_cornea = Conicoid{7.8, 0.0};
  // Le Grand's published indices (visible light), kept as published so the
  // preset matches other software; docs/eye-models.md gives the 850 nm ones.
  m.posterior_cornea = PosteriorCornea{Conicoid{6.5, 0.0}, 0.55, 1.3771};
  m.aqueous_index = 1.3374;
  set_typical_kappa(m);
  return m;
}

EyeModel navarro_eye() {
  EyeModel m = shared_anatomy();
  m.name = "navarro";
  m.anterior_cornea = Conicoid{7.72, -0.26};
  // Indices at 850 nm from Navarro's dispersion formula (Navarro et al.
  // 1985, as used by Escudero-Sanz and Navarro 1999); 1.376 / 1.3374 at
  // 589.3 nm.
  m.posterior_cornea = PosteriorCornea{Conicoid{6.5, 0.0}, 0.55, 1.3700};
  m.aqueous_index = 1.3311;
  set_typical_kappa(m);
  return m;
}

namespace {

struct Preset {
  const char* name;
  EyeModel (*make)();
};
constexpr Preset kPresets[] = {{"keratometric", keratometric_eye}, {"le_grand", le_grand_eye}, {"navarro", navarro_eye}};

}  // namespace

std::optional<EyeModel> eye_model_preset(const std::string& name) {
  for (const Preset& p : kPresets) {
    if (name == p.name) return p.make();
  }
  return std::nullopt;
}

const std::vector<std::string>& eye_model_preset_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const Preset& p : kPresets) out.emplace_back(p.name);
    return out;
  }();
  return names;
}

}  // namespace purkinje
