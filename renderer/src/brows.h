#pragma once
// An eye's brows (Brows in appearance.h) as hairs of capsules (internal to
// renderer/), rooted on the face mesh: built per scene with the face.
// Their draws come from streams the lashes never use (lashes.h: 2 eye and
// 2 eye + 1), so that brows and lashes of one seed do not repeat each
// other's numbers.
//
// The band, in the head frame's nasal coordinate n and height y: from its
// head above the medial canthus (n = eyelids.half_width_mm) to its tail
// 14 mm past the lateral canthus (n = -lateral_canthus_mm - 14), at
// fraction s of the way its lower edge at height_mm + 2.5 (1 - ((s -
// 0.52) / 0.52)^2) (the arch's top above the lateral limbus) and its
// height width_mm (1 - 0.6 s). Roots are drawn uniformly over the band
// (hairs_per_mm2 times its area of them), thinned where it is feathered
// (kept with probability smoothstep(s; -0.02, 0.15) times smoothstep(e;
// -0.1, 0.2), e the distance from the nearer edge as a fraction of the
// band's height: no hard outline), and set on the mesh where a ray
// along the head's -z meets it (its front-most triangle). A hair is
// kBrowSegments chords of equal length, each leaving the tangent plane of
// the skin below its start (the root's, for the first) in the direction
// of growth at the hair's elevation at the chord's middle: lift_deg at the
// root, falling by curl_deg over the hair's length, never below 0 (it
// lies on the skin from there on). The hair thus follows the brow
// ridge's curve rather than the plane at its root. Growth, as seen from the front
// (angle above the lateral direction): 80 deg (up) at the head, turning
// over the first quarter to the body's +-20 deg (the band's lower edge
// tipped up, its upper edge down, meeting along the middle), and over
// the last quarter to -20 deg (down) at the tail. Jitter per hair, from
// the counter stream (seed, stream): growth +-12 deg, lift +-5 deg,
// length +-20%, curl +-30%.

#include <cstdint>
#include <vector>

#include "face_mesh.h"
#include "lashes.h"
#include "purkinje/models/appearance.h"

namespace purkinje::renderer {

inline constexpr int kBrowSegments = 4;

// The brows of one eye's face: `mesh` is that face, `world_from_head` its
// head frame; the draws are the stream kBrowStreams + `eye`'s.
std::vector<HairSegment> build_brows(const Brows& brows, const Eyelids& lids, const Face& face, const FaceMesh& mesh,
                                     const Pose& world_from_head, int eye);

// The brows' streams begin here: far past any eye's lash streams.
inline constexpr std::uint64_t kBrowStreams = std::uint64_t{1} << 32;

}  // namespace purkinje::renderer
