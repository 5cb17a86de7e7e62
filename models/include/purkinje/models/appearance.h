#pragma once
// How an eye and its surroundings look under near-infrared light: albedos,
// the procedural iris texture, and the eyelids and skin. Plain
// data; the renderer builds surfaces from it. Albedos are Lambertian
// reflectances at about 850 nm.

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "purkinje/models/geometry.h"

namespace purkinje {

// Eyelids and the skin around them, attached to the head (not to the eye:
// the eye turns behind them). The lids lie on a sphere about the eye's
// centre of rotation; the palpebral opening is bounded by two parabolic
// margins. Heights are measured along the head's up direction from the
// centre of rotation, on the plane facing forward, for the eye in primary
// position (optical axis along head_forward).
//
// The margins follow the eye's vertical rotation, as real lids do (lid-gaze
// coupling). With e the eye's elevation (the angle of its optical axis
// above head_forward in the head's vertical plane, atan2(o . up,
// o . forward): positive up), each margin turns with the lid sphere about
// the head's left-right axis through the centre of rotation by gain * e,
// the gain chosen by the sign of e. Horizontal gaze leaves the margins
// where they are. A gain of 0 keeps a margin fixed to the head. Where the
// turned margins would cross (the upper one turned below the lower one),
// the lids meet and the opening is closed there; each turn is limited to
// +-90 deg.
//
// Default gains, static gaze (fixation), from the literature:
// - Upper lid 1 in both directions: during steady fixation the upper lid
//   and the eye take "essentially equal average positions" (Becker and
//   Fuchs 1988, J Neurophysiol 60:1227-1252, search coils, vertical gaze).
// - Lower lid 0.6 in downgaze: Read et al. 2006 (Optom Vis Sci 83:715-722,
//   76 young adults) measure the vertical palpebral aperture shrinking
//   from 9.7 to 6.4 mm between primary gaze and 40 deg downgaze; with the
//   upper lid following 1:1 and these default margins (a 10 mm aperture),
//   the lower margin must turn by 0.6 of the eye's rotation to leave that
//   aperture seen along the line of sight (0.8 seen from straight ahead).
// - Lower lid 0 in upgaze: the lower lid moves little and mostly in
//   downgaze, pulled by its retractors from the inferior rectus. Leite et
//   al. 2006 (Braz J Med Biol Res 39:1651-1657) measure lower-lid saccades
//   of 2.2 mm against 9.2 mm of the upper lid in the same vertical
//   saccades (young adults): a ratio of 0.24, which, with the 0.6 in
//   downgaze, leaves about 0 for upgaze if the saccades spanned both
//   sides of primary position equally.
struct Eyelids {
  double opening = 1.0;             // 1: margins as given; 0: closed (both at the closing line)
  double upper_margin_mm = 4.5;     // upper lid margin height at the middle, fully open
  double lower_margin_mm = -5.5;    // lower lid margin height at the middle, fully open
  double closing_line_mm = -1.0;    // where the margins meet when closed
  double half_width_mm = 15.0;      // half the width of the opening (the canthi)
  // Margin turn per eye elevation (see above), each in [0, 2].
  double upper_gain_upgaze = 1.0;
  double upper_gain_downgaze = 1.0;
  double lower_gain_upgaze = 0.0;
  double lower_gain_downgaze = 0.6;
};

// Which of a face's eyes this is: it sets which side the nose is on.
enum class EyeSide { right, left };
// As scene files and labels spell it.
constexpr const char* to_string(EyeSide side) { return side == EyeSide::right ? "right" : "left"; }

// Eyelashes along a face's lid margins (docs/scene-format.md: lashes).
// Each lash is a tapering hair rooted on the lid's anterior margin: it
// leaves along the lid's outward normal tipped by root_deg toward the
// opening, then bends away from the opening by curl_deg in all, in the
// plane of that normal and the lid's rise. Lashes are sparser and shorter
// toward the canthi and absent medial to the lacrimal punctum; each is
// jittered in place, length, direction and curl by a stream of `seed`.
// Defaults from textbook anatomy of adult lashes: upper lid 100-150
// lashes of 8-12 mm in 2-3 rows over about 25 mm of margin, rising at
// 110-130 deg from the downward vertical with the eye open; lower lid 50-75
// of 6-8 mm, bent forward and down; shafts about 0.1 mm thick at the root,
// longest at the lid's middle, shortest at the medial canthus. Albedo: a
// guess (no NIR measurement of lashes found): melanin absorbs less at
// 850 nm than in the visible, so dark lashes are not black there; mascara
// (carbon black) darkens them.
struct Lashes {
  double upper_per_mm = 4.5;    // lashes per mm of the upper margin's lashed part
  double lower_per_mm = 3.0;
  double upper_length_mm = 9.5;  // at the middle of the lid; shorter toward the canthi
  double lower_length_mm = 6.5;
  double upper_curl_deg = 45;    // total bend, root to tip, away from the opening
  double lower_curl_deg = 20;
  double root_deg = 20;          // the root's tilt from the lid's normal toward the opening
  double thickness_mm = 0.1;     // diameter at the root; a third of it at the tip
  double albedo = 0.1;
  std::uint64_t seed = 1;
};

// A hair group's number by its name in scene files, with its bounds (as
// FaceKey's).
template <class Hairs>
struct HairKey {
  std::string_view name;
  double Hairs::*member;
  double low;
  double high;
};

// Lashes' numbers by their names in scene files ("lashes": {...}) and, with
// "lash_" before them, in data sets.
using LashKey = HairKey<Lashes>;
inline constexpr std::array<LashKey, 9> kLashKeys{{
    {"upper_per_mm", &Lashes::upper_per_mm, 0, 10},
    {"lower_per_mm", &Lashes::lower_per_mm, 0, 10},
    {"upper_length_mm", &Lashes::upper_length_mm, 1, 15},
    {"lower_length_mm", &Lashes::lower_length_mm, 1, 15},
    // A lash may not turn back toward the eye: with a root tilted 40 (+5)
    // deg toward the opening and no curl its tip still leads away from the
    // cornea.
    {"upper_curl_deg", &Lashes::upper_curl_deg, 0, 120},
    {"lower_curl_deg", &Lashes::lower_curl_deg, 0, 120},
    {"root_deg", &Lashes::root_deg, -45, 40},
    {"thickness_mm", &Lashes::thickness_mm, 0.02, 0.3},
    {"albedo", &Lashes::albedo, 0, 1},
}};

// Eyebrows on a face (docs/scene-format.md: brows): hairs rooted in a band
// on the brow ridge that runs from above the medial canthus (the brow's
// head) to past the lateral canthus (its tail), arching up over its
// lateral half and narrowing toward the tail. They lie nearly flat: each
// leaves the skin lift_deg above it and bends back toward it by curl_deg
// in all, following the skin's curve and lying on it once curled down to
// it; at the head they point up, along the body laterally (the
// band's lower hairs tipped up and its upper ones down, so that they meet
// along its middle), at the tail laterally and down; each is jittered in
// place, length, direction and curl by a stream of `seed`. Defaults from
// adult anthropometry, rounded: a brow's lower edge about 16 mm above the
// pupil at its head, its arch some 2.5 mm higher above the lateral
// limbus, its tail about 14 mm lateral to the lateral canthus; 10 mm tall
// at the head; 250-600 hairs a brow (1.5 per mm^2 here) of 6-10 mm and
// 0.05-0.1 mm thick. Albedo: a guess, as the lashes' (a little lighter:
// brow hairs are finer and less pigmented than lashes).
struct Brows {
  double hairs_per_mm2 = 1.5;
  double height_mm = 16;        // the band's lower edge at its head, above the centre of rotation
  double width_mm = 10;         // the band's height at its head; 0.4 of it at the tail
  double hair_length_mm = 8;
  double thickness_mm = 0.08;   // diameter at the root; a third of it at the tip
  double lift_deg = 20;         // at the root, above the skin
  double curl_deg = 20;         // toward the skin, root to tip (a hair curled down to it lies on it)
  double albedo = 0.15;
  std::uint64_t seed = 1;
};

// Brows' numbers by their names in scene files ("brows": {...}) and, with
// "brows_" before them, in data sets ("brow_" begins a face key).
using BrowKey = HairKey<Brows>;
inline constexpr std::array<BrowKey, 8> kBrowKeys{{
    {"hairs_per_mm2", &Brows::hairs_per_mm2, 0, 6},
    {"height_mm", &Brows::height_mm, 8, 30},
    {"width_mm", &Brows::width_mm, 2, 15},
    {"hair_length_mm", &Brows::hair_length_mm, 2, 15},
    {"thickness_mm", &Brows::thickness_mm, 0.02, 0.2},
    {"lift_deg", &Brows::lift_deg, 5, 60},
    {"curl_deg", &Brows::curl_deg, 0, 60},
    {"albedo", &Brows::albedo, 0, 1},
}};

// The periocular region as a face (docs/scene-format.md: face): in place
// of the lid sphere and the flat wall, the renderer builds a skin surface
// per eye from these numbers and the lids' margins (Eyelids): lids that lie
// on the eye (cornea included, in its current gaze) with a rounded margin
// of real thickness, an upper-lid crease, canthi tied to the head (only
// the margins' middles follow the gaze), a brow ridge, a cheek and the
// side of the nose up to the face's midline, where the other eye's face
// begins. Lengths in the head frame (origin at the centre of rotation,
// forward out of the face, up along the head).
struct Face {
  EyeSide side = EyeSide::right;
  // From the globe to the lid's skin at the margins: the margin's width.
  double margin_thickness_mm = 1.8;
  // Upper-lid crease above the upper margin at the middle (0: no crease),
  // and how deep its fold is.
  double crease_height_mm = 7.0;
  double crease_depth_mm = 0.6;
  // Rise of the line through the canthi toward the lateral canthus.
  double canthal_tilt_deg = 4.0;
  // The lateral canthus's distance from the centre of rotation across the
  // head: the lids meet on the globe there (less than the sclera's
  // radius), while eyelids.half_width_mm places the medial canthus, past
  // the globe, where the socket's floor (the caruncle) fills the opening.
  double lateral_canthus_mm = 11.0;
  // How far the brow ridge stands in front of the corneal apex (primary
  // position); negative: behind it (deep-set brows).
  double brow_prominence_mm = 3.0;
  // From the centre of rotation to the face's midline (half the
  // interpupillary distance): the nose's ridge.
  double midline_mm = 31.5;
  // Absent: no lashes.
  std::optional<Lashes> lashes;
  // Absent: no brows.
  std::optional<Brows> brows;
};

// Face's lengths and angles by their names in scene files and data sets,
// with the bounds a face can have: beyond them its surface folds over
// itself or leaves the grid the renderer builds it on.
// `shared`: both eyes' faces must agree on it (they meet there).
struct FaceKey {
  std::string_view name;
  double Face::*member;
  double low;
  double high;
  bool shared = false;
};
inline constexpr std::array<FaceKey, 7> kFaceKeys{{
    {"margin_thickness_mm", &Face::margin_thickness_mm, 0.5, 4},
    {"crease_height_mm", &Face::crease_height_mm, 0, 15},
    {"crease_depth_mm", &Face::crease_depth_mm, 0, 2},
    {"canthal_tilt_deg", &Face::canthal_tilt_deg, -15, 15},
    {"lateral_canthus_mm", &Face::lateral_canthus_mm, 5, 20},
    {"brow_prominence_mm", &Face::brow_prominence_mm, -8, 12},
    {"midline_mm", &Face::midline_mm, 20, 45, true},
}};

// The tear film over the sclera (docs/scene-format.md: tear film): wet,
// the sclera mirrors each light as a highlight that is no Purkinje image,
// which glint detectors may take for a glint. The film follows the
// sclera's sphere, its facets tilted about the sphere's normal by a
// Gaussian of sclera_roughness_deg along each tangent direction
// (conjunctival folds, vessels and an uneven film): a highlight keeps the
// mirror's power, spread over the sphere where the tilts reach. The
// sclera's albedo stays its diffuse reflectance. The roughness is a guess
// (no measurement of the bulbar conjunctiva's slopes was found): scleral
// highlights in eye-tracker images are larger and softer than glints.
struct TearFilm {
  double sclera_roughness_deg = 2.0;
  // The lower lid's tear meniscus: the concave strip of tears between the
  // lid margin and the globe, a fillet of this radius (0: none). Healthy
  // adults' lower menisci measure 0.31-0.37 mm in radius (Yokoi et al.
  // 1999, Br J Ophthalmol 83:92; UHR-OCT, Biomed Opt Express 10:2744,
  // 2019), dry eyes about 0.25 mm. Rendered for eyes with a face only,
  // as its highlights (docs/rendering.md: tear meniscus).
  double meniscus_radius_mm = 0.3;
  // The upper lid's, the same fillet under its margin (0: none). Smaller
  // than the lower one in healthy eyes (Wang et al. 2009, Invest
  // Ophthalmol Vis Sci 50:2722, by OCT). An ARVO abstract measured the
  // heights by fluorescein, the upper's 0.36 mm against the lower's 0.40
  // in controls: the default scales the lower's radius by that, rounded
  // down (a guess).
  double upper_meniscus_radius_mm = 0.25;
};
// The tear film's refractive index in the near infrared, for its Fresnel
// reflectance: tears measure 1.3370 at 589 nm (Craig, Simmons, Patel and
// Tomlinson 1995, Optom Vis Sci 72:718-724); water falls from 1.333 to
// 1.329 between 589 and 850 nm (Hale and Querry 1973), and so, taken
// alike, do tears.
inline constexpr double kTearFilmIndex = 1.333;

struct EyeAppearance {
  double iris_albedo = 0.25;           // mean of the textured iris
  double iris_texture_contrast = 0.5;  // 0: flat iris; 1: albedo varies by about +-100% of the mean
  std::uint64_t iris_seed = 1;         // the procedural texture's seed
  // The iris's variety beyond its fibres, crypts and collarette, seeded by
  // iris_seed (docs/scene-format.md: appearance): contraction furrows,
  // broken dark rings over its outer third (0: none; 1: 0.8 of the mean
  // darker at their middles), and this many pigment spots (iris
  // freckles, 0 to 20). Both darken the iris by the area they cover.
  double iris_furrow_contrast = 0.0;
  int iris_freckles = 0;
  double sclera_albedo = 0.55;
  double skin_albedo = 0.45;
  // Low-contrast albedo textures, seeded by iris_seed (the eye's texture
  // seed): the skin's fine wrinkles, pores and blotches, the sclera's
  // faint vessels. 0: uniform; up to 1 (docs/scene-format.md:
  // appearance). Near-infrared skin shows little detail, and vessels
  // little contrast.
  double skin_texture_contrast = 0.0;
  double sclera_vessel_contrast = 0.0;
  // Bright pupil: fraction of the light entering the pupil that the fundus
  // sends back toward its source (retro-reflection); 0 keeps the pupil dark.
  double fundus_reflectance = 0.05;
  // Head frame (world): the eyelids' opening faces `head_forward`; its
  // margins are stacked along `head_up`.
  UnitVector3 head_forward = -UnitVector3::unit_z();
  UnitVector3 head_up = -UnitVector3::unit_y();
  // Absent: no lids and no skin; the eye floats on a black background.
  std::optional<Eyelids> eyelids;
  // Absent: the lids lie on a sphere in a flat wall (Eyelids); present
  // (with eyelids only): the periocular face above.
  std::optional<Face> face;
  // Absent: a dry sclera, Lambertian only; present: it mirrors the lights too.
  std::optional<TearFilm> tear_film;
};

}  // namespace purkinje
