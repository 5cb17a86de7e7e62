#pragma once
// How an eye and its surroundings look under near-infrared light: albedos,
// the procedural iris texture, and the head-fixed eyelids and skin. Plain
// data; the renderer builds surfaces from it. Albedos are Lambertian
// reflectances at about 850 nm.

#include <cstdint>
#include <optional>

#include "purkinje/models/geometry.h"

namespace purkinje {

// Eyelids and the skin around them, fixed to the head (not to the eye: the
// eye turns behind them). The lids lie on a sphere about the eye's centre
// of rotation; the palpebral opening is bounded by two parabolic margins.
// Heights are measured along the head's up direction from the centre of
// rotation, on the plane facing forward.
struct Eyelids {
  double opening = 1.0;             // 1: margins as given; 0: closed (both at the closing line)
  double upper_margin_mm = 4.5;     // upper lid margin height at the middle, fully open
  double lower_margin_mm = -5.5;    // lower lid margin height at the middle, fully open
  double closing_line_mm = -1.0;    // where the margins meet when closed
  double half_width_mm = 15.0;      // half the width of the opening (the canthi)
};

struct EyeAppearance {
  double iris_albedo = 0.25;           // mean of the textured iris
  double iris_texture_contrast = 0.5;  // 0: flat iris; 1: albedo varies by about +-100% of the mean
  std::uint64_t iris_seed = 1;         // the procedural texture's seed
  double sclera_albedo = 0.55;
  double skin_albedo = 0.45;
  // Bright pupil: fraction of the light entering the pupil that the fundus
  // sends back toward its source (retro-reflection); 0 keeps the pupil dark.
  double fundus_reflectance = 0.05;
  // Head frame (world): the eyelids' opening faces `head_forward`; its
  // margins are stacked along `head_up`.
  UnitVector3 head_forward = -UnitVector3::unit_z();
  UnitVector3 head_up = -UnitVector3::unit_y();
  // Absent: no lids and no skin; the eye floats on a black background.
  std::optional<Eyelids> eyelids;
};

}  // namespace purkinje
